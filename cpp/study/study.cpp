#include "study/study.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <type_traits>
#include <utility>

#include <fmt/format.h>

#include "evaluator/displaced_mesh.h"
#include "image/image_io.h"
#include "scene/scene_json.h"
#include "study/cache.h"
#include "study/compare.h"
#include "study/convergence.h"
#include "study/executor.h"
#include "study/figures.h"
#include "study/filtering_study.h"
#include "study/fit.h"
#include "study/interplay.h"
#include "study/plan.h"
#include "study/rendering.h"
#include "study/report_files.h"
#include "study/sections.h"
#include "util/files.h"
#include "util/parallel.h"

namespace penumbra {
namespace fs = std::filesystem;

namespace {

void warn(const StudyOptions& options, StudyRunStats& stats, const std::string& text) {
  stats.warnings.push_back(text);
  if (options.log) options.log("WARNING: " + text);
}

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
      r.cached[i] = 1;
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
// follow each other. Each group is a group of tasks for one worker
// (execute_tasks), in `group_starts`: a serving Blender keeps its mesh, and
// the evaluator's renders that share a pass (MethodBatches: the truths on one
// mesh, the methods of one variant) are taken by the worker whose task
// renders the pass, which then finds their images ready, while the other
// workers go on to other renders instead of waiting for that pass.
struct Order {
  std::vector<std::size_t> todo, group_starts;
};
// render_group_key, and for an evaluator bump render its shared pass's
// (the methods that MethodBatches renders together).
std::string local_group_key(const Job& job) {
  std::string key = render_group_key(job);
  if (!key.empty() || job.representation != Representation::kBump) return key;
  return shared_pass_key(job);
}
Order group_by_mesh(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo) {
  std::vector<std::string> keys(todo.size());
  std::map<std::string, std::vector<std::size_t>> groups;
  for (std::size_t k = 0; k < todo.size(); ++k) {
    keys[k] = local_group_key(jobs[todo[k]]);
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
    if (blender) {
      std::map<std::size_t, std::string> terminator;  // each member's, as text
      for (std::size_t m : members) terminator[m] = jobs[m].scene_json()["terminator"].dump();
      std::stable_sort(members.begin(), members.end(),
                       [&](std::size_t a, std::size_t b) { return terminator[a] < terminator[b]; });
    }
    for (std::size_t m = 0; m < members.size(); ++m) add(members[m], m == 0);
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

// The render phase of one round: the cache, then what it lacks through the
// executor; counts what never started.
Renders render_jobs(const std::string& study_file, const std::vector<Job>& jobs,
                    const RenderCache& cache, const Renderers& renderers, Executor& executor,
                    const StudyOptions& options, StudyRunStats& stats,
                    const ConvergenceRound* convergence = nullptr) {
  Renders r(jobs.size());
  const std::size_t cached_before = stats.cached;
  const Order order = group_by_mesh(jobs, use_cache(jobs, cache, options, r, stats));
  // The cache must hold what is to be rendered (uncompressed EXR sizes).
  ResourceEstimate needed;
  for (std::size_t i : order.todo) needed.output_bytes += jobs[i].resources.output_bytes;
  check_resources(needed, std::numeric_limits<double>::infinity(), study_file, cache.folder());
  executor.render({jobs, order.todo, order.group_starts, stats.cached - cached_before, cache,
                   renderers, convergence},
                  r, stats);
  settle_duplicates(jobs, r, stats);
  return r;
}

// The study folder's subfolders, cleared of what killed runs left.
// The folders a run makes in its output folder, each after its parent.
constexpr const char* kRunFolders[] = {"cache", "cache/sums", "images", "images/flip"};

void prepare_folders(const fs::path& out, const StudyOptions& options, StudyRunStats& stats) {
  for (const char* sub : kRunFolders) {
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

// A run refused before its first file (the free-space check, an input
// found bad late) leaves no empty folders behind, nor one it created.
void remove_empty_folders(const fs::path& out, bool out_existed) {
  std::error_code ec;
  for (auto sub = std::rbegin(kRunFolders); sub != std::rend(kRunFolders); ++sub)
    if (fs::is_empty(out / *sub, ec) && !ec) fs::remove(out / *sub, ec);
  // The lock file of a folder this run made (its lock is released by now).
  if (!out_existed) fs::remove(out / kFolderLockName, ec);
  if (!out_existed && fs::is_empty(out, ec) && !ec) fs::remove(out, ec);
}

// One run at a time in a folder: a second would render everything the first
// has not cached yet once more (docs/studies.md).
FolderLock lock_folder(const fs::path& out) {
  try {
    return FolderLock(out.string());
  } catch (const FolderLocked& e) {
    throw OutputError(fmt::format(
        "{}: another penumbra run is writing this folder ({}): wait for it to end, or choose "
        "another -o",
        out.string(), e.what()));
  } catch (const std::runtime_error& e) {
    throw OutputError(e.what());
  }
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The convergence phase: check renders go through the cache like any other.
// `independent`: the jobs that do not wait for the truths' settings (the
// external renderers', the sections'), which a submitting executor's first
// round carries, so that they render while the truths converge.
std::vector<VariantConvergence> converge(const Study& study, Plan& plan,
                                         const std::vector<Job>& independent,
                                         const RenderCache& cache, const StudyOptions& options,
                                         const Renderers& renderers, Executor& executor,
                                         StudyRunStats& stats) {
  bool carry = executor.submits();
  const RenderBatch batch = [&](const std::vector<Job>& jobs, const std::vector<ChainState>& chains,
                                std::vector<std::string>* errors) {
    std::vector<Job> keyed = jobs;
    assign_keys(keyed, renderers.identities);
    const std::size_t checks = keyed.size();
    if (options.log)
      options.log(fmt::format("ground truth: checking convergence ({} renders)", checks));
    std::vector<char> lacking(checks);
    for (std::size_t i = 0; i < checks; ++i) lacking[i] = !cache.contains(keyed[i].key);
    // Only with a round that must be submitted anyway: a run submits once.
    const bool submits = std::find(lacking.begin(), lacking.end(), 1) != lacking.end();
    if (submits && std::exchange(carry, false))
      keyed.insert(keyed.end(), independent.begin(), independent.end());
    StudyRunStats carried;  // the carried jobs are counted in the main phase
    const ConvergenceRound round{plan, study.ground_truth, options.max_memory_bytes, chains,
                                 lacking};
    const Renders r = render_jobs(study.file, keyed, cache, renderers, executor, options,
                                  keyed.size() == checks ? stats : carried, &round);
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

// The jobs that do not wait for the truths' settings: the external
// renderers' (the evaluator's take the settings reached) and the sections'.
std::vector<Job> independent_jobs(const Plan& plan, const std::vector<Job>& section_jobs) {
  std::vector<Job> out;
  for (const Job& j : plan.jobs)
    if (j.renderer != RendererKind::kEvaluator) out.push_back(j);
  out.insert(out.end(), section_jobs.begin(), section_jobs.end());
  return out;
}

// The sections' part of the render phase, the jobs from `first` on, moved
// out of `r`, which keeps the plan's.
SectionRenders take_section_renders(Renders& r, std::size_t first) {
  const auto from = [&](auto& v) {
    using Vector = std::decay_t<decltype(v)>;
    Vector tail(std::make_move_iterator(v.begin() + static_cast<long>(first)),
                std::make_move_iterator(v.end()));
    v.resize(first);
    return tail;
  };
  SectionRenders out;
  out.images = from(r.images.images);
  out.done = from(r.images.done);
  out.cached = from(r.cached);
  out.errors = from(r.errors);
  r.attempted.resize(first);
  r.same_as.resize(first);
  return out;
}

void draw_figures(const fs::path& out, const StudyOptions& options, StudyRunStats& stats) {
  if (options.log)
    options.log(
        fmt::format("figures: drawing the figures and report.html (harness/report.py, log {}) ...",
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

// What a run has once every render is accounted for.
struct Rendered {
  const Plan& plan;
  const std::vector<VariantConvergence>& convergence;
  Renders& renders;  // the plan's jobs, then the sections'
  const std::optional<InterplayJobs>& interplay;
};

// penumbra fit into <out>/fit, unless the last fit's stamp says report.json
// (less its provenance), the evaluator's code and Penumbra's version are
// unchanged. A study without an evaluator raw-bump variant and its truth has
// nothing to fit: said, not an error.
void fit_study_folder(const fs::path& out, const StudyOptions& options, StudyRunStats& stats) {
  const auto log = [&](const std::string& line) {
    if (options.log) options.log("fit: " + line);
  };
  const std::string digest = fit_inputs_digest(out);
  if (fit_is_current(out / "fit", digest)) {
    log("report.json and the evaluator are unchanged: kept fit/ of the last run");
    return;
  }
  const auto start = std::chrono::steady_clock::now();
  FitOptions fit;
  fit.folder = out.string();
  fit.jobs = options.parallelism.threads();
  fit.progress = [&](const std::string& line) { log(line); };
  FitResult result;
  try {
    result = fit_study(fit);
  } catch (const InputError& e) {
    // A fit of an earlier report.json would be read as this one's.
    for (const char* file : {"fit.json", "fit.csv", "table.json", ".inputs"})
      fs::remove(out / "fit" / file);
    log(fmt::format("nothing to fit ({})", e.what()));
    return;
  }
  if (!std::isfinite(result.study_floor.floor.value)) {
    log("nothing to fit: no variant has raw-bump light in the terminator region's bins");
    return;
  }
  write_fit(result, out / "fit");
  write_fit_stamp(out / "fit", digest);
  stats.fit_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  log(
      fmt::format("floor {:.2f} % [{:.2f}, {:.2f}] of albedo*E/pi against raw bump's {:.2f} % "
                  "over {} variants ({} left out: their truth did not converge), fit/fit.json in "
                  "{:.1f} s",
                  100 * result.study_floor.floor.value, 100 * result.study_floor.floor.interval.low,
                  100 * result.study_floor.floor.interval.high, 100 * result.study_floor.none.value,
                  result.variants.size(), result.unconverged.size(), stats.fit_s));
}

// The steps after the render phase: the comparisons, the sections' steps,
// the report files, the fit and the figures.
void report_study(const Study& study, const Rendered& in, const StepContext& context,
                  const StudyOptions& options, StudyRunStats& stats) {
  const fs::path out(context.out_dir);
  const SectionRenders sections = take_section_renders(in.renders, in.plan.jobs.size());
  const Comparisons comparisons = compare_renders(in.plan, in.renders.images, out, options, stats);
  const std::vector<FilteringEntry> filtering =
      study.filtering ? run_filtering_section(*study.filtering, context)
                      : std::vector<FilteringEntry>{};
  std::optional<InterplayResult> interplay;
  if (in.interplay)
    interplay = measure_interplay_section(*study.interplay, *in.interplay, sections, context);
  write_report_files(
      {study, in.plan, comparisons, context.renderers.versions, in.renders.errors,
       in.renders.images.done, in.convergence, filtering, interplay ? &*interplay : nullptr},
      out.string());
  if (options.fit) fit_study_folder(out, options, stats);
  if (!options.figures) return;
  const auto figures_start = std::chrono::steady_clock::now();
  try {
    draw_figures(out, options, stats);
    stats.figures_s = seconds_since(figures_start);
  } catch (const RenderCancelled&) {
    remove_report_files(out.string());
    throw;
  }
}

// run_study once its folders exist: the sections, the renders and the report.
StudyRunStats run_prepared(const Study& study, Plan& plan, Renderers& renderers, Executor& executor,
                           const StudyOptions& options, StudyRunStats& stats,
                           std::chrono::steady_clock::time_point start) {
  const fs::path out(options.output_dir);
  const RenderCache cache((out / "cache").string());
  auto blender_sessions = std::make_unique<BlenderSessions>((out / "cache").string());
  renderers.blender_sessions = blender_sessions.get();
  const StepContext context{out.string(), cache, renderers, options.parallelism, options.log};
  // The sections' renders join the plan's (study/sections.h).
  std::optional<InterplayJobs> interplay;
  if (study.interplay) interplay = plan_interplay_section(*study.interplay, context);
  const std::vector<Job> section_jobs = interplay ? interplay->jobs : std::vector<Job>{};
  stats.renders += section_jobs.size();
  const std::vector<VariantConvergence> convergence =
      converge(study, plan, independent_jobs(plan, section_jobs), cache, options, renderers,
               executor, stats);
  if (stats.not_started > 0) {  // interrupted while checking the truths
    stats.seconds = seconds_since(start);
    return stats;
  }
  std::vector<Job> jobs = plan.jobs;
  jobs.insert(jobs.end(), section_jobs.begin(), section_jobs.end());
  Renders r = render_jobs(study.file, jobs, cache, renderers, executor, options, stats);
  stats.blender_processes = blender_sessions->started();
  blender_sessions.reset();  // the processes end here, not after the figures
  renderers.blender_sessions = nullptr;
  stats.seconds = stats.render_phase_s = seconds_since(start);
  if (stats.not_started > 0) return stats;  // interrupted: no report from a partial study

  report_study(study, {plan, convergence, r, interplay}, context, options, stats);
  stats.seconds = seconds_since(start);
  return stats;
}

}  // namespace

namespace {

// The process's mesh cache for a run: a quarter of its memory budget, in
// the meshes' measured bytes per triangle (never below the default), so that
// the displaced meshes of one round of convergence checks are still there
// when the next round (in the reverse order, converge_truths) asks for them.
class MeshCacheForRun {
 public:
  explicit MeshCacheForRun(double max_memory_bytes) : before_(mesh_cache_triangles()) {
    const double triangles = max_memory_bytes / 4.0 / kMeshBytesPerTriangle;
    set_mesh_cache_triangles(std::max(kMeshCacheTriangles, static_cast<std::size_t>(triangles)));
  }
  ~MeshCacheForRun() { set_mesh_cache_triangles(before_); }
  MeshCacheForRun(const MeshCacheForRun&) = delete;
  MeshCacheForRun& operator=(const MeshCacheForRun&) = delete;

 private:
  std::size_t before_;
};

}  // namespace

StudyRunStats run_study(const Study& study, const StudyOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const MeshCacheForRun mesh_cache(options.max_memory_bytes);
  const fs::path out(options.output_dir);
  const std::unique_ptr<Executor> executor = make_executor(options);
  Renderers renderers = probe_renderers(study_renderers(study), options.timeout_s,
                                        options.dry_run ? "" : executor->probe_cache(out.string()));
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
    count_planned(plan, cache, checks, options.parallelism.threads(), stats);
    return stats;
  }
  const bool out_existed = fs::exists(out);
  prepare_folders(out, options, stats);
  try {
    const FolderLock lock = lock_folder(out);
    return run_prepared(study, plan, renderers, *executor, options, stats, start);
  } catch (...) {
    remove_empty_folders(out, out_existed);
    throw;
  }
}

}  // namespace penumbra
