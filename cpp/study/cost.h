// What the renders of a plan will cost, in core-hours (cores allocated x
// wall time, which is what Slurm bills), for `penumbra run --dry-run`.
// Every cache entry records its wall time and thread count; a plan's
// uncached renders are priced from the cached renders of the same renderer
// and representation, scaled by pixel samples, or from built-in rates
// measured on a 2-core machine when the cache has none.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "scene/renderer_table.h"
#include "scene/scene.h"

namespace penumbra {

struct Plan;
class RenderCache;

// Cache-entry attributes that carry a render's cost.
inline constexpr const char* kCostWallAttribute = "penumbra:wall_seconds";
inline constexpr const char* kCostThreadsAttribute = "penumbra:threads";

struct CostLine {
  RendererKind renderer = RendererKind::kEvaluator;
  Representation representation = Representation::kBump;
  bool tessellated = false;   // a low-poly mesh (smooth shading on facets)
  std::size_t renders = 0;    // to render
  double core_seconds = 0.0;  // estimated, for those renders
  // Cached renders of this kind the rate comes from (at most 64 are read);
  // 0: the built-in rate.
  std::size_t measured = 0;
  double core_seconds_per_msample = 0.0;  // the rate used (per 10^6 pixel samples)
  // Measured lines: the cost at the slowest and the fastest rate of the
  // cached renders read (their full range, not a confidence interval);
  // built-in lines: both 0, no spread known.
  double core_seconds_low = 0.0, core_seconds_high = 0.0;
};

struct CostEstimate {
  std::vector<CostLine> lines;  // one per kind with renders to do, in table order
  double core_seconds = 0.0;
};

// The built-in rate of a kind of render (core-seconds per 10^6 pixel
// samples), if the table has one.
std::optional<double> built_in_rate(RendererKind renderer, Representation representation,
                                    bool tessellated);

// `to_render[i]` marks plan.jobs[i] as not in the cache.
CostEstimate estimate_cost(const Plan& plan, const RenderCache& cache,
                           const std::vector<char>& to_render);

}  // namespace penumbra
