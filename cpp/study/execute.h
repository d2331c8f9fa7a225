// Running a list of renders in parallel, with progress, an ETA, interruption
// (Ctrl-C, a render budget) and per-task failures kept as results: shared by
// studies and the calibration.
#pragma once

#include <atomic>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace penumbra {

struct ExecuteOptions {
  int jobs = 1;  // tasks at a time
  // Stop starting tasks after this many; -1: no limit (tests use it to
  // simulate an interruption).
  long max_started = -1;
  const std::atomic<bool>* interrupted = nullptr;  // set by a signal handler
  std::function<void(const std::string&)> log;     // one line per finished task
  std::function<void(std::size_t done, std::size_t total, double eta_s)> progress;
  // Counted as done before this run, for "[done/total]" (cached renders).
  std::size_t already_done = 0;
  std::size_t total = 0;  // for progress; default: already_done + tasks
  // Groups of tasks that one worker runs in order (util/parallel.h); empty:
  // each task alone. Ignored with max_started, which needs index order.
  std::vector<std::size_t> group_starts;
};

// What happened to each task.
struct ExecuteResult {
  std::vector<char> done, attempted;  // attempted and not done: failed
  std::vector<std::string> errors;    // the failure's message
  std::vector<double> seconds;
  std::size_t finished = 0, failed = 0;
};

// Thrown by a task that was stopped from outside (Ctrl-C: the task turns its
// own RenderCancelled into this): neither done nor failed, so a later run
// does it again.
struct TaskCancelled {};

// Runs task(i) for i in [0, count): a task returns normally when done, throws
// TaskCancelled when it was stopped, and throws std::exception on failure.
// `label(i)` names task i in log lines.
ExecuteResult execute_tasks(std::size_t count, const ExecuteOptions& options,
                            const std::function<void(std::size_t)>& task,
                            const std::function<std::string(std::size_t)>& label);

}  // namespace penumbra
