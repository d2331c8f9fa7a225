// The command line, as a function so that tests can check exit codes and
// messages without spawning processes.
#pragma once

#include <ostream>

namespace penumbra {

// Documented exit codes (also in `penumbra --help`).
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;    // a run failed: renderer or internal error
inline constexpr int kExitBadInput = 2;   // usage, scene file or output path
inline constexpr int kExitThreshold = 3;  // a comparison missed its bound, or NaN/Inf pixels

int run_cli(int argc, const char* const* argv, std::ostream& out, std::ostream& err);

}  // namespace penumbra
