// Rendering a study's jobs on a Slurm cluster: the planner writes the jobs
// still missing from the cache into a batch file, `sbatch --array` runs
// chunks of it (each array task renders into the same content-addressed
// cache with the same atomic writes as a local run), and a report job that
// depends on the array runs `penumbra run` again, which reads the cache,
// submits what is still missing (a later convergence round, a task that was
// killed) or writes the report. A killed task, a preempted node or a second
// submission loses nothing and redoes nothing.
//
// Assumes a folder shared by the submitting host and the nodes (the study's
// output folder, at the same path everywhere) and the same Penumbra binary,
// harness and renderers on every node: array tasks check the renderer
// versions and code digests against the plan's and refuse to cache renders
// that would not match their keys.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "study/cache.h"
#include "study/plan.h"
#include "study/rendering.h"

namespace penumbra {

struct SlurmOptions {
  std::string partition;                 // empty: the cluster's default
  int array_limit = 64;                  // array tasks running at once (--array=...%N)
  int renders_per_task = 8;              // renders per array task, in plan order
  std::vector<std::string> sbatch_args;  // given to every sbatch call as they are
  // The command that continues the study (`penumbra run STUDY -o DIR
  // --executor slurm ...`), submitted as the report job; argv[0] an
  // absolute path.
  std::vector<std::string> continue_argv;
  // Set in the report job: the chain of submissions it continues. Failures
  // recorded by array tasks are then final for this chain; a run started by
  // hand clears them and tries again.
  std::string chain;
  double timeout_s = 60.0;  // for sbatch and squeue themselves
};

// What one `penumbra run --executor slurm` did with the renders it lacked.
struct SlurmSubmission {
  std::size_t submitted = 0;     // renders in the new array
  std::size_t still_queued = 0;  // renders of an earlier array still queued or running
  std::string array_job, report_job, batch_file, chain;
  int tasks = 0;
};

// Why a render failed in an array task ("" if it did not): the record the
// task left beside the cache entry. Given up renders (submitted
// kMaxSlurmSubmissions times in one chain without a result) fail too.
inline constexpr int kMaxSlurmSubmissions = 3;

// The renders of `todo` (indices into `jobs`) are sorted into: failed in this
// chain (their errors in `errors`), queued in an array that still runs, and
// submitted now. Returns what was submitted; `study_folder` holds cache/ and
// slurm/. Throws RendererError when sbatch fails or is missing.
SlurmSubmission submit_renders(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo,
                               const std::string& study_folder, const RenderCache& cache,
                               const std::vector<std::pair<RendererKind, RendererIdentity>>& ids,
                               double render_timeout_s, const SlurmOptions& options,
                               std::vector<std::string>& errors);

// The array task's side: renders task `task` of the batch file into the
// study's cache, recording each failure beside its entry; renders already
// cached are skipped. Returns the number of failures. Throws InputError for
// a batch file it cannot use, TaskCancelled when stopped (scancel).
struct SlurmTaskResult {
  std::size_t rendered = 0, cached = 0, failed = 0;
};
SlurmTaskResult run_slurm_task(const std::string& batch_file, int task, int threads,
                               const std::function<void(const std::string&)>& log);

// For `penumbra status DIR`: the submissions recorded in DIR/slurm, the
// renders of each that the cache holds, that failed and that are missing.
struct SlurmStatus {
  struct Batch {
    std::string file, array_job, report_job, chain;
    std::size_t renders = 0, done = 0, failed = 0;
  };
  std::vector<Batch> batches;
  bool report_written = false;
};
SlurmStatus slurm_status(const std::string& study_folder);

}  // namespace penumbra
