// The bump-filtering experiment of the Ray Tracing Gems chapter (Fig. 12-6)
// and Schilling's Figs. 8-11, measured on a bump-mapped plane: a GGX mirror-
// like material (Fresnel 1, no diffuse) whose bump map is seen at 2^l
// texels per pixel. A pixel footprint is a square of 2^l finest texels a
// side: one texel of pyramid level l, or that square shifted by a fraction
// of a pixel.
//
// Reference: the unfiltered, fully supersampled footprint: the radiance
// averaged over every finest texel it covers, each shaded with its own
// bumped normal and the base GGX lobe (exact for a plane under a distant
// light and an orthographic view: nothing varies within a texel but the
// normal, and a plane casts no shadows on itself). Filtered: one shading
// point with the level's mean normal and the lobe the filter makes from the
// level's roughness. Each footprint is lit from a sweep of light directions
// in two planes (x-z and y-z) and seen from a fixed view; the radiance over
// the sweep is the footprint's highlight profile. Per footprint:
//   energy ratio:  sum of the filtered profile / the reference's;
//   width ratio:   interquartile width (degrees of light angle holding the
//                  middle half of the profile's energy), filtered / reference,
//                  geometric mean of the two planes;
//   profile error: ||filtered - reference||_2 / ||reference||_2.
// Each is reported as its mean over the sampled footprints with a 95 %
// percentile bootstrap interval; the chapter's claim (sigma^2 = 2 alpha^2
// beats sigma^2 = alpha^2) is tested per cell as a paired comparison of
// profile errors over the same footprints.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "analysis/statistics.h"
#include "core/bump_pyramid.h"
#include "core/roughness_filter.h"

namespace penumbra {

struct FilteringOptions {
  std::vector<double> alphas = {0.01, 0.05, 0.1, 0.2, 0.4, 0.8};  // base GGX alpha
  int max_level = 6;                     // 2^6 = 64 texels per pixel side, capped by the map
  std::vector<RoughnessFilter> filters;  // empty: every filter with a BRDF
  double view_deg = 0.0;                 // view zenith angle, tilted towards +x
  double sweep_max_deg = 80.0;           // light zenith range [-max, max]
  double sweep_step_deg = 0.5;
  int footprints = 32;  // sampled per level (all texels when fewer)
  // The pixel grid's offset from the texel grid, in pixels (both axes),
  // [0, 1): 0 aligns each footprint with a texel of its level; otherwise
  // the reference covers the shifted square (partial texels by area).
  double shift = 0.0;
  // Instead, each footprint's own shift, uniform in [0, 1)^2 from `seed`:
  // the average over where a pixel can fall on the texel grid.
  bool random_shift = false;
  // What the filters read: kBox, the exact moments of the footprint's
  // square (the mapping's own error, whatever the shift); kTrilinear, the
  // pyramid's trilinear lookup at its centre (sample_pyramid: what a
  // renderer with mip maps reads; adds the lookup kernel's error, which
  // depends on where the footprint falls on the texel grid).
  enum class Lookup { kBox, kTrilinear } lookup = Lookup::kBox;
  std::uint64_t seed = 1;
  int jobs = 1;
};

struct MeanWithInterval {
  double mean = 0.0;
  Interval interval;  // 95 % bootstrap of the mean over footprints
  std::size_t n = 0;  // footprints where the quantity is defined
};

struct FilteringCell {
  RoughnessFilter filter;
  double alpha = 0.0;
  int level = 0;
  MeanWithInterval energy_ratio, width_ratio, profile_error;
};

// ggx-variance-estevez2019 (a) against beckmann-variance (b) on profile
// error over one cell's footprints (negative mean difference: a is better).
struct ClaimCell {
  double alpha = 0.0;
  int level = 0;
  PairedComparison comparison;
};

// One filter over every footprint of levels >= 1: each footprint's metric
// averaged over the base roughnesses, then the mean over footprints.
struct FilterSummary {
  RoughnessFilter filter;
  MeanWithInterval energy_ratio, width_ratio, profile_error;
};

struct FilteringResult {
  std::vector<FilteringCell> cells;    // filter-major, then alpha, then level
  std::vector<ClaimCell> claim;        // levels >= 1
  std::vector<FilterSummary> summary;  // ascending mean profile error
  // The lowest-error filter against the runner-up on the same footprints
  // (negative: the first is better); n = 0 with fewer than two filters.
  PairedComparison best_against_runner_up;
  int levels = 0;  // measured: 0 .. levels - 1
  std::vector<RoughnessFilter> filters;
  std::size_t footprints = 0;  // measured, over every level
};

// Where the experiment's inputs came from, for the report files.
struct FilteringSource {
  std::string heights, channel;
  int width = 0, height = 0;
  double texel_size = 0.0, height_scale = 1.0;
  std::string edge;
};

// filtering.json: options, units, what each number is compared against,
// every cell with its interval, the claim test and the summary sentences.
std::string filtering_json(const FilteringResult& result, const FilteringOptions& options,
                           const FilteringSource& source);
// filtering.csv: one row per cell.
std::string filtering_csv(const FilteringResult& result);
// Sentences that state, from the numbers, which filter keeps the roughness
// best and whether the chapter's claim reproduces.
std::vector<std::string> filtering_findings(const FilteringResult& result);

// Whether a filter has a normalised BRDF to measure and render with (all but
// Schilling's Blinn-Phong, whose paper gives none).
bool is_measurable(RoughnessFilter filter);
// Filters that have a BRDF to measure (is_measurable), in table order.
std::vector<RoughnessFilter> measurable_filters();

// `progress` (may be empty) is called with (done, total) footprint-levels.
FilteringResult run_filtering_experiment(
    const std::vector<PyramidLevel>& pyramid, const FilteringOptions& options,
    const std::function<void(std::size_t, std::size_t)>& progress = {});

}  // namespace penumbra
