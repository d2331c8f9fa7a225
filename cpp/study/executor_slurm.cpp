// The Slurm executor: the round's renders as one job array and a report job
// that runs the study again (study/slurm.h). A run submits once; convergence
// checks go to array tasks as whole chains, so that the truths need no
// submission per round.
#include <filesystem>

#include <fmt/format.h>

#include "study/executor.h"
#include "study/slurm.h"
#include "util/files.h"

namespace penumbra {
namespace fs = std::filesystem;

namespace {

// Every variant whose checks the round lacks goes to an array task as the
// rest of its chain, with its evaluator jobs (plan settings) to render at the
// settings reached. Variants with the same truth (the same check keys) decide
// alike: one chain renders the evaluator jobs of all of them.
SlurmChains chains_to_submit(const ConvergenceRound& round, const std::vector<Job>& keyed) {
  SlurmChains out;
  const Plan& plan = round.plan;
  for (const ChainState& c : round.chains) {
    std::vector<std::size_t> missing;
    for (std::size_t i = c.first; i < c.first + c.count; ++i)
      if (round.lacking[i]) missing.push_back(i);
    if (missing.empty()) continue;
    std::vector<Job> then;
    for (std::size_t j : plan.variants[c.truth->variant].jobs)
      if (plan.jobs[j].renderer == RendererKind::kEvaluator) then.push_back(plan.jobs[j]);
    for (std::size_t k = 1; k < missing.size(); ++k)
      out.covered.emplace(keyed[missing[k]].key, keyed[missing[0]].key);
    const auto [it, inserted] = out.by_key.try_emplace(keyed[missing[0]].key);
    if (inserted)
      it->second = {*c.truth,       c.edge_steps,           c.spp_steps,
                    round.settings, round.max_memory_bytes, {}};
    it->second.then.insert(it->second.then.end(), then.begin(), then.end());
  }
  return out;
}

class SlurmExecutor : public Executor {
 public:
  explicit SlurmExecutor(const StudyOptions& options) : options_(options) {}

  // Failures its array tasks recorded count as failed renders; the rest is
  // submitted (or still queued) and not started here.
  void render(const RenderRound& round, Renders& r, StudyRunStats& stats) override {
    // One submission per run, whose report job is the one continuation:
    // later rounds of this run wait for it.
    if (round.todo.empty() || (stats.slurm && stats.slurm->submitted > 0)) return;
    const SlurmChains chains =
        round.convergence ? chains_to_submit(*round.convergence, round.jobs) : SlurmChains{};
    const SlurmSubmission sub = submit_renders(
        round.jobs, round.todo, options_.output_dir, round.cache, round.renderers.identities,
        options_.timeout_s, *options_.slurm, r.errors, &chains);
    for (std::size_t i : round.todo)
      if (!r.errors[i].empty()) {
        r.attempted[i] = 1;
        count_failure(round.jobs[i], r.errors[i], stats);
      }
    log_submission(sub);
    stats.slurm = sub;
  }

  bool submits() const override { return true; }

  // A Slurm study probes from many short processes (report jobs): once per
  // host and renderer executable is enough.
  std::string probe_cache(const std::string& study_folder) const override {
    return (fs::path(study_folder) / "slurm" / fmt::format("versions.{}.json", host_tag()))
        .string();
  }

 private:
  void log_submission(const SlurmSubmission& sub) const {
    if (!options_.log) return;
    if (sub.submitted > 0)
      options_.log(fmt::format(
          "slurm: submitted {} renders as array job {} ({} tasks{}); the report follows as job {}",
          sub.submitted - sub.chains, sub.array_job, sub.tasks,
          sub.chains > 0 ? fmt::format(", with {} ground-truth convergence chains", sub.chains)
                         : "",
          sub.report_job));
    if (sub.still_queued > 0)
      options_.log(fmt::format("slurm: {} renders are still queued or running", sub.still_queued));
  }

  const StudyOptions& options_;
};

}  // namespace

std::unique_ptr<Executor> make_slurm_executor(const StudyOptions& options) {
  return std::make_unique<SlurmExecutor>(options);
}

}  // namespace penumbra
