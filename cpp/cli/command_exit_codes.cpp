// `penumbra exit-codes`: the exit statuses of every command (cli/exit_codes.h).
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli/command.h"

namespace penumbra {

namespace {

int exit_codes(bool as_json, std::ostream& out) {
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

}  // namespace

Command add_exit_codes_command(CLI::App& app, SharedOptions&) {
  auto as_json = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand(
      "exit-codes", "list the exit statuses of every command (code, name, meaning)");
  cmd->add_flag("--json", *as_json,
                "print a JSON array of {code, name, meaning} (the signal row: code 128, "
                "meaning \"128+N: ...\")");
  return {cmd, [as_json](const CommandContext& c) { return exit_codes(*as_json, c.out); }};
}

}  // namespace penumbra
