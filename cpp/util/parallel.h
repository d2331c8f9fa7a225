// Independent renders in parallel: `jobs` worker threads take tasks in index
// order. Each task must catch its own exceptions (a failed render is a result
// to report, not a reason to stop the others).
//
// Plain threads rather than TBB (which the evaluator uses): tasks are long
// renders that mostly wait on an external process, and a TBB arena would
// also cap the evaluator's own parallel loops inside each task. Tasks start
// in index order, which keeps "stop after N renders" deterministic.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <functional>
#include <thread>
#include <vector>

namespace penumbra {

//
// With `group_starts` (ascending, the first 0), the tasks from one start to
// the next are one group that one worker runs in order: renders that reuse
// what the worker's last render built (a serving Blender's mesh) stay on one
// worker. Groups start in index order.
inline void run_parallel(int jobs, std::size_t tasks, const std::function<void(std::size_t)>& task,
                         const std::vector<std::size_t>& group_starts = {}) {
  std::atomic<std::size_t> next{0};
  const std::size_t groups = group_starts.empty() ? tasks : group_starts.size();
  auto worker = [&] {
    for (std::size_t g = next++; g < groups; g = next++) {
      if (group_starts.empty()) {
        task(g);
        continue;
      }
      const std::size_t end = g + 1 < groups ? group_starts[g + 1] : tasks;
      for (std::size_t i = group_starts[g]; i < end; ++i) task(i);
    }
  };
  const int n = std::max(1, std::min<int>(jobs, static_cast<int>(groups)));
  std::vector<std::thread> threads;
  for (int t = 1; t < n; ++t) threads.emplace_back(worker);
  worker();
  for (std::thread& t : threads) t.join();
}

}  // namespace penumbra
