// Rendering one planned job into the cache: what both executors (local
// threads and Slurm array tasks) do for each render.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "image/image.h"
#include "renderers/external/blender/blender_sessions.h"
#include "renderers/renderers.h"
#include "study/cache.h"
#include "study/plan.h"

namespace penumbra {

// What the renderers are: versions (a missing renderer fails its renders,
// not the study) and the digests of the code behind their pixels.
struct Renderers {
  std::map<RendererKind, std::string> versions, unavailable;
  std::vector<std::pair<RendererKind, RendererIdentity>> identities;
  BlenderSessions* blender_sessions = nullptr;  // the run's serving Blender processes
};

// The renderers a study uses (bump section, then low-poly), each once.
std::vector<RendererKind> study_renderers(const Study& study);
// `probe_cache` (optional): a JSON file of versions already probed, by
// executable path, size and modification time, so that many short processes
// on one node (Slurm array tasks) start a renderer for --version only once.
Renderers probe_renderers(const std::vector<RendererKind>& kinds, double timeout_s,
                          const std::string& probe_cache = "");

// What a job's shared pass is keyed by: an evaluator bump render's scene
// without its terminator ("methods:", its variant's methods), an evaluator
// displacement truth's without its light, material and terminator
// ("lightings:", the truths on one mesh); empty for any other render.
std::string shared_pass_key(const Job& job);

// Evaluator bump renders of one variant that differ only in their method
// share their samples, and so do the displacement truths (and their
// convergence checks) of variants that differ only in their light,
// material and terminator: the first of them to start renders them all in one pass
// (render_evaluator_methods, render_evaluator_lightings), with every core;
// the others wait for it and take their image. Each is still its own job:
// cached under its own key, counted, failed or cancelled alone. The images
// have the bits of separate renders (tested), so cache keys do not change.
// A truths' pass holds one displaced mesh, as each of its members alone
// would, so it needs no more memory than its largest member. Thread-safe.
class MethodBatches {
 public:
  // Batches of two or more among `jobs[todo]`; the truths' only with `truths`.
  MethodBatches(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo,
                bool truths = true);
  ~MethodBatches();

  // The run of `job` when it is in a batch (its share of the pass's wall
  // time in `seconds`); nullopt when it renders alone. Throws what the pass
  // threw, and RendererError when its image has NaN or Inf values.
  // A truths' pass extends and keeps its truths' sums in `cache` as a truth
  // rendered alone does (render_into_cache).
  std::optional<RendererRun> take(const Job& job, const RenderSettings& settings,
                                  const RenderCache& cache, const Renderers& renderers);

  // Passes over the methods of one variant, and the renders they hold.
  std::size_t batches() const { return method_batches_; }
  std::size_t members() const { return method_members_; }
  // Passes over the truths of one geometry, and the renders they hold.
  std::size_t truth_batches() const { return truth_batches_; }
  std::size_t truth_members() const { return truth_members_; }

 private:
  struct Batch;
  MethodsRun render_batch(const Batch& batch, const RenderSettings& settings,
                          const RenderCache& cache, const Renderers& renderers) const;
  std::size_t method_batches_ = 0, method_members_ = 0, truth_batches_ = 0, truth_members_ = 0;
  const std::vector<Job>& jobs_;
  std::map<std::string, std::pair<std::size_t, std::size_t>> member_;  // key -> batch, slot
  std::vector<std::unique_ptr<Batch>> batches_;
};

// Renders `job` with `threads` threads and writes it into the cache; returns
// the image. An evaluator displacement truth extends the cached sums of its
// scene at a quarter (or 4^-k) of its samples where the cache holds them,
// with the bits of a render from scratch, and keeps its own sums there
// (RenderCache::store_sums, issue 45). Throws RendererError (or ExportError), TaskCancelled when
// interrupted. With `batches`, a job in a batch takes its image from the
// batch's shared pass. `core_seconds`, when given, receives the render's cost
// as its cache entry records it: wall seconds times threads (a batch
// member: its share of the pass).
Image render_into_cache(const Job& job, const RenderCache& cache, double timeout_s, int threads,
                        const Renderers& renderers, MethodBatches* batches = nullptr,
                        double* core_seconds = nullptr);

}  // namespace penumbra
