#include "util/process.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <stdexcept>
#include <thread>

#include <fmt/format.h>

#include "util/strict_json.h"

namespace penumbra {

std::optional<std::string> find_executable(const std::string& name) {
  auto executable = [](const std::string& path) {
    struct stat st {};
    return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode) &&
           ::access(path.c_str(), X_OK) == 0;
  };
  if (name.empty()) return std::nullopt;
  if (name.find('/') != std::string::npos)
    return executable(name) ? std::optional<std::string>(name) : std::nullopt;
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    const std::size_t end = std::min(dirs.find(':', start), dirs.size());
    const std::string dir = dirs.substr(start, end - start);
    const std::string candidate = (dir.empty() ? "." : dir) + "/" + name;
    if (executable(candidate)) return candidate;
    start = end + 1;
  }
  return std::nullopt;
}

namespace {

std::atomic<bool> g_cancel{false};

// The guard (the child between Penumbra and the renderer) ends its whole
// process group when Penumbra dies, kill -9 included: the kernel sends it
// this signal then (PR_SET_PDEATHSIG).
extern "C" void end_group_on_parent_death(int) {
  ::kill(0, SIGKILL);
}

// Closes every descriptor from 3 up except `keep` (async-signal-safe).
void close_inherited(std::initializer_list<int> keep) {
  struct rlimit limit {};
  long last = 1024;
  if (::getrlimit(RLIMIT_NOFILE, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY)
    last = static_cast<long>(std::min<rlim_t>(limit.rlim_cur, 65536));
  for (int fd = 3; fd < last; ++fd)
    if (std::find(keep.begin(), keep.end(), fd) == keep.end()) ::close(fd);
}

// Runs in the forked child; only async-signal-safe calls (Penumbra has
// threads). Becomes the leader of a new process group, forks the renderer
// into it, waits, and writes the renderer's raw wait status to `status_fd`.
[[noreturn]] void guard_process(char* const* args, char* const* envp, const char* cwd, int input,
                                int log, int status_fd, pid_t penumbra) {
  ::setpgid(0, 0);
  // The guard never execs, so O_CLOEXEC does not shield it: close what it
  // inherited from Penumbra, above all the write ends of other coprocesses'
  // stdin pipes, which would otherwise never see end of input.
  close_inherited({input, log, status_fd});
  // A thread's blocked signals survive fork and exec: start with none blocked,
  // so that the death signal and the renderer's SIGTERM arrive.
  sigset_t none;
  ::sigemptyset(&none);
  ::sigprocmask(SIG_SETMASK, &none, nullptr);
  struct sigaction action {};
  action.sa_handler = end_group_on_parent_death;
  ::sigemptyset(&action.sa_mask);
  ::sigaction(SIGUSR1, &action, nullptr);
  struct sigaction pipe_default {};
  pipe_default.sa_handler = SIG_DFL;
  ::sigaction(SIGPIPE, &pipe_default, nullptr);  // Penumbra may ignore it (Coprocess)
  ::prctl(PR_SET_PDEATHSIG, SIGUSR1);
  if (::getppid() != penumbra) ::kill(0, SIGKILL);  // Penumbra died before prctl
  const pid_t renderer = ::fork();
  if (renderer == 0) {
    struct sigaction fallback {};
    fallback.sa_handler = SIG_DFL;
    ::sigaction(SIGUSR1, &fallback, nullptr);
    // Penumbra started with a standard stream closed may hold the log or the
    // input at fd 0-2: move both above 2 before they are put in place.
    const int in = ::fcntl(input >= 0 ? input : ::open("/dev/null", O_RDONLY), F_DUPFD, 3);
    const int out = ::fcntl(log, F_DUPFD, 3);
    if (in >= 0) ::dup2(in, 0);
    ::dup2(out, 1);
    ::dup2(out, 2);
    if (::chdir(cwd) != 0) ::_exit(126);
    if (envp)
      ::execve(args[0], args, envp);
    else
      ::execv(args[0], args);
    ::_exit(127);
  }
  int status = 127 << 8;  // as if exec failed, when fork did
  if (renderer > 0)
    while (::waitpid(renderer, &status, 0) < 0 && errno == EINTR) {
    }
  if (::write(status_fd, &status, sizeof status) != sizeof status) ::_exit(125);
  ::_exit(0);
}

bool guard_exited(pid_t pid) {
  siginfo_t info{};
  const int w = ::waitid(P_PID, static_cast<id_t>(pid), &info, WEXITED | WNOHANG | WNOWAIT);
  if (w < 0 && errno != EINTR) throw std::runtime_error("waitid failed");
  return w == 0 && info.si_pid == pid;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Polls the guard `pid` until it exits (returns kExited), `done` holds,
// `timeout_s` seconds pass since `start` or cancel_processes() is called.
enum class PollEnd { kExited, kDone, kTimedOut, kCancelled };
PollEnd poll_guard(pid_t pid, double timeout_s, const std::function<bool()>& done,
                   std::chrono::steady_clock::time_point start) {
  for (;;) {
    if (guard_exited(pid)) return PollEnd::kExited;
    if (done && done()) return PollEnd::kDone;
    const double t = seconds_since(start);
    if (g_cancel.load()) return PollEnd::kCancelled;
    if (t > timeout_s) return PollEnd::kTimedOut;
    std::this_thread::sleep_for(std::chrono::milliseconds(t < 1.0 ? 5 : 25));
  }
}

// Ends the group of guard `pid`: SIGTERM, SIGKILL two seconds later if it
// still runs.
void terminate_group(pid_t pid) {
  ::kill(-pid, SIGTERM);
  const auto start = std::chrono::steady_clock::now();
  while (!guard_exited(pid)) {
    if (seconds_since(start) > 2.0) {
      ::kill(-pid, SIGKILL);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

// Reaps the guard that exited (or is being killed) and returns the wait
// status of the renderer itself when the guard could report it. The group is
// killed before the guard is reaped, so its id cannot have been reused by then.
int reap_guard(pid_t pid, int status_fd) {
  ::kill(-pid, SIGKILL);  // whatever the renderer left running in its group
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  int renderer_status = 0;
  if (::read(status_fd, &renderer_status, sizeof renderer_status) ==
      static_cast<ssize_t>(sizeof renderer_status))
    status = renderer_status;  // the guard finished: report the renderer itself
  ::close(status_fd);
  return status;
}

void set_exit(int status, ProcessResult& result) {
  if (WIFEXITED(status)) result.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) result.signal = WTERMSIG(status);
}

struct Guarded {
  pid_t pid = -1;
  int status_fd = -1;
  std::chrono::steady_clock::time_point start;
};

// Forks the guard, which runs `argv` in its own process group with stdin from
// `input` (-1: /dev/null) and stdout + stderr appended to `log_path`.
Guarded start_guarded(const std::vector<std::string>& argv, const std::string& cwd,
                      const std::string& log_path, int input,
                      const std::vector<std::string>& environment = {}) {
  if (argv.empty()) throw std::invalid_argument("run_process: empty argv");
  // Everything the child touches is prepared before fork(): between fork and
  // exec only async-signal-safe calls are allowed (TBB threads exist).
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  std::vector<char*> env;
  for (const std::string& e : environment) env.push_back(const_cast<char*>(e.c_str()));
  env.push_back(nullptr);
  char* const* envp = environment.empty() ? nullptr : env.data();
  const int log = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (log < 0)
    throw std::runtime_error(
        fmt::format("cannot open log file {}: {}", log_path, std::strerror(errno)));
  int status_pipe[2];
  if (::pipe2(status_pipe, O_CLOEXEC) != 0) {
    ::close(log);
    throw std::runtime_error(fmt::format("cannot create a pipe: {}", std::strerror(errno)));
  }
  Guarded g;
  g.start = std::chrono::steady_clock::now();
  const pid_t penumbra = ::getpid();
  g.pid = ::fork();
  if (g.pid < 0) {
    ::close(log), ::close(status_pipe[0]), ::close(status_pipe[1]);
    throw std::runtime_error(fmt::format("cannot start {}: {}", argv[0], std::strerror(errno)));
  }
  if (g.pid == 0) {
    ::close(status_pipe[0]);
    guard_process(args.data(), envp, cwd.c_str(), input, log, status_pipe[1], penumbra);
  }
  ::setpgid(g.pid, g.pid);  // also here, so that the group exists before any kill(-pid)
  ::close(log);
  ::close(status_pipe[1]);
  g.status_fd = status_pipe[0];
  return g;
}

}  // namespace

void cancel_processes() {
  g_cancel.store(true);
}
void reset_cancel_processes() {
  g_cancel.store(false);
}
bool processes_cancelled() {
  return g_cancel.load();
}

ProcessResult run_process(const std::vector<std::string>& argv, const std::string& cwd,
                          const std::string& log_path, double timeout_s) {
  const Guarded g = start_guarded(argv, cwd, log_path, -1);
  ProcessResult result;
  const PollEnd end = poll_guard(g.pid, timeout_s, nullptr, g.start);
  if (end != PollEnd::kExited) {
    (end == PollEnd::kCancelled ? result.cancelled : result.timed_out) = true;
    terminate_group(g.pid);
  }
  set_exit(reap_guard(g.pid, g.status_fd), result);
  result.seconds = seconds_since(g.start);
  return result;
}

Coprocess::Coprocess(const std::vector<std::string>& argv, const std::string& cwd,
                     const std::string& log_path, const std::vector<std::string>& environment) {
  // A coprocess that dies must not take Penumbra with it when written to.
  // Children get the default back (guard_process).
  ::signal(SIGPIPE, SIG_IGN);
  int input[2];
  if (::pipe2(input, O_CLOEXEC) != 0)
    throw std::runtime_error(fmt::format("cannot create a pipe: {}", std::strerror(errno)));
  Guarded g;
  try {
    g = start_guarded(argv, cwd, log_path, input[0], environment);
  } catch (...) {
    ::close(input[0]), ::close(input[1]);
    throw;
  }
  ::close(input[0]);
  pid_ = g.pid, status_fd_ = g.status_fd, input_ = input[1];
}

Coprocess::~Coprocess() {
  close(5.0);
}

bool Coprocess::send_line(const std::string& line) {
  if (input_ < 0 || finished_) return false;
  const std::string text = line + "\n";
  std::size_t sent = 0;
  while (sent < text.size()) {
    // A reader that is gone makes write() fail with EPIPE: SIGPIPE is
    // ignored (constructor).
    const ssize_t n = ::write(input_, text.data() + sent, text.size() - sent);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    sent += static_cast<std::size_t>(n);
  }
  return true;
}

std::optional<ProcessResult> Coprocess::wait_until(const std::function<bool()>& done,
                                                   double timeout_s) {
  if (finished_) return final_;
  const auto start = std::chrono::steady_clock::now();
  const PollEnd end = poll_guard(pid_, timeout_s, done, start);
  if (end == PollEnd::kDone) return std::nullopt;
  ProcessResult result;
  if (end != PollEnd::kExited) {
    (end == PollEnd::kCancelled ? result.cancelled : result.timed_out) = true;
    terminate_group(pid_);
  }
  finish(result);
  result.seconds = seconds_since(start);
  return result;
}

void Coprocess::finish(ProcessResult& result) {
  if (input_ >= 0) ::close(input_), input_ = -1;
  set_exit(reap_guard(pid_, status_fd_), result);
  finished_ = true;
  final_ = result;
}

bool Coprocess::alive() {
  if (finished_ || pid_ < 0) return false;
  if (!guard_exited(pid_)) return true;
  ProcessResult result;
  finish(result);
  return false;
}

void Coprocess::close(double grace_s) {
  if (finished_ || pid_ < 0) return;
  if (input_ >= 0) ::close(input_), input_ = -1;  // end of input: it should exit
  ProcessResult result;
  const auto start = std::chrono::steady_clock::now();
  if (poll_guard(pid_, grace_s, nullptr, start) != PollEnd::kExited) terminate_group(pid_);
  finish(result);
}

std::string tail_lines(const std::string& path, int lines) {
  std::ifstream in(path);
  if (!in) return "";
  std::deque<std::string> last;
  std::string line;
  while (std::getline(in, line)) {
    last.push_back(line);
    if (static_cast<int>(last.size()) > lines) last.pop_front();
  }
  std::string out;
  // A renderer's log may hold terminal escapes or binary junk.
  for (const std::string& l : last) out += printable(l, 400) + "\n";
  return out;
}

}  // namespace penumbra
