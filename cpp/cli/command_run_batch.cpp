// `penumbra run-batch`: one array task of a Slurm study (study/slurm.h), as
// sbatch runs it.
#include <cstdlib>

#include <fmt/format.h>

#include "cli/command.h"
#include "cli/stop_signals.h"
#include "study/execute.h"
#include "study/slurm.h"

namespace penumbra {

namespace {

struct RunBatchArgs {
  std::string batch;
  int task = -1;  // default: SLURM_ARRAY_TASK_ID
};

int run_batch(const RunBatchArgs& a, const CommandContext& c) {
  int task = a.task;
  if (task < 0) {
    const char* env = std::getenv("SLURM_ARRAY_TASK_ID");
    if (!env) throw UsageError("run-batch: no --task and no SLURM_ARRAY_TASK_ID");
    task = std::atoi(env);
  }
  // A task renders one image at a time with the cores Slurm gave it.
  const char* cpus = std::getenv("SLURM_CPUS_PER_TASK");
  const Parallelism parallelism{1, cpus && std::atoi(cpus) > 0 ? std::atoi(cpus) : 1};
  const StopSignals stop;
  SlurmTaskResult r;
  try {
    r = run_slurm_task(a.batch, task, parallelism.threads_per_render, [&](const std::string& line) {
      c.err << "penumbra run-batch: " << line << "\n" << std::flush;
    });
  } catch (const TaskCancelled&) {
    c.err << "penumbra run-batch: stopped; unfinished renders are submitted again by the report "
             "job\n";
    return StopSignals::exit_code();
  }
  c.out << fmt::format(
      "task {}: {} rendered, {} already cached, {} failed (recorded beside the "
      "cache entries)\n",
      task, r.rendered, r.cached, r.failed);
  return r.failed > 0 ? kExitFailure : kExitOk;
}

}  // namespace

Command add_run_batch_command(CLI::App& app, SharedOptions&) {
  auto a = std::make_shared<RunBatchArgs>();
  CLI::App* cmd = app.add_subcommand(
      "run-batch",
      "render one array task of a Slurm study's batch file into its cache (run by sbatch)");
  cmd->add_option("batch", a->batch, "batch file (STUDY_DIR/slurm/batch-*.json)")->required();
  cmd->add_option("--task", a->task, "task index (default: SLURM_ARRAY_TASK_ID)")
      ->check(CLI::NonNegativeNumber);
  return {cmd, [a](const CommandContext& c) { return run_batch(*a, c); }};
}

}  // namespace penumbra
