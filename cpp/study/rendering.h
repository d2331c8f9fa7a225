// Rendering one planned job into the cache: what both executors (local
// threads and Slurm array tasks) do for each render.
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "image/image.h"
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

// Renders `job` with `threads` threads and writes it into the cache; returns
// the image. Throws RendererError (or ExportError), TaskCancelled when
// interrupted.
Image render_into_cache(const Job& job, const RenderCache& cache, double timeout_s, int threads,
                        const Renderers& renderers);

}  // namespace penumbra
