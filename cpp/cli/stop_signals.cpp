#include "cli/stop_signals.h"

#include "cli/exit_codes.h"
#include "util/process.h"

namespace penumbra {

namespace {

std::atomic<bool> g_interrupted{false};
std::atomic<int> g_signal{0};
extern "C" void on_stop_signal(int signal) {
  g_signal.store(signal);
  g_interrupted.store(true);
  cancel_processes();  // ends running renderers and everything they started
}

constexpr std::array<int, 3> kStopSignals{SIGINT, SIGTERM, SIGHUP};

}  // namespace

StopSignals::StopSignals() {
  g_interrupted.store(false);
  g_signal.store(0);
  reset_cancel_processes();
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  for (std::size_t i = 0; i < kStopSignals.size(); ++i)
    ::sigaction(kStopSignals[i], &action, &previous_[i]);
}

StopSignals::~StopSignals() {
  for (std::size_t i = 0; i < kStopSignals.size(); ++i)
    ::sigaction(kStopSignals[i], &previous_[i], nullptr);
  reset_cancel_processes();
}

int StopSignals::exit_code() {
  return kExitSignalBase + (g_signal.load() ? g_signal.load() : SIGINT);
}

const std::atomic<bool>& StopSignals::interrupted() {
  return g_interrupted;
}

}  // namespace penumbra
