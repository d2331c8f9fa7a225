// Running external renderers: PATH lookup, a wall-clock timeout, stdout and
// stderr captured in a log file.
#pragma once

#include <functional>
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

// A long-lived child that serves many requests (a renderer rendering job
// after job, so that its start-up is paid once): started like run_process,
// under the same guard, but with stdin a pipe that send_line() writes to.
// Requests end when the child leaves a sign the caller checks (a file).
// The destructor closes stdin (a well-behaved child then exits) and ends the
// group after a short grace. The guard's parent-death signal follows the
// thread that started it (PR_SET_PDEATHSIG), so a coprocess ends with that
// thread at the latest: users check alive() and start a new one.
class Coprocess {
 public:
  // `environment`: the child's whole environment ("NAME=value"); empty:
  // Penumbra's own.
  Coprocess(const std::vector<std::string>& argv, const std::string& cwd,
            const std::string& log_path, const std::vector<std::string>& environment = {});
  ~Coprocess();
  Coprocess(const Coprocess&) = delete;
  Coprocess& operator=(const Coprocess&) = delete;

  // False when the child no longer reads (it exited).
  bool send_line(const std::string& line);
  // Waits until `done()` holds (returns nullopt), the child exits, the
  // timeout passes or cancel_processes() is called; in the last three cases
  // the group is ended and the result says how, as run_process's would
  // (seconds: this wait's wall time). Once ended, returns that result again.
  std::optional<ProcessResult> wait_until(const std::function<bool()>& done, double timeout_s);
  // Still running: neither ended by wait_until nor exited on its own (a
  // guard also ends its group when the thread that started it exits).
  bool alive();
  // Closes stdin, waits up to `grace_s` for the child to exit, then ends the group.
  void close(double grace_s);

 private:
  void finish(ProcessResult& result);
  int pid_ = -1, status_fd_ = -1, input_ = -1;
  bool finished_ = false;
  ProcessResult final_;
};

// Ends every running and future run_process call (Ctrl-C, SIGTERM); safe to
// call from a signal handler. reset_cancel_processes() allows new ones again.
void cancel_processes();
void reset_cancel_processes();
bool processes_cancelled();

// The last `lines` lines of a text file ("" if unreadable).
std::string tail_lines(const std::string& path, int lines);

}  // namespace penumbra
