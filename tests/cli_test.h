// Runs the command line in-process, as the tests of the CLI and the fuzzer do.
#pragma once

#include <sstream>
#include <string>
#include <vector>

#include "cli/cli.h"

namespace penumbra {

struct CliResult {
  int code = -1;
  std::string out, err;
};

// `penumbra ARGS...`: exit code and what it printed.
inline CliResult run_penumbra(std::vector<std::string> args) {
  args.insert(args.begin(), "penumbra");
  std::vector<const char*> argv;
  for (const std::string& a : args) argv.push_back(a.c_str());
  std::ostringstream out, err;
  const int code = run_cli(static_cast<int>(argv.size()), argv.data(), out, err);
  return {code, out.str(), err.str()};
}

}  // namespace penumbra
