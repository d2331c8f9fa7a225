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

inline void run_parallel(int jobs, std::size_t tasks,
                         const std::function<void(std::size_t)>& task) {
  std::atomic<std::size_t> next{0};
  auto worker = [&] {
    for (std::size_t i = next++; i < tasks; i = next++) task(i);
  };
  const int n = std::max(1, std::min<int>(jobs, static_cast<int>(tasks)));
  std::vector<std::thread> threads;
  for (int t = 1; t < n; ++t) threads.emplace_back(worker);
  worker();
  for (std::thread& t : threads) t.join();
}

}  // namespace penumbra
