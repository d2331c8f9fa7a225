// Running external renderers: PATH lookup, a wall-clock timeout, stdout and
// stderr captured in a log file.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace penumbra {

// Absolute path of `name` (a bare command name looked up in PATH, or a path
// containing '/'), if it names an executable file.
std::optional<std::string> find_executable(const std::string& name);

struct ProcessResult {
  int exit_code = -1;      // valid when neither timed out nor signalled
  bool timed_out = false;  // killed after the timeout
  bool cancelled = false;  // killed because cancel_processes() was called
  int signal = 0;          // terminating signal, 0 if it exited
  double seconds = 0.0;    // wall time
  bool ok() const { return !timed_out && !cancelled && signal == 0 && exit_code == 0; }
};

// Runs `argv` (argv[0] an executable path) in folder `cwd` with stdin from
// /dev/null and stdout + stderr appended to `log_path`, in a process group of
// its own under a small guard process. After `timeout_s` seconds, or once
// cancel_processes() is called, the whole group gets SIGTERM, then SIGKILL two
// seconds later; when the renderer exits, whatever it left running in the
// group is killed; if Penumbra dies (kill -9 included) the guard kills the
// group. So no renderer, and nothing a renderer started, outlives its call.
ProcessResult run_process(const std::vector<std::string>& argv, const std::string& cwd,
                          const std::string& log_path, double timeout_s);

// Ends every running and future run_process call (Ctrl-C, SIGTERM); safe to
// call from a signal handler. reset_cancel_processes() allows new ones again.
void cancel_processes();
void reset_cancel_processes();
bool processes_cancelled();

// The last `lines` lines of a text file ("" if unreadable).
std::string tail_lines(const std::string& path, int lines);

}  // namespace penumbra
