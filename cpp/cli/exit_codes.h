// Penumbra's exit statuses, as one table: the exception mapping of run_cli
// returns these codes, every --help ends with the table's sentence
// (exit_status_text) and `penumbra exit-codes [--json]` prints it, so that
// the documentation can be generated from it.
//
// Unlike OpenImageIO's idiff, whose 2 is a failed comparison, Penumbra's 2
// is bad input and 3 a failed comparison, so that scripts can tell the two
// apart.
#pragma once

#include <span>
#include <string>
#include <string_view>

namespace penumbra {

inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;    // a run failed: renderer or internal error
inline constexpr int kExitBadInput = 2;   // usage, scene file or output path
inline constexpr int kExitThreshold = 3;  // a comparison missed its bound, or NaN/Inf pixels
// Stopped by signal N: the status is kExitSignalBase + N (StopSignals).
inline constexpr int kExitSignalBase = 128;

struct ExitCodeInfo {
  int code;
  std::string_view name;   // short, stable: for scripts and docs
  std::string_view shown;  // how the code is written: "2", or "128+N" for the signal row
  std::string_view meaning;
};

// The signal row stands for every 128+N (129 SIGHUP, 130 SIGINT, 143
// SIGTERM): its code is the base, 128, and its meaning says "128+N".
inline constexpr ExitCodeInfo kExitCodes[] = {
    {kExitOk, "ok", "0", "success"},
    {kExitFailure, "failure", "1",
     "a run failed (renderer or internal error, NaN or Inf in a render)"},
    {kExitBadInput, "bad-input", "2",
     "bad input (usage, scene or study file, output path, a render over --max-memory)"},
    {kExitThreshold, "threshold", "3",
     "a comparison missed its bound or an image holds NaN/Inf (compare, calibrate)"},
    {kExitSignalBase, "signal", "128+N",
     "stopped by signal N (130 Ctrl-C, 143 SIGTERM), nothing half-written"},
};

// The meaning with the code written into it where the code stands for a
// range ("128+N: stopped by signal N ..."): what `exit-codes --json` prints.
inline std::string exit_code_meaning(const ExitCodeInfo& info) {
  if (info.shown == std::to_string(info.code)) return std::string(info.meaning);
  return std::string(info.shown) + ": " + std::string(info.meaning);
}

// "Exit status: 0 success; 1 ...; 128+N stopped by signal N ...": the footer
// of every --help.
inline std::string exit_status_text() {
  std::string text = "Exit status:";
  for (const ExitCodeInfo& info : kExitCodes)
    text += std::string(&info == kExitCodes ? " " : "; ") + std::string(info.shown) + " " +
            std::string(info.meaning);
  return text + ".";
}

}  // namespace penumbra
