#include "study/study.h"

#include <chrono>
#include <filesystem>
#include <limits>

#include <fmt/format.h>

#include "image/image_io.h"
#include "scene/scene_json.h"
#include "study/cache.h"
#include "study/compare.h"
#include "study/convergence.h"
#include "study/execute.h"
#include "study/figures.h"
#include "study/plan.h"
#include "study/report_files.h"
#include "util/files.h"

namespace penumbra {
namespace fs = std::filesystem;

namespace {

// What the renderers are: versions (a missing renderer fails its renders,
// not the study) and the digests of the code behind their pixels.
struct Renderers {
  std::map<RendererKind, std::string> versions, unavailable;
  std::vector<std::pair<RendererKind, RendererIdentity>> identities;
};

Renderers probe_renderers(const Study& study, double timeout_s) {
  std::vector<RendererKind> kinds = study.bump.renderers;
  if (study.lowpoly)
    for (RendererKind r : study.lowpoly->renderers)
      if (std::find(kinds.begin(), kinds.end(), r) == kinds.end()) kinds.push_back(r);
  Renderers out;
  for (RendererKind r : kinds) {
    RenderSettings probe;
    probe.timeout_s = timeout_s;
    RendererIdentity id;
    try {
      id.version = out.versions[r] = renderer_version(r, probe);
      id.code_digest = pixel_code_digest(r, probe);
    } catch (const std::exception& e) {
      out.versions.erase(r);
      out.unavailable[r] = e.what();
    }
    out.identities.push_back({r, id});
  }
  return out;
}

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
  std::vector<std::size_t> todo;
  std::map<std::string, std::size_t> first_with_key;
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    if (cache.contains(jobs[i].key)) {
      std::string reason;
      if (std::optional<Image> image = cache.lookup(jobs[i].key, &reason)) {
        r.images.images[i] = std::move(*image);
        r.images.done[i] = 1;
        ++stats.cached;
        continue;
      }
      warn(options, stats,
           fmt::format("cache entry {} of {} is damaged: {}; rendering it again",
                       cache.exr_path(jobs[i].key), jobs[i].label, reason));
      cache.remove(jobs[i].key);
    }
    if (const auto [it, inserted] = first_with_key.try_emplace(jobs[i].key, i); !inserted)
      r.same_as[i] = static_cast<long>(it->second);
    else
      todo.push_back(i);
  }
  return todo;
}

// Renders `job` and writes it into the cache; returns the image. Throws
// RendererError, TaskCancelled when interrupted.
Image render_into_cache(const Job& job, const RenderCache& cache, const StudyOptions& options,
                        const Renderers& renderers) {
  if (const auto missing = renderers.unavailable.find(job.renderer);
      missing != renderers.unavailable.end())
    throw RendererError(missing->second);
  RenderSettings settings;
  settings.timeout_s = options.timeout_s;
  settings.threads = threads_per_job(options.jobs);
  settings.log_path = cache.log_path(job.key);
  std::error_code ignored;
  fs::remove(settings.log_path, ignored);
  RendererRun run;
  try {
    run = render_with(job.renderer, job.scene, settings);
  } catch (const RenderCancelled&) {
    throw TaskCancelled{};
  }
  cache.store(job.key, run.image,
              {{"penumbra:version", kPenumbraVersion},
               {"penumbra:renderer", to_string(job.renderer)},
               {"penumbra:renderer_version", renderers.versions.at(job.renderer)},
               {"penumbra:scene", job.scene_json.dump()},
               {"penumbra:method", job.method},
               {"penumbra:representation", to_string(job.representation)},
               {"penumbra:radiance_unit", "W m^-2 sr^-1"}});
  if (job.renderer == RendererKind::kEvaluator) fs::remove(settings.log_path, ignored);
  return std::move(run.image);
}

// The render phase: the cache, then what it lacks; counts what never started.
Renders render_jobs(const std::string& study_file, const std::vector<Job>& jobs,
                    const RenderCache& cache, const StudyOptions& options,
                    const Renderers& renderers, StudyRunStats& stats) {
  Renders r(jobs.size());
  const std::size_t cached_before = stats.cached;
  const std::vector<std::size_t> todo = use_cache(jobs, cache, options, r, stats);
  const std::size_t cached = stats.cached - cached_before;
  // The cache must hold what is to be rendered (uncompressed EXR sizes).
  ResourceEstimate needed;
  for (std::size_t i : todo) needed.output_bytes += jobs[i].resources.output_bytes;
  check_resources(needed, std::numeric_limits<double>::infinity(), study_file, cache.folder());
  if (options.log)
    options.log(fmt::format("{} renders: {} cached, {} to do, {} in parallel", jobs.size(), cached,
                            todo.size(), options.jobs));
  ExecuteOptions eo;
  eo.jobs = options.jobs;
  eo.max_started = options.max_new_renders;
  eo.interrupted = options.interrupted;
  eo.log = options.log;
  eo.progress = options.progress;
  eo.already_done = cached;
  eo.total = jobs.size();
  const ExecuteResult result = execute_tasks(
      todo.size(), eo,
      [&](std::size_t t) {
        r.images.images[todo[t]] = render_into_cache(jobs[todo[t]], cache, options, renderers);
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
  for (std::size_t i = 0; i < jobs.size(); ++i)
    if (r.same_as[i] >= 0) {
      const auto j = static_cast<std::size_t>(r.same_as[i]);
      r.images.done[i] = r.images.done[j], r.attempted[i] = r.attempted[j];
      r.errors[i] = r.errors[j];
      r.images.images[i] = r.images.images[j];
    }
  for (std::size_t i = 0; i < jobs.size(); ++i)
    if (!r.images.done[i] && !r.attempted[i]) ++stats.not_started;
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

// The convergence phase: check renders go through the cache like any other.
std::vector<VariantConvergence> converge(const Study& study, Plan& plan, const RenderCache& cache,
                                         const StudyOptions& options, const Renderers& renderers,
                                         StudyRunStats& stats) {
  const RenderBatch batch = [&](const std::vector<Job>& jobs, std::vector<std::string>* errors) {
    std::vector<Job> keyed = jobs;
    assign_keys(keyed, renderers.identities);
    if (options.log)
      options.log(fmt::format("ground truth: checking convergence ({} renders)", keyed.size()));
    const Renders r = render_jobs(study.file, keyed, cache, options, renderers, stats);
    stats.renders += keyed.size();
    std::vector<std::optional<Image>> images(keyed.size());
    for (std::size_t i = 0; i < keyed.size(); ++i)
      if (r.images.done[i]) images[i] = r.images.images[i];
    *errors = r.errors;
    return images;
  };
  std::vector<VariantConvergence> out =
      converge_truths(plan, study.ground_truth, options.max_memory_bytes, batch, options.log);
  assign_keys(plan, renderers.identities);
  return out;
}

}  // namespace

StudyRunStats run_study(const Study& study, const StudyOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const fs::path out(options.output_dir);
  const Renderers renderers = probe_renderers(study, options.timeout_s);
  Plan plan = plan_study(study, options.max_memory_bytes);
  assign_keys(plan, renderers.identities);
  const RenderCache cache((out / "cache").string());

  StudyRunStats stats;
  stats.renders = plan.jobs.size();
  if (options.dry_run) {
    for (const Job& job : plan.jobs) {
      ++stats.planned[to_string(job.renderer)];
      if (cache.contains(job.key)) ++stats.cached;
    }
    return stats;
  }
  prepare_folders(out, options, stats);
  const std::vector<VariantConvergence> convergence =
      converge(study, plan, cache, options, renderers, stats);
  if (stats.not_started > 0) return stats;  // interrupted while checking the truths
  const Renders r = render_jobs(study.file, plan.jobs, cache, options, renderers, stats);
  stats.seconds = seconds_since(start);
  if (stats.not_started > 0) return stats;  // interrupted: no report from a partial study

  const Comparisons comparisons = compare_study(plan, r.images, out.string());
  write_report_files(
      {study, plan, comparisons, renderers.versions, r.errors, r.images.done, convergence},
      out.string());
  if (options.figures) {
    if (options.log)
      options.log(
          fmt::format("figures: drawing the figures and report.html (harness/report.py, "
                      "log {}) ...",
                      (out / "report.log").string()));
    stats.report_html = draw_report(out.string(), options.python, options.timeout_s);
  }
  stats.seconds = seconds_since(start);
  return stats;
}

}  // namespace penumbra
