// The command line, as a function so that tests can check exit codes and
// messages without spawning processes.
#pragma once

#include <ostream>

#include "cli/exit_codes.h"

namespace penumbra {

int run_cli(int argc, const char* const* argv, std::ostream& out, std::ostream& err);

}  // namespace penumbra
