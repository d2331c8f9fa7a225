#include "util/process.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <fstream>
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

// Runs in the forked child; only async-signal-safe calls (Penumbra has
// threads). Becomes the leader of a new process group, forks the renderer
// into it, waits, and writes the renderer's raw wait status to `status_fd`.
[[noreturn]] void guard_process(char* const* args, const char* cwd, int log, int status_fd,
                                pid_t penumbra) {
  ::setpgid(0, 0);
  // A thread's blocked signals survive fork and exec: start with none blocked,
  // so that the death signal and the renderer's SIGTERM arrive.
  sigset_t none;
  ::sigemptyset(&none);
  ::sigprocmask(SIG_SETMASK, &none, nullptr);
  struct sigaction action {};
  action.sa_handler = end_group_on_parent_death;
  ::sigemptyset(&action.sa_mask);
  ::sigaction(SIGUSR1, &action, nullptr);
  ::prctl(PR_SET_PDEATHSIG, SIGUSR1);
  if (::getppid() != penumbra) ::kill(0, SIGKILL);  // Penumbra died before prctl
  const pid_t renderer = ::fork();
  if (renderer == 0) {
    struct sigaction fallback {};
    fallback.sa_handler = SIG_DFL;
    ::sigaction(SIGUSR1, &fallback, nullptr);
    const int null = ::open("/dev/null", O_RDONLY);
    if (null >= 0) ::dup2(null, 0);
    ::dup2(log, 1);
    ::dup2(log, 2);
    if (::chdir(cwd) != 0) ::_exit(126);
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

// Waits for the guard `pid`, ending its group at the timeout or on cancel();
// returns the guard's wait status. The group is killed before the guard is
// reaped, so its id cannot have been reused by then.
int wait_for_group(pid_t pid, double timeout_s, ProcessResult& result,
                   const std::chrono::steady_clock::time_point& start) {
  auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  bool terminated = false;
  double kill_at = 0.0;
  for (;;) {
    siginfo_t info{};
    const int w = ::waitid(P_PID, static_cast<id_t>(pid), &info, WEXITED | WNOHANG | WNOWAIT);
    if (w == 0 && info.si_pid == pid) break;
    if (w < 0 && errno != EINTR) throw std::runtime_error("waitid failed");
    const double t = elapsed();
    const bool cancel = g_cancel.load();
    if (!terminated && (t > timeout_s || cancel)) {
      ::kill(-pid, SIGTERM);
      terminated = true;
      (cancel ? result.cancelled : result.timed_out) = true;
      kill_at = t + 2.0;
    } else if (terminated && kill_at > 0.0 && t > kill_at) {
      ::kill(-pid, SIGKILL);
      kill_at = 0.0;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(t < 1.0 ? 5 : 25));
  }
  ::kill(-pid, SIGKILL);  // whatever the renderer left running in its group
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return status;
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
  if (argv.empty()) throw std::invalid_argument("run_process: empty argv");
  // Everything the child touches is prepared before fork(): between fork and
  // exec only async-signal-safe calls are allowed (TBB threads exist).
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const int log = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (log < 0)
    throw std::runtime_error(
        fmt::format("cannot open log file {}: {}", log_path, std::strerror(errno)));
  int status_pipe[2];
  if (::pipe2(status_pipe, O_CLOEXEC) != 0) {
    ::close(log);
    throw std::runtime_error(fmt::format("cannot create a pipe: {}", std::strerror(errno)));
  }
  const auto start = std::chrono::steady_clock::now();
  const pid_t penumbra = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(log), ::close(status_pipe[0]), ::close(status_pipe[1]);
    throw std::runtime_error(fmt::format("cannot start {}: {}", argv[0], std::strerror(errno)));
  }
  if (pid == 0) {
    ::close(status_pipe[0]);
    guard_process(args.data(), cwd.c_str(), log, status_pipe[1], penumbra);
  }
  ::setpgid(pid, pid);  // also here, so that the group exists before any kill(-pid)
  ::close(log);
  ::close(status_pipe[1]);

  ProcessResult result;
  int status = wait_for_group(pid, timeout_s, result, start);
  int renderer_status = 0;
  if (::read(status_pipe[0], &renderer_status, sizeof renderer_status) ==
      static_cast<ssize_t>(sizeof renderer_status))
    status = renderer_status;  // the guard finished: report the renderer itself
  ::close(status_pipe[0]);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (WIFEXITED(status)) result.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) result.signal = WTERMSIG(status);
  return result;
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
