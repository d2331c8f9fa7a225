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

// How much of the machine a command uses, decided once (run_cli, from the
// global --threads and the command's --jobs) and passed down:
//   --threads T  threads in all; default: the cores. It also caps the
//                evaluator's TBB pool, which every evaluator render shares.
//   --jobs J     renders at once, or as many of a command's other
//                independent tasks (cache reads, comparisons, the footprints
//                of `penumbra filtering`); default: T.
// Each render then gets T / J threads, at least one: what an external
// renderer is given (POV-Ray's +WT; Blender always renders on one). A
// command that renders one image at a time (`penumbra render`) gives it
// threads(): T, or J where J > T.
struct Parallelism {
  int renders = 1;             // J
  int threads_per_render = 1;  // T / J, at least 1
  int threads() const { return renders * threads_per_render; }
};

// `jobs` and `threads`: --jobs and --threads, 0 where not given.
inline Parallelism resolve_parallelism(int jobs, int threads = 0) {
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const int budget = threads > 0 ? threads : cores;
  Parallelism p;
  p.renders = jobs > 0 ? jobs : budget;
  p.threads_per_render = std::max(1, budget / p.renders);
  return p;
}

// `jobs` worker threads take `tasks` in index order.
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
