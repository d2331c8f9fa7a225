#include "study/execute.h"

#include <algorithm>
#include <chrono>
#include <mutex>
#include <thread>

#include <fmt/format.h>

#include "util/parallel.h"

namespace penumbra {

namespace {

struct Shared {
  std::mutex mutex;
  long started = 0;
  double busy_seconds = 0.0;
};

bool may_start(const ExecuteOptions& options, Shared& shared) {
  if (options.interrupted && options.interrupted->load()) return false;
  if (options.max_started >= 0 && shared.started >= options.max_started) return false;
  ++shared.started;
  return true;
}

void report(const ExecuteOptions& options, std::size_t count, const ExecuteResult& r,
            const Shared& shared, const std::string& label, const std::string& error,
            double seconds) {
  const std::size_t total = options.total ? options.total : options.already_done + count;
  const double eta = shared.busy_seconds / double(r.finished) * double(count - r.finished) /
                     std::max(1, options.jobs);
  if (options.progress) options.progress(options.already_done + r.finished, total, eta);
  if (!options.log) return;
  const std::string first_line = error.substr(0, error.find('\n'));
  options.log(fmt::format("[{}/{}] {} {} ({:.1f} s){}", options.already_done + r.finished, total,
                          error.empty() ? "rendered" : "FAILED", label, seconds,
                          error.empty() ? "" : ": " + first_line));
}

}  // namespace

ExecuteResult execute_tasks(std::size_t count, const ExecuteOptions& options,
                            const std::function<void(std::size_t)>& task,
                            const std::function<std::string(std::size_t)>& label) {
  ExecuteResult r;
  r.done.assign(count, 0);
  r.attempted.assign(count, 0);
  r.errors.resize(count);
  r.seconds.assign(count, 0.0);
  Shared shared;
  const std::vector<std::size_t> no_groups;
  const std::vector<std::size_t>& groups =
      options.max_started >= 0 ? no_groups : options.group_starts;
  run_parallel(
      options.jobs, count,
      [&](std::size_t i) {
        {
          std::lock_guard<std::mutex> lock(shared.mutex);
          if (!may_start(options, shared)) return;
          r.attempted[i] = 1;
        }
        const auto t0 = std::chrono::steady_clock::now();
        std::string error;
        try {
          task(i);
        } catch (const TaskCancelled&) {  // neither done nor failed: a later run does it
          std::lock_guard<std::mutex> lock(shared.mutex);
          r.attempted[i] = 0;
          return;
        } catch (const std::exception& e) {
          error = e.what();
          if (error.empty()) error = "failed";
        }
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::lock_guard<std::mutex> lock(shared.mutex);
        ++r.finished;
        shared.busy_seconds += seconds;
        r.seconds[i] = seconds;
        if (error.empty()) {
          r.done[i] = 1;
        } else {
          r.errors[i] = error;
          ++r.failed;
        }
        report(options, count, r, shared, label(i), error, seconds);
      },
      groups);
  return r;
}

}  // namespace penumbra
