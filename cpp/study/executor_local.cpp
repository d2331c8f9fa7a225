// The local executor: the round's renders on --jobs worker threads, each
// with its share of the cores (util/parallel.h Parallelism).
#include <fmt/format.h>

#include "study/execute.h"
#include "study/executor.h"

namespace penumbra {

namespace {

class LocalExecutor : public Executor {
 public:
  explicit LocalExecutor(const StudyOptions& options) : options_(options) {}

  void render(const RenderRound& round, Renders& r, StudyRunStats& stats) override {
    const std::vector<Job>& jobs = round.jobs;
    const std::vector<std::size_t>& todo = round.todo;
    if (options_.log)
      options_.log(fmt::format("{} renders: {} cached, {} to do, {} in parallel", jobs.size(),
                               round.cached, todo.size(), options_.parallelism.renders));
    MethodBatches batches(jobs, todo, options_.shared_truths);
    stats.method_batches += batches.batches();
    stats.batched_renders += batches.members();
    stats.truth_batches += batches.truth_batches();
    stats.batched_truths += batches.truth_members();
    if (options_.log && batches.batches() > 0)
      options_.log(fmt::format("{} of them in {} passes that render several methods of one variant",
                               batches.members(), batches.batches()));
    if (options_.log && batches.truth_batches() > 0)
      options_.log(
          fmt::format("{} of them in {} passes that render the ground truths of several lights and "
                      "materials on one displaced mesh",
                      batches.truth_members(), batches.truth_batches()));
    std::vector<double> core_seconds(todo.size(), 0.0);  // one slot per task: no lock
    const ExecuteResult result = execute_tasks(
        todo.size(), execute_options(round),
        [&](std::size_t t) {
          r.images.images[todo[t]] = render_into_cache(
              jobs[todo[t]], round.cache, options_.timeout_s,
              options_.parallelism.threads_per_render, round.renderers, &batches, &core_seconds[t]);
        },
        [&](std::size_t t) { return jobs[todo[t]].label; });
    for (std::size_t t = 0; t < todo.size(); ++t) {
      const std::size_t i = todo[t];
      r.images.done[i] = result.done[t], r.attempted[i] = result.attempted[t];
      r.errors[i] = result.errors[t];
      if (result.done[t]) ++stats.rendered, stats.render_core_seconds += core_seconds[t];
      if (result.attempted[t] && !result.done[t]) count_failure(jobs[i], r.errors[i], stats);
    }
  }

  bool submits() const override { return false; }
  std::string probe_cache(const std::string&) const override { return ""; }

 private:
  ExecuteOptions execute_options(const RenderRound& round) const {
    ExecuteOptions eo;
    eo.jobs = options_.parallelism.renders;
    eo.max_started = options_.max_new_renders;
    eo.interrupted = options_.interrupted;
    eo.log = options_.log;
    eo.progress = options_.progress;
    eo.already_done = round.cached;
    eo.total = round.jobs.size();
    eo.group_starts = round.group_starts;
    return eo;
  }

  const StudyOptions& options_;
};

}  // namespace

std::unique_ptr<Executor> make_local_executor(const StudyOptions& options) {
  return std::make_unique<LocalExecutor>(options);
}

}  // namespace penumbra
