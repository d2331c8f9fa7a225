// What a study will cost before it runs, for `penumbra run --dry-run`: the
// renders in core-seconds (cores x wall time, which is what Slurm bills),
// the ground truths' convergence checks, the comparisons and figures, and the
// wall time on the cores this run would use.
//
// A render's cost is a fixed part (starting the renderer, reading the scene,
// writing the EXR) plus parts proportional to its pixel samples and to the
// triangles of the mesh it builds (RenderCostModel, renderers/renderer.h).
// Each renderer's entry holds these per kind of render, measured on a 2-core
// machine (cost.cpp says how); a kind the study's own cache already holds
// renders of is priced from those instead (every cache entry records its
// wall time and thread count). The convergence checks are priced from the
// first round the dry run can see, times the ratio of all rounds to the
// first measured on the shipped studies.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "renderers/registry.h"
#include "scene/scene.h"

namespace penumbra {

struct Plan;
struct Job;
class RenderCache;

// Cache-entry attributes that carry a render's cost.
inline constexpr const char* kCostWallAttribute = "penumbra:wall_seconds";
inline constexpr const char* kCostThreadsAttribute = "penumbra:threads";

// The built-in model of a kind of render (its renderer's entry,
// RendererEntry::costs), if the entry has one.
std::optional<RenderCostModel> built_in_cost(RendererKind renderer, Representation representation,
                                             bool tessellated);

struct CostLine {
  RendererKind renderer = RendererKind::kEvaluator;
  Representation representation = Representation::kBump;
  bool tessellated = false;   // a low-poly mesh (smooth shading on facets)
  std::size_t renders = 0;    // to render
  double core_seconds = 0.0;  // estimated, for those renders
  // Cached renders of this kind the sample rate comes from (at most 64 are
  // read); 0: the built-in model.
  std::size_t measured = 0;
  RenderCostModel model;  // the model used (per_msample from the cache where measured)
  // Measured lines: the cost at the slowest and the fastest rate of the
  // cached renders read (their full range, not a confidence interval);
  // built-in lines: both 0, no spread known.
  double core_seconds_low = 0.0, core_seconds_high = 0.0;
};

struct CostEstimate {
  std::vector<CostLine> lines;  // one per kind with renders to do, in table order
  double core_seconds = 0.0;    // the planned renders
  // The ground truths' convergence checks: the first round the dry run sees,
  // and all rounds (kCheckRoundsRatio times the first).
  std::size_t first_checks = 0;
  double first_checks_core_seconds = 0.0;
  double checks_core_seconds = 0.0;
  // Comparing every render with its truths and drawing the figures, wall
  // seconds on 2 cores.
  std::size_t comparisons = 0;
  double report_seconds = 0.0;
  // Renders, checks and report on `cores` cores.
  int cores = 1;
  double wall_seconds = 0.0;
};

// All rounds of convergence checks over the first round's cost: 2.1 on the
// default study and 1.5 on the smoke study (cold runs, cache headers).
inline constexpr double kCheckRoundsRatio = 2.0;

// `to_render[i]` marks plan.jobs[i] as not in the cache; `first_checks` are
// the convergence checks of the first round that are not cached; `cores`
// the cores the run would use (--jobs x threads per render).
CostEstimate estimate_cost(const Plan& plan, const RenderCache& cache,
                           const std::vector<char>& to_render,
                           const std::vector<Job>& first_checks = {}, int cores = 1);

}  // namespace penumbra
