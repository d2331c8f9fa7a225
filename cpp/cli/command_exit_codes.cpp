// `penumbra exit-codes`: the exit statuses of every command (cli/exit_codes.h).
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "cli/exit_codes.h"

namespace penumbra {

int command_exit_codes(bool as_json, std::ostream& out) {
  if (as_json) {
    nlohmann::json list = nlohmann::json::array();
    for (const ExitCodeInfo& info : kExitCodes)
      list.push_back({{"code", info.code},
                      {"name", std::string(info.name)},
                      {"meaning", exit_code_meaning(info)}});
    out << list.dump(2) << "\n";
    return kExitOk;
  }
  out << fmt::format("{:<6} {:<10} {}\n", "code", "name", "meaning");
  for (const ExitCodeInfo& info : kExitCodes)
    out << fmt::format("{:<6} {:<10} {}\n", info.shown, info.name, info.meaning);
  return kExitOk;
}

}  // namespace penumbra
