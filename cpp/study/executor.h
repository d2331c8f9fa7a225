// Where a study's renders run. The study run (study/study.h) takes what the
// cache holds and hands each round of renders it lacks to one Executor,
// without knowing which:
//   local  renders here, --jobs at once on threads (study/execute.h), each
//          written into the cache as it finishes;
//   slurm  submits them as a Slurm job array over the shared study folder
//          (study/slurm.h), whose report job runs the study again: the
//          round returns at once, its renders not started here.
// Both render a job the same way (render_into_cache, study/rendering.h).
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "study/cache.h"
#include "study/compare.h"
#include "study/convergence.h"
#include "study/plan.h"
#include "study/rendering.h"
#include "study/study.h"

namespace penumbra {

// The state of every job of a round.
struct Renders {
  RenderedImages images;
  std::vector<std::string> errors;
  std::vector<char> attempted;
  std::vector<char> cached;   // taken from the cache, not rendered by this round
  std::vector<long> same_as;  // a job with an earlier job's key takes its result
  explicit Renders(std::size_t n) : errors(n), attempted(n, 0), cached(n, 0), same_as(n, -1) {
    images.done.assign(n, 0);
    images.images.resize(n);
  }
};

// Counts a render that failed in `stats`, with the first line of its error.
inline void count_failure(const Job& job, const std::string& error, StudyRunStats& stats) {
  ++stats.failed;
  stats.failures.push_back(job.label + ": " + error.substr(0, error.find('\n')));
}

// The ground-truth convergence checks a round renders (study/convergence.h),
// for an executor that hands the rest of a variant's chain of checks to one
// worker instead of waiting for every round.
struct ConvergenceRound {
  const Plan& plan;
  const GroundTruthSettings& settings;
  double max_memory_bytes = 0.0;
  const std::vector<ChainState>& chains;
  // Per check (the round's first jobs): not in the cache when the round
  // began, before damaged entries were removed.
  const std::vector<char>& lacking;
};

// The renders of one round that the cache lacks.
struct RenderRound {
  const std::vector<Job>& jobs;
  const std::vector<std::size_t>& todo;          // into `jobs`, in the order to render them
  const std::vector<std::size_t>& group_starts;  // groups of `todo` one worker renders in order
  std::size_t cached = 0;                        // jobs of the round the cache held
  const RenderCache& cache;
  const Renderers& renderers;
  const ConvergenceRound* convergence = nullptr;  // when the round holds convergence checks
};

class Executor {
 public:
  virtual ~Executor() = default;
  // Renders, or hands on, the round's `todo`: records each job's outcome in
  // `r` (done with its image, attempted, its error) and counts it in `stats`
  // (rendered, failed and why; a submission).
  virtual void render(const RenderRound& round, Renders& r, StudyRunStats& stats) = 0;
  // True when render() hands renders on and returns before they are done. A
  // run then submits once: its first round with renders to do also carries
  // every job that does not wait for the truths (the external renderers',
  // the sections'), and the run ends after it.
  virtual bool submits() const = 0;
  // A file that remembers the renderers' probed versions across the many
  // processes of one study (probe_renderers in study/rendering.h); "": none.
  virtual std::string probe_cache(const std::string& study_folder) const = 0;
};

// Each keeps a reference to `options` (executor_local.cpp, executor_slurm.cpp).
std::unique_ptr<Executor> make_local_executor(const StudyOptions& options);
std::unique_ptr<Executor> make_slurm_executor(const StudyOptions& options);

// The executor the options choose: Slurm with options.slurm, else local.
inline std::unique_ptr<Executor> make_executor(const StudyOptions& options) {
  return options.slurm ? make_slurm_executor(options) : make_local_executor(options);
}

}  // namespace penumbra
