#include "study/rendering.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <future>
#include <mutex>
#include <set>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "image/image_io.h"
#include "scene/scene_json.h"
#include "study/cost.h"
#include "study/execute.h"
#include "util/files.h"
#include "util/process.h"
#include "util/strict_json.h"
#include "util/version.h"

namespace penumbra {
namespace fs = std::filesystem;

std::vector<RendererKind> study_renderers(const Study& study) {
  std::vector<RendererKind> kinds = study.bump.renderers;
  if (study.lowpoly)
    for (RendererKind r : study.lowpoly->renderers)
      if (std::find(kinds.begin(), kinds.end(), r) == kinds.end()) kinds.push_back(r);
  return kinds;
}

namespace {

// renderer_version, remembered in `probe_cache` by the executable's path,
// size and modification time (a changed executable is probed again).
std::string cached_version(RendererKind r, const RenderSettings& settings,
                           const std::string& probe_cache) {
  const std::string exe = renderer_executable(r, settings);
  if (probe_cache.empty() || exe.empty()) return renderer_version(r, settings);
  std::error_code ec;
  const auto size = fs::file_size(exe, ec);
  const auto mtime = fs::last_write_time(exe, ec).time_since_epoch().count();
  if (ec) return renderer_version(r, settings);
  const std::string id = fmt::format("{}|{}|{}", exe, size, mtime);
  nlohmann::json known = nlohmann::json::object();
  try {
    if (fs::exists(probe_cache)) known = read_json_file(probe_cache);
  } catch (const InputError&) {  // half-written by a killed process: probe again
  }
  if (known.is_object() && known.contains(id) && known[id].is_string()) return known[id];
  const std::string version = renderer_version(r, settings);
  if (!known.is_object()) known = nlohmann::json::object();
  known[id] = version;
  fs::create_directories(fs::path(probe_cache).parent_path(), ec);
  write_text_file(probe_cache, known.dump(1) + "\n");
  return version;
}

}  // namespace

Renderers probe_renderers(const std::vector<RendererKind>& kinds, double timeout_s,
                          const std::string& probe_cache) {
  Renderers out;
  for (RendererKind r : kinds) {
    RenderSettings probe;
    probe.timeout_s = timeout_s;
    RendererIdentity id;
    try {
      id.version = out.versions[r] = cached_version(r, probe, probe_cache);
      id.code_digest = pixel_code_digest(r, probe);
    } catch (const std::exception& e) {
      out.versions.erase(r);
      out.unavailable[r] = e.what();
    }
    out.identities.push_back({r, id});
  }
  return out;
}

namespace {

// Whether a render keeps its per-pixel sums for a check at 4^k times its
// samples to extend: evaluator displacement truths that draw no random
// numbers while shading, seen by a jittered camera (RenderOptions::resume).
bool keeps_sums(const Job& job, const Scene& scene) {
  return job.renderer == RendererKind::kEvaluator &&
         job.representation == Representation::kDisplacement && shares_samples(scene.terminator) &&
         scene.camera.jitter;
}

// The sample counts whose sums a render of `spp` samples can extend, the
// most first (core/sample_pattern.h, nests).
std::vector<int> nested_counts(int spp) {
  std::vector<int> out;
  for (int n = spp; nests_quarter(n); n /= 4) out.push_back(n / 4);
  return out;
}

// The cached sums of every one of `keys` at the most samples below `spp`
// that all of them have; empty when there are none.
std::vector<SampleSums> resumable_sums(const RenderCache& cache,
                                       const std::vector<std::string>& keys, int spp) {
  for (int fewer : nested_counts(spp)) {
    std::vector<SampleSums> found;
    for (const std::string& key : keys) {
      std::optional<SampleSums> sums = cache.lookup_sums(key, fewer);
      if (!sums) break;
      found.push_back(std::move(*sums));
    }
    if (found.size() == keys.size()) return found;
  }
  return {};
}

// The renders of `scenes` (the jobs `jobs`) by `render_pass`, extending the
// cached sums of their scenes where they keep them, and keeping theirs
// (each where errors(k) is empty).
template <typename Render>
auto render_keeping_sums(const std::vector<const Job*>& jobs, const std::vector<Scene>& scenes,
                         RenderSettings settings, const RenderCache& cache,
                         const Renderers& renderers, Render&& render_pass) {
  std::vector<std::string> keys;
  for (std::size_t k = 0; k < jobs.size(); ++k)
    if (keeps_sums(*jobs[k], scenes[k]))
      keys.push_back(samples_key(*jobs[k], renderers.identities));
  if (keys.size() != jobs.size()) return render_pass(settings, [](std::size_t) { return false; });
  const std::vector<SampleSums> resume = resumable_sums(cache, keys, scenes.front().camera.spp);
  std::vector<SampleSums> sums;
  if (!resume.empty()) settings.progress.resume = &resume;
  settings.progress.sums = &sums;
  return render_pass(settings, [&](std::size_t k) {
    cache.store_sums(keys[k], sums[k]);
    return true;
  });
}

}  // namespace

std::string shared_pass_key(const Job& job) {
  if (job.renderer != RendererKind::kEvaluator) return {};
  const bool bump = job.representation == Representation::kBump;
  if (!bump && job.representation != Representation::kDisplacement) return {};
  nlohmann::json scene = job.scene_json();
  for (const char* part : bump ? std::vector<const char*>{"terminator"}
                               : std::vector<const char*>{"light", "material", "terminator"})
    scene.erase(part);
  return (bump ? "methods:" : "lightings:") + scene.dump();
}

struct MethodBatches::Batch {
  std::vector<std::size_t> jobs;  // indices into jobs_
  bool lightings = false;         // displacement truths of one geometry (else methods)
  std::mutex mutex;
  bool started = false;
  std::shared_future<MethodsRun> run;  // reset once every slot took its image
  std::vector<char> taken;             // per slot
};

MethodBatches::MethodBatches(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo,
                             bool truths)
    : jobs_(jobs) {
  // Bump renders by their scene without its terminator; displacement
  // truths by theirs without the light, the material and the terminator,
  // which each truth of the pass keeps (render_lightings).
  std::map<std::string, std::vector<std::size_t>> groups;
  std::set<std::string> keys;
  for (std::size_t i : todo) {
    const Job& job = jobs[i];
    std::string key = shared_pass_key(job);
    if (key.empty() || (!truths && job.representation == Representation::kDisplacement) ||
        !shares_samples(job.scene().terminator) || !keys.insert(job.key).second)
      continue;
    groups[std::move(key)].push_back(i);
  }
  for (auto& [scene, members] : groups) {
    if (members.size() < 2) continue;
    auto batch = std::make_unique<Batch>();
    batch->jobs = members;
    batch->lightings = scene.starts_with("lightings:");
    (batch->lightings ? truth_members_ : method_members_) += members.size();
    ++(batch->lightings ? truth_batches_ : method_batches_);
    batch->taken.assign(members.size(), 0);
    for (std::size_t slot = 0; slot < members.size(); ++slot)
      member_[jobs[members[slot]].key] = {batches_.size(), slot};
    batches_.push_back(std::move(batch));
  }
}

MethodBatches::~MethodBatches() = default;

MethodsRun MethodBatches::render_batch(const Batch& batch, const RenderSettings& settings,
                                       const RenderCache& cache, const Renderers& renderers) const {
  if (batch.lightings) {
    std::vector<Scene> scenes;
    std::vector<const Job*> members;
    for (std::size_t i : batch.jobs) {
      scenes.push_back(jobs_[i].scene());
      members.push_back(&jobs_[i]);
    }
    return render_keeping_sums(members, scenes, settings, cache, renderers,
                               [&](const RenderSettings& s, auto&& keep) {
                                 MethodsRun run = render_evaluator_lightings(scenes, s);
                                 for (std::size_t k = 0; k < scenes.size(); ++k)
                                   if (run.errors[k].empty()) keep(k);
                                 return run;
                               });
  }
  std::vector<TerminatorSettings> methods;
  for (std::size_t i : batch.jobs) methods.push_back(jobs_[i].scene().terminator);
  return render_evaluator_methods(jobs_[batch.jobs.front()].scene(), methods, settings);
}

std::optional<RendererRun> MethodBatches::take(const Job& job, const RenderSettings& settings,
                                               const RenderCache& cache,
                                               const Renderers& renderers) {
  const auto found = member_.find(job.key);
  if (found == member_.end()) return std::nullopt;
  Batch& batch = *batches_[found->second.first];
  const std::size_t slot = found->second.second;
  std::promise<MethodsRun> promise;
  bool owner = false;
  std::shared_future<MethodsRun> run;
  {
    const std::lock_guard<std::mutex> lock(batch.mutex);
    if (!batch.started) {
      batch.started = owner = true;
      batch.run = promise.get_future().share();
    }
    // A job asked again after the pass was freed renders alone (same bits).
    if (!batch.run.valid()) return std::nullopt;
    run = batch.run;
  }
  if (owner) {
    try {
      promise.set_value(render_batch(batch, settings, cache, renderers));
    } catch (...) {
      promise.set_exception(std::current_exception());
    }
  }
  const MethodsRun& pass = run.get();  // rethrows the pass's error
  if (!pass.errors[slot].empty()) throw RendererError(pass.errors[slot]);
  RendererRun out;
  out.image = pass.images[slot];
  out.seconds = pass.seconds / double(batch.jobs.size());
  // The pass's mesh is recorded as built by its first member, as reused by
  // the others (their cache entries' penumbra:mesh_build_seconds).
  out.stats = pass.stats;
  out.stats.mesh_reused = pass.stats.mesh_reused || slot != 0;
  {
    // The last member frees the pass's images.
    const std::lock_guard<std::mutex> lock(batch.mutex);
    batch.taken[slot] = 1;
    if (std::all_of(batch.taken.begin(), batch.taken.end(), [](char t) { return t != 0; }))
      batch.run = {};
  }
  return out;
}

Image render_into_cache(const Job& job, const RenderCache& cache, double timeout_s, int threads,
                        const Renderers& renderers, MethodBatches* batches, double* core_seconds) {
  if (const auto missing = renderers.unavailable.find(job.renderer);
      missing != renderers.unavailable.end())
    throw RendererError(missing->second);
  RenderSettings settings;
  settings.timeout_s = timeout_s;
  settings.threads = threads;
  settings.log_path = cache.log_path(job.key);
  settings.blender_sessions = renderers.blender_sessions;
  // A stop signal (util/process.h) ends the evaluator's render too, not only
  // external processes: an interrupted task must not go on to cache it.
  settings.progress.progress = [](double) {
    if (processes_cancelled()) throw RenderCancelled("interrupted");
  };
  std::error_code ignored;
  fs::remove(settings.log_path, ignored);
  RendererRun run;
  const auto start = std::chrono::steady_clock::now();
  std::optional<RendererRun> shared;
  try {
    shared = batches ? batches->take(job, settings, cache, renderers) : std::nullopt;
    if (shared) {
      run = std::move(*shared);
    } else {
      const Scene scene = job.scene();
      run = render_keeping_sums({&job}, {scene}, settings, cache, renderers,
                                [&](const RenderSettings& s, auto&& keep) {
                                  RendererRun alone = render_with(job.renderer, scene, s);
                                  keep(0);
                                  return alone;
                                });
    }
  } catch (const RenderCancelled&) {
    throw TaskCancelled{};
  }
  // A batch member's cost is its share of the pass (for the cost estimates),
  // on the worker's threads as a render alone counts them: the pass ran on
  // one worker while the others rendered too, so that wall times the
  // machine's cores would count the cores the others used twice.
  const double wall_seconds =
      shared ? run.seconds
             : std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const unsigned used_threads = threads > 0 ? static_cast<unsigned>(threads)
                                            : std::max(1u, std::thread::hardware_concurrency());
  if (core_seconds) *core_seconds = wall_seconds * used_threads;
  std::vector<std::pair<std::string, std::string>> attributes{
      {"penumbra:version", kPenumbraVersion},
      {kCostWallAttribute, fmt::format("{:.3f}", wall_seconds)},
      {kCostThreadsAttribute, std::to_string(used_threads)},
      {"penumbra:host", host_tag()},
      {"penumbra:renderer", to_string(job.renderer)},
      {"penumbra:renderer_version", renderers.versions.at(job.renderer)},
      {"penumbra:scene", job.scene_json().dump()},
      {"penumbra:method", job.method},
      {"penumbra:representation", to_string(job.representation)},
      {"penumbra:radiance_unit", "W m^-2 sr^-1"}};
  // What a truth's cost is made of: the mesh build, or none when the
  // process's mesh cache held it (evaluator/displaced_mesh.h). An external
  // renderer's stats are its geometry pass's, not its cost.
  const bool external = renderer_info(job.renderer).external();
  if (!external && run.stats.triangles > 0) {
    attributes.emplace_back(
        "penumbra:mesh_build_seconds",
        fmt::format("{:.3f}", run.stats.mesh_reused ? 0.0 : run.stats.build_seconds));
    attributes.emplace_back("penumbra:mesh_triangles", std::to_string(run.stats.triangles));
  }
  // A truth that extended the sums of fewer samples: how many it took.
  if (!external && run.stats.resumed_spp > 0)
    attributes.emplace_back("penumbra:resumed_spp", std::to_string(run.stats.resumed_spp));
  cache.store(job.key, run.image, attributes);
  if (!external) fs::remove(settings.log_path, ignored);  // only a process writes a log
  return std::move(run.image);
}

}  // namespace penumbra
