// What any terminator factor of given inputs could achieve: the floor of the
// terminator-profile error over all functions G on a grid of those inputs
// (core/factor_table.h), and the G that reaches it.
//
// A factor G multiplies raw bump's light at each shading point. Raw bump's
// render, tallied per terminator-profile bin and grid cell (the evaluator's
// tally, evaluator/evaluator.h), makes the profile of any G given at the
// cells' centres (multilinear between them) a linear function of those values:
//   P_b(G) = (r_b + sum_c t_bc G_c) / n_b
// with n_b the bin's pixels, r_b the light G does not scale (other lobes,
// points outside the grid), t_bc the light in cell c. The terminator RMSE
// against the truth's profile Q is then a least-squares residual, and its
// floor over G in [g_min, g_max] a bounded linear least-squares problem,
// solved here exactly (to a stated KKT residual): a projected-gradient
// start, then an active-set solve of the free cells (Eigen's LDLT).
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "analysis/metrics.h"
#include "core/factor_table.h"

namespace penumbra {

// Raw bump's light in one render, by profile bin (as terminator_profile
// bins pixels: fully covered, by their analysis.theta) and grid cell, in
// fractions of albedo*E/pi summed over the bin's pixels.
struct ProfileTally {
  double bin_degrees = 1.0;
  std::vector<std::uint64_t> count;  // pixels per bin
  std::vector<double> rest;          // per bin: light no G of the grid scales
  // Per bin: (cell, light in that cell), cells ascending, no repeats.
  std::vector<std::vector<std::pair<int, double>>> scaled;
  // The profile a factor table would give (the tally's grid; G = 1 is raw bump).
  Profile profile(const std::vector<double>& g) const;
};

// A render's pixel tally binned as terminator_profile bins its pixels (fully
// covered ones, by analysis.theta): tally.profile(all ones) is the render's
// own profile, to float rounding. `radiance_scale`: albedo*E/pi.
ProfileTally profile_tally(const Image& image, const PixelTally& tally, double radiance_scale,
                           const ProfileOptions& options = {});

// `t`, tallied on `from`, as on `to`: a grid whose axes are some of
// `from`'s, the others summed out. Every G of `to` is the G of `from` that
// is constant along the summed axes, so the profile of a G of `to` through
// this tally is that of its extension through `t`; a point outside `from`
// on a summed axis stays raw bump, as it does in `t`. std::invalid_argument
// where an axis of `to` is not one of `from`'s.
ProfileTally marginal_tally(const ProfileTally& t, const FactorGrid& from, const FactorGrid& to);

// One variant of a fit: its tally and its truth's profile.
struct TallyVariant {
  std::string id;
  ProfileTally tally;
  Profile truth;
};

// The terminator-region RMSE (analysis/metrics.h) of G on one variant,
// fraction of albedo*E/pi.
double tally_rmse(const TallyVariant& v, const std::vector<double>& g);

// Raw bump's light in one render by pixel, as the image metrics see it
// (compare_images: pixels fully covered in the render and its truth, both
// finite): row r's radiance under a factor G is sum_c light_rc G_c plus the
// light no G scales, so its error against the truth is that sum minus
// `target` (the truth less that light). Fractions of albedo*E/pi.
struct PixelRows {
  std::vector<double> target;
  std::vector<std::uint32_t> offsets{0};  // row r's entries: [offsets[r], offsets[r + 1])
  std::vector<int> cells;                 // ascending within a row, no repeats
  std::vector<double> light;
  std::size_t rows() const { return target.size(); }
};

// `render`'s tally (its size) against `truth`; `radiance_scale`: albedo*E/pi.
// std::invalid_argument where the sizes or channels do not match.
PixelRows pixel_rows(const Image& render, const Image& truth, const PixelTally& tally,
                     double radiance_scale, double min_coverage = 0.999);

// The image RMSE (ImageMetrics::rmse / radiance_scale) of G over the rows;
// NaN with no row.
double pixel_rmse(const PixelRows& rows, const std::vector<double>& g);

struct FloorOptions {
  double g_min = 0.0, g_max = 2.0;
  // Weight of the squared second differences of G along each grid axis (a
  // smoothness prior; 0: none), as a mean over them, relative to one
  // variant's mean squared error; and of (G - 1)^2 in the cells no variant
  // lights, which only the prior reaches (it fixes their linear trend).
  double smoothness = 0.0;
  double ridge = 1e-9;
  int max_iterations = 5000;
  // Above this many variables the solve works on a sparse h: profile bins
  // couple only cells of neighbouring light angles, a pixel only the cells
  // its samples reach, and the prior only neighbours, so a grid with a
  // third input keeps h about 1 % full, where a dense factorisation of its
  // thousands of cells takes a minute. A sparse solve without a prior (the
  // lit cells alone, whose system can be semidefinite) factors with a
  // vanishing proximal term; one with a prior iterates conjugate gradients,
  // since a complete factor of its every cell fills in. Up to this many, h
  // is dense. Both reach the same minimum within the solver's tolerance
  // (tested).
  int dense_variables = 1024;
};

struct FloorSolution {
  std::vector<double> g;             // per grid cell; 1 where no variant has light
  std::vector<char> constrained;     // cells some variant has light in
  std::vector<double> variant_rmse;  // per variant, at g
  double objective = 0.0;            // mean over variants of the squared RMSE at g (no prior)
  double kkt_residual = 0.0;         // largest violation of optimality, objective units
  int iterations = 0;
};

// The G on `grid` minimising the mean over `variants` of their squared
// terminator RMSE (plus the prior), with g_min <= G <= g_max.
FloorSolution solve_floor(const FactorGrid& grid, const std::vector<TallyVariant>& variants,
                          const FloorOptions& options = {});

// The G on `grid` minimising one render's image RMSE (pixel_rmse), with
// g_min <= G <= g_max: the per-variant floor of the image metric. Unlike
// the profile, the image is not binned by an input, so one variant's floor
// is not zero by construction: a pixel's samples mix light angles and
// deviations, and what the bump gets wrong within a pixel no factor of the
// point's inputs can undo. variant_rmse holds the one render's RMSE at G.
FloorSolution solve_image_floor(const FactorGrid& grid, const PixelRows& rows,
                                const FloorOptions& options = {});

}  // namespace penumbra
