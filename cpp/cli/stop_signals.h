// SIGINT, SIGTERM and SIGHUP while a command runs: running renderers are
// ended, nothing half-written is left, and the exit status is 128 + the
// signal (130 for Ctrl-C; cli/exit_codes.h).
#pragma once

#include <signal.h>

#include <array>
#include <atomic>

namespace penumbra {

// While alive, the stop signals set interrupted() and end the processes this
// one started (util/process.h) instead of killing it.
class StopSignals {
 public:
  StopSignals();
  ~StopSignals();
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;
  // 128 + the signal received (SIGINT if none was).
  static int exit_code();
  // Set by a stop signal; a long loop checks it between steps.
  static const std::atomic<bool>& interrupted();

 private:
  std::array<struct sigaction, 3> previous_{};
};

}  // namespace penumbra
