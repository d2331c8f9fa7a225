#include "study/study.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <limits>
#include <map>
#include <utility>

#include <fmt/format.h>

#include "image/image_io.h"
#include "scene/scene_json.h"
#include "study/cache.h"
#include "study/compare.h"
#include "study/convergence.h"
#include "study/execute.h"
#include "study/figures.h"
#include "study/filtering_study.h"
#include "study/interplay.h"
#include "study/plan.h"
#include "study/rendering.h"
#include "study/report_files.h"
#include "study/slurm.h"
#include "util/files.h"
#include "util/parallel.h"

namespace penumbra {
namespace fs = std::filesystem;

namespace {

void warn(const StudyOptions& options, StudyRunStats& stats, const std::string& text) {
  stats.warnings.push_back(text);
  if (options.log) options.log("WARNING: " + text);
}

// The state of every job after the render phase.
struct Renders {
  RenderedImages images;
  std::vector<std::string> errors;
  std::vector<char> attempted;
  std::vector<long> same_as;  // a job with an earlier job's key takes its result
  explicit Renders(std::size_t n) : errors(n), attempted(n, 0), same_as(n, -1) {
    images.done.assign(n, 0);
    images.images.resize(n);
  }
};

// Takes what the cache holds (verified entries only; damaged ones are removed
// with a warning) and returns the jobs still to render. Jobs with the same key
// (a ground truth shared by every tessellation level) are rendered once.
std::vector<std::size_t> use_cache(const std::vector<Job>& jobs, const RenderCache& cache,
                                   const StudyOptions& options, Renders& r, StudyRunStats& stats) {
  // Reading and verifying an entry (EXR decompression, checksum) is most of
  // a warm run: in parallel, each into its own slot; the verdicts are taken
  // in job order below.
  std::vector<std::string> reasons(jobs.size());
  std::vector<char> damaged(jobs.size(), 0);
  run_parallel(options.parallelism.renders, jobs.size(), [&](std::size_t i) {
    if (!cache.contains(jobs[i].key)) return;
    if (std::optional<Image> image = cache.lookup(jobs[i].key, &reasons[i])) {
      r.images.images[i] = std::move(*image);
      r.images.done[i] = 1;
    } else {
      damaged[i] = 1;
    }
  });
  std::vector<std::size_t> todo;
  std::map<std::string, std::size_t> first_with_key;
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    if (r.images.done[i]) {
      ++stats.cached;
      continue;
    }
    if (damaged[i] && !first_with_key.count(jobs[i].key)) {  // once per entry
      warn(options, stats,
           fmt::format("cache entry {} of {} is damaged: {}; rendering it again",
                       cache.exr_path(jobs[i].key), jobs[i].label, reasons[i]));
      cache.remove(jobs[i].key);
    }
    if (const auto [it, inserted] = first_with_key.try_emplace(jobs[i].key, i); !inserted)
      r.same_as[i] = static_cast<long>(it->second);
    else
      todo.push_back(i);
  }
  return todo;
}

// The jobs of `todo` in plan order, each group placed at its first member;
// Blender groups sorted by method, so that renders with the same material
// follow each other. Blender groups are groups of tasks for one worker
// (execute_tasks), in `group_starts`; an evaluator render uses its own.
struct Order {
  std::vector<std::size_t> todo, group_starts;
};
Order group_by_mesh(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo) {
  std::vector<std::string> keys(todo.size());
  std::map<std::string, std::vector<std::size_t>> groups;
  for (std::size_t k = 0; k < todo.size(); ++k) {
    keys[k] = render_group_key(jobs[todo[k]]);
    if (!keys[k].empty()) groups[keys[k]].push_back(todo[k]);
  }
  Order order;
  auto add = [&](std::size_t i, bool starts) {
    if (starts) order.group_starts.push_back(order.todo.size());
    order.todo.push_back(i);
  };
  for (std::size_t k = 0; k < todo.size(); ++k) {
    if (keys[k].empty()) {
      add(todo[k], true);
      continue;
    }
    const auto group = groups.find(keys[k]);
    if (group == groups.end()) continue;  // placed with the first of its group
    std::vector<std::size_t>& members = group->second;
    const bool blender = jobs[members.front()].renderer == RendererKind::kBlender;
    if (blender)
      std::stable_sort(members.begin(), members.end(), [&](std::size_t a, std::size_t b) {
        return jobs[a].scene_json["terminator"].dump() < jobs[b].scene_json["terminator"].dump();
      });
    for (std::size_t m = 0; m < members.size(); ++m) add(members[m], !blender || m == 0);
    groups.erase(group);
  }
  return order;
}

// Copies each job's result to the later jobs with the same key; counts what
// never started.
void settle_duplicates(const std::vector<Job>& jobs, Renders& r, StudyRunStats& stats) {
  for (std::size_t i = 0; i < jobs.size(); ++i)
    if (r.same_as[i] >= 0) {
      const auto j = static_cast<std::size_t>(r.same_as[i]);
      r.images.done[i] = r.images.done[j], r.attempted[i] = r.attempted[j];
      r.errors[i] = r.errors[j];
      r.images.images[i] = r.images.images[j];
    }
  for (std::size_t i = 0; i < jobs.size(); ++i)
    if (!r.images.done[i] && !r.attempted[i]) ++stats.not_started;
}

// The Slurm executor's render phase: failures its array tasks recorded count
// as failed renders, the rest is submitted (or still queued) and not started
// here.
void slurm_phase(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo,
                 const RenderCache& cache, const StudyOptions& options, const Renderers& renderers,
                 const SlurmChains* chains, Renders& r, StudyRunStats& stats) {
  // One submission per run, whose report job is the one continuation: later
  // rounds of this run wait for it.
  if (todo.empty() || (stats.slurm && stats.slurm->submitted > 0))
    return settle_duplicates(jobs, r, stats);
  const SlurmSubmission sub =
      submit_renders(jobs, todo, options.output_dir, cache, renderers.identities, options.timeout_s,
                     *options.slurm, r.errors, chains);
  for (std::size_t i : todo)
    if (!r.errors[i].empty()) {
      r.attempted[i] = 1;
      ++stats.failed;
      stats.failures.push_back(jobs[i].label + ": " +
                               r.errors[i].substr(0, r.errors[i].find('\n')));
    }
  if (options.log && sub.submitted > 0)
    options.log(fmt::format(
        "slurm: submitted {} renders as array job {} ({} tasks{}); the report follows as job {}",
        sub.submitted - sub.chains, sub.array_job, sub.tasks,
        sub.chains > 0 ? fmt::format(", with {} ground-truth convergence chains", sub.chains) : "",
        sub.report_job));
  if (options.log && sub.still_queued > 0)
    options.log(fmt::format("slurm: {} renders are still queued or running", sub.still_queued));
  stats.slurm = sub;
  settle_duplicates(jobs, r, stats);
}

// The render phase: the cache, then what it lacks; counts what never started.
Renders render_jobs(const std::string& study_file, const std::vector<Job>& jobs,
                    const RenderCache& cache, const StudyOptions& options,
                    const Renderers& renderers, StudyRunStats& stats,
                    const SlurmChains* chains = nullptr) {
  Renders r(jobs.size());
  const std::size_t cached_before = stats.cached;
  const Order order = group_by_mesh(jobs, use_cache(jobs, cache, options, r, stats));
  const std::vector<std::size_t>& todo = order.todo;
  const std::size_t cached = stats.cached - cached_before;
  // The cache must hold what is to be rendered (uncompressed EXR sizes).
  ResourceEstimate needed;
  for (std::size_t i : todo) needed.output_bytes += jobs[i].resources.output_bytes;
  check_resources(needed, std::numeric_limits<double>::infinity(), study_file, cache.folder());
  if (options.slurm) {
    slurm_phase(jobs, todo, cache, options, renderers, chains, r, stats);
    return r;
  }
  if (options.log)
    options.log(fmt::format("{} renders: {} cached, {} to do, {} in parallel", jobs.size(), cached,
                            todo.size(), options.parallelism.renders));
  ExecuteOptions eo;
  eo.jobs = options.parallelism.renders;
  eo.max_started = options.max_new_renders;
  eo.interrupted = options.interrupted;
  eo.log = options.log;
  eo.progress = options.progress;
  eo.already_done = cached;
  eo.total = jobs.size();
  eo.group_starts = order.group_starts;
  MethodBatches batches(jobs, todo);
  stats.method_batches += batches.batches();
  stats.batched_renders += batches.members();
  if (options.log && batches.batches() > 0)
    options.log(fmt::format("{} of them in {} passes that render several methods of one variant",
                            batches.members(), batches.batches()));
  const ExecuteResult result = execute_tasks(
      todo.size(), eo,
      [&](std::size_t t) {
        r.images.images[todo[t]] =
            render_into_cache(jobs[todo[t]], cache, options.timeout_s,
                              options.parallelism.threads_per_render, renderers, &batches);
      },
      [&](std::size_t t) { return jobs[todo[t]].label; });
  for (std::size_t t = 0; t < todo.size(); ++t) {
    const std::size_t i = todo[t];
    r.images.done[i] = result.done[t], r.attempted[i] = result.attempted[t];
    r.errors[i] = result.errors[t];
    if (result.done[t]) ++stats.rendered;
    if (result.attempted[t] && !result.done[t]) {
      ++stats.failed;
      stats.failures.push_back(jobs[i].label + ": " +
                               r.errors[i].substr(0, r.errors[i].find('\n')));
    }
  }
  settle_duplicates(jobs, r, stats);
  return r;
}

// The study folder's subfolders, cleared of what killed runs left.
void prepare_folders(const fs::path& out, const StudyOptions& options, StudyRunStats& stats) {
  for (const char* sub : {"cache", "images"}) {
    std::error_code ec;
    fs::create_directories(out / sub, ec);
    if (ec)
      throw OutputError(fmt::format("{}: cannot create: {}", (out / sub).string(), ec.message()));
    // What a killed earlier run (kill -9) left half-written.
    stats.stale_removed += remove_stale_temporaries((out / sub).string());
  }
  if (stats.stale_removed > 0)
    warn(options, stats,
         fmt::format("removed {} temporary files and work folders of killed runs",
                     stats.stale_removed));
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// On Slurm, every variant whose checks this round lacks goes to an array task
// as the rest of its chain, with its evaluator jobs (plan settings) to render
// at the settings reached: one submission instead of one per round.
// Variants with the same truth (the same check keys) decide alike: one chain
// renders the evaluator jobs of all of them.
SlurmChains chains_to_submit(const Plan& plan, const Study& study, double max_memory_bytes,
                             const std::vector<Job>& keyed, const std::vector<ChainState>& chains,
                             const RenderCache& cache) {
  SlurmChains out;
  for (const ChainState& c : chains) {
    std::vector<std::size_t> missing;
    for (std::size_t i = c.first; i < c.first + c.count; ++i)
      if (!cache.contains(keyed[i].key)) missing.push_back(i);
    if (missing.empty()) continue;
    std::vector<Job> then;
    for (std::size_t j : plan.variants[c.truth->variant].jobs)
      if (plan.jobs[j].renderer == RendererKind::kEvaluator) then.push_back(plan.jobs[j]);
    for (std::size_t k = 1; k < missing.size(); ++k)
      out.covered.emplace(keyed[missing[k]].key, keyed[missing[0]].key);
    const auto [it, inserted] = out.by_key.try_emplace(keyed[missing[0]].key);
    if (inserted)
      it->second = {*c.truth, c.edge_steps, c.spp_steps, study.ground_truth, max_memory_bytes, {}};
    it->second.then.insert(it->second.then.end(), then.begin(), then.end());
  }
  return out;
}

// The convergence phase: check renders go through the cache like any other.
std::vector<VariantConvergence> converge(const Study& study, Plan& plan, const RenderCache& cache,
                                         const StudyOptions& options, const Renderers& renderers,
                                         StudyRunStats& stats) {
  // On Slurm each round is a submission; the external renderers' jobs do
  // not depend on the truths' settings, so the first one carries them too
  // and they render while the truths converge.
  bool carry_external = options.slurm.has_value();
  const RenderBatch batch = [&](const std::vector<Job>& jobs, const std::vector<ChainState>& chains,
                                std::vector<std::string>* errors) {
    std::vector<Job> keyed = jobs;
    assign_keys(keyed, renderers.identities);
    const std::size_t checks = keyed.size();
    if (options.log)
      options.log(fmt::format("ground truth: checking convergence ({} renders)", checks));
    // Only with a round that must be submitted anyway: a run submits once.
    const bool submits = std::any_of(keyed.begin(), keyed.end(),
                                     [&](const Job& j) { return !cache.contains(j.key); });
    const SlurmChains slurm_chains =
        submits && options.slurm
            ? chains_to_submit(plan, study, options.max_memory_bytes, keyed, chains, cache)
            : SlurmChains{};
    if (submits && std::exchange(carry_external, false))
      for (const Job& j : plan.jobs)
        if (j.renderer != RendererKind::kEvaluator) keyed.push_back(j);
    StudyRunStats carried;  // the external jobs are counted in the main phase
    const Renders r = render_jobs(study.file, keyed, cache, options, renderers,
                                  keyed.size() == checks ? stats : carried, &slurm_chains);
    if (keyed.size() != checks) {
      stats.slurm = carried.slurm;
      stats.not_started += carried.not_started;
    }
    stats.renders += checks;
    std::vector<std::optional<Image>> images(checks);
    for (std::size_t i = 0; i < checks; ++i)
      if (r.images.done[i]) images[i] = r.images.images[i];
    errors->assign(r.errors.begin(), r.errors.begin() + static_cast<long>(checks));
    return images;
  };
  std::vector<VariantConvergence> out =
      converge_truths(plan, study.ground_truth, options.max_memory_bytes, batch);
  // Verdicts on renders that never ran (interrupted, submitted to Slurm) are
  // no verdicts: the run stops before the report.
  if (options.log && stats.not_started == 0)
    for (const VariantConvergence& r : out) options.log(convergence_log_line(plan, r));
  assign_keys(plan, renderers.identities);
  return out;
}

// A dry run decides the truths' settings from the cached check renders
// alone, as the real run would, so that the jobs it counts carry the keys
// the run will look up (the bump renders share their truth's samples). A
// check missing from the cache stops that variant at the settings reached;
// it is counted as a render to do.
// The first round of convergence checks that the cache lacks (counted in
// stats and returned, keyed, for the cost estimate).
std::vector<Job> dry_run_convergence(const Study& study, Plan& plan, const RenderCache& cache,
                                     const StudyOptions& options, const Renderers& renderers,
                                     StudyRunStats& stats) {
  std::vector<Job> missing;
  const RenderBatch from_cache = [&](const std::vector<Job>& jobs, const std::vector<ChainState>&,
                                     std::vector<std::string>* errors) {
    std::vector<Job> keyed = jobs;
    assign_keys(keyed, renderers.identities);
    std::vector<std::optional<Image>> images(keyed.size());
    errors->assign(keyed.size(), "");
    for (std::size_t i = 0; i < keyed.size(); ++i) {
      std::string reason;
      if (cache.contains(keyed[i].key)) images[i] = cache.lookup(keyed[i].key, &reason);
      if (!images[i]) {
        (*errors)[i] = "not rendered yet (dry run)";
        ++stats.planned_checks;
        stats.planned_output_bytes += keyed[i].resources.output_bytes;
        missing.push_back(keyed[i]);
      }
    }
    return images;
  };
  converge_truths(plan, study.ground_truth, options.max_memory_bytes, from_cache);
  assign_keys(plan, renderers.identities);
  return missing;
}

void count_planned(const Plan& plan, const RenderCache& cache, const std::vector<Job>& checks,
                   int cores, StudyRunStats& stats) {
  std::vector<char> to_render(plan.jobs.size(), 0);
  for (std::size_t i = 0; i < plan.jobs.size(); ++i) {
    const Job& job = plan.jobs[i];
    ++stats.planned[to_string(job.renderer)];
    if (cache.contains(job.key)) {
      ++stats.cached;
    } else {
      to_render[i] = 1;
      stats.planned_output_bytes += job.resources.output_bytes;
    }
    stats.planned_peak_memory_bytes =
        std::max(stats.planned_peak_memory_bytes, job.resources.memory_bytes);
  }
  stats.cost = estimate_cost(plan, cache, to_render, checks, cores);
}

// Every comparison, those of images compared before taken from the store.
Comparisons compare_renders(const Plan& plan, const RenderedImages& images, const fs::path& out,
                            const StudyOptions& options, StudyRunStats& stats) {
  std::string warning;
  ComparisonStore store((out / "cache" / "comparisons.bin").string(), &warning);
  if (!warning.empty()) warn(options, stats, warning);
  PreviewFolder pictures(out);
  Comparisons c = compare_study(plan, images, pictures, options.parallelism.renders, &store);
  store.save();
  pictures.save();
  stats.comparisons_measured = store.inserted();
  stats.comparisons_kept = store.found();
  stats.pictures_drawn = pictures.drawn();
  stats.pictures_kept = pictures.kept();
  if (options.log)
    options.log(fmt::format(
        "comparisons: {} measured, {} kept from earlier runs; pictures: {} drawn, {} kept",
        store.inserted(), store.found(), pictures.drawn(), pictures.kept()));
  return c;
}

}  // namespace

StudyRunStats run_study(const Study& study, const StudyOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const fs::path out(options.output_dir);
  // A Slurm study probes from many short processes (report jobs): once per
  // host and renderer executable is enough.
  const std::string probes =
      options.slurm && !options.dry_run
          ? (out / "slurm" / fmt::format("versions.{}.json", host_tag())).string()
          : "";
  Renderers renderers = probe_renderers(study_renderers(study), options.timeout_s, probes);
  Plan plan = plan_study(study, options.max_memory_bytes);
  assign_keys(plan, renderers.identities);
  const RenderCache cache((out / "cache").string());

  StudyRunStats stats;
  stats.renders = plan.jobs.size();
  if (options.log)
    for (const std::string& notice : study.notices) options.log("notice: " + notice);
  if (options.dry_run) {
    const std::vector<Job> checks =
        dry_run_convergence(study, plan, cache, options, renderers, stats);
    count_planned(plan, cache, checks, options.parallelism.renders * options.parallelism.threads_per_render, stats);
    return stats;
  }
  prepare_folders(out, options, stats);
  auto blender_sessions = std::make_unique<BlenderSessions>((out / "cache").string());
  renderers.blender_sessions = blender_sessions.get();
  const std::vector<VariantConvergence> convergence =
      converge(study, plan, cache, options, renderers, stats);
  if (stats.not_started > 0) {  // interrupted while checking the truths
    stats.seconds = seconds_since(start);
    return stats;
  }
  const Renders r = render_jobs(study.file, plan.jobs, cache, options, renderers, stats);
  stats.blender_processes = blender_sessions->started();
  blender_sessions.reset();  // the processes end here, not after the figures
  renderers.blender_sessions = nullptr;
  stats.seconds = seconds_since(start);
  if (stats.not_started > 0) return stats;  // interrupted: no report from a partial study

  const Comparisons comparisons = compare_renders(plan, r.images, out, options, stats);
  const std::vector<FilteringEntry> filtering =
      study.filtering ? run_filtering_section(*study.filtering, out.string(),
                                              options.parallelism.renders, options.log)
                      : std::vector<FilteringEntry>{};
  std::optional<InterplayResult> interplay;
  if (study.interplay)
    interplay = run_interplay_section(*study.interplay, out.string(), cache, renderers,
                                      options.parallelism.threads(), options.log);
  write_report_files({study, plan, comparisons, renderers.versions, r.errors, r.images.done,
                      convergence, filtering, interplay ? &*interplay : nullptr},
                     out.string());
  if (options.figures) {
    if (options.log)
      options.log(
          fmt::format("figures: drawing the figures and report.html (harness/report.py, "
                      "log {}) ...",
                      (out / "report.log").string()));
    // The figures grow with variants x methods (72 x 20 in the default
    // study: about 5 min on 2 idle cores), so they get at least an hour,
    // not one render's time-out.
    const double figures_timeout_s = std::max(options.timeout_s, kFiguresTimeoutS);
    stats.report_html = draw_report(
        out.string(), options.self_contained_html, options.python, figures_timeout_s,
        [&](const std::string& line) {
          if (options.log) options.log("figures: " + line);
        },
        /*reuse_unchanged=*/true);
  }
  stats.seconds = seconds_since(start);
  return stats;
}

}  // namespace penumbra
