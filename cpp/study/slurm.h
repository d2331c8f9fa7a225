// Rendering a study's jobs on a Slurm cluster: the planner writes the jobs
// still missing from the cache into a batch file, `sbatch --array` runs
// chunks of it (each array task renders into the same content-addressed
// cache with the same atomic writes as a local run), and a report job that
// depends on the array runs `penumbra run` again, which reads the cache,
// submits what is still missing (a task that was killed) or writes the
// report. The ground-truth convergence, whose rounds depend on each other's
// images, goes to array tasks as one chain per variant (SlurmChain), so that
// a study needs one submission, not one per round. A killed task, a preempted node or a second
// submission loses nothing and redoes nothing.
//
// Assumes a folder shared by the submitting host and the nodes (the study's
// output folder, at the same path everywhere) and the same Penumbra binary,
// harness and renderers on every node: array tasks check the renderer
// versions and code digests against the plan's and refuse to cache renders
// that would not match their keys.
#pragma once

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "study/cache.h"
#include "study/plan.h"
#include "study/rendering.h"
#include "study/study_file.h"

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

// A variant's ground-truth convergence handed to one array task, so that its
// rounds need no submission each: the task continues the chain
// (continue_chain) from `edge_steps` and `spp_steps` refinements of `truth`,
// then renders `then`, the variant's evaluator jobs, at the settings reached.
// The next `penumbra run` finds those renders in the cache and makes the same
// decisions from them. The chain's batch entry is its first check still
// missing from the cache.
struct SlurmChain {
  Job truth;  // the plan's, at the plan's settings
  int edge_steps = 0, spp_steps = 0;
  GroundTruthSettings settings;
  double max_memory_bytes = 0.0;
  std::vector<Job> then;  // at the plan's settings
};
struct SlurmChains {
  std::map<std::string, SlurmChain> by_key;  // by the key of the chain's batch entry
  // The chains' other missing checks, each with its chain's entry key.
  std::map<std::string, std::string> covered;
};

// What one `penumbra run --executor slurm` did with the renders it lacked.
struct SlurmSubmission {
  std::size_t submitted = 0;     // renders in the new array
  std::size_t still_queued = 0;  // renders of an earlier array still queued or running
  std::size_t chains = 0;        // of them, convergence chains (SlurmChain)
  std::string array_job, report_job, batch_file, chain;
  int tasks = 0;
};

// Why a render failed in an array task ("" if it did not): the record the
// task left beside the cache entry. Given up renders (submitted
// kMaxSlurmSubmissions times in one chain without a result) fail too.
inline constexpr int kMaxSlurmSubmissions = 3;

// Array tasks of at most `per` renders over renders in submission order,
// whose group keys (render_group_key) are `keys`: a run of consecutive
// renders with one non-empty key (renders that share a mesh) is split only
// where it is longer than `per` itself, so that a task builds each mesh, or
// starts each Blender scene, once. Each task is [first, count).
std::vector<std::pair<std::size_t, std::size_t>> slurm_task_ranges(
    const std::vector<std::string>& keys, int per);

// The renders of `todo` (indices into `jobs`) are sorted into: failed in this
// chain (their errors in `errors`), queued in an array that still runs, and
// submitted now. A job whose key is in `chains` is submitted as that chain,
// in an array task of its own; one in `chains->covered` is left to its chain.
// Returns what was submitted; `study_folder` holds cache/ and slurm/. Throws
// RendererError when sbatch fails or is missing.
SlurmSubmission submit_renders(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo,
                               const std::string& study_folder, const RenderCache& cache,
                               const std::vector<std::pair<RendererKind, RendererIdentity>>& ids,
                               double render_timeout_s, const SlurmOptions& options,
                               std::vector<std::string>& errors,
                               const SlurmChains* chains = nullptr);

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
    std::size_t renders = 0, done = 0, failed = 0;  // renders other than chains
    std::size_t chains = 0;                         // convergence chains (SlurmChain)
  };
  std::vector<Batch> batches;
  bool report_written = false;
};
SlurmStatus slurm_status(const std::string& study_folder);

}  // namespace penumbra
