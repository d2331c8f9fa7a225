// Intervals for the metrics of one comparison (a test image against its
// reference), from a paired block bootstrap over bands of image rows.
//
// The image is cut into horizontal bands of `band_rows` rows. Each bootstrap
// replicate draws as many bands with replacement, builds both terminator
// profiles and the image error from the same bands (paired: test and
// reference always see the same pixels), and recomputes the metric; the
// interval is the replicates' 95 % percentile spread around their mean,
// placed around the estimate (see centred_interval). Bands are longer
// than the correlation between neighbouring rows, so the interval covers the
// spread of the metric over the image's regions: the phases of the bump each
// region happens to sample and the sample noise of both renders. It does not
// cover a bias both images share (an unconverged ground truth), one the
// sampling of phases cannot reveal (a grating phase-locked to theta: every
// band then sees the same phases and the interval collapses), nor where the
// pixel grid happens to cut a hard terminator (measured in the README,
// "Reading the numbers": up to 20 % for a half-pixel camera shift).
#pragma once

#include <cstdint>
#include <limits>

#include "analysis/metrics.h"
#include "analysis/statistics.h"

namespace penumbra {

struct ComparisonIntervals {
  Interval rmse_terminator;    // profile, fraction of albedo*E/pi
  Interval image_rmse;         // W m^-2 sr^-1, like ImageMetrics::rmse
  Interval view_rmse_grazing;  // fraction of albedo*E/pi, like ViewMetrics
  Interval view_bias_grazing;  // signed, same unit
  // The other profile metrics (ProfileMetrics): fraction of albedo*E/pi,
  // degrees. NaN where the metric is undefined in the estimate.
  Interval max_error, position_error, lit_bias;
  // Mean HDR-FLIP (ImageMetrics::flip): the same bands of rows and resamples
  // (mean_flip_interval, analysis/flip.h); NaN unless it was measured.
  Interval flip{std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
  // mean(replicates) - estimate: how much resampling noise inflates the
  // terminator RMSE (a finite-pixel bias of the same sign in the estimate).
  double rmse_terminator_bias = 0.0;
  int bands = 0, resamples = 0;
};

// Bands: a fixed fraction of the image height, so that an interval means
// the same at every resolution (8 rows at 128 px).
inline constexpr int kIntervalBands = 16;
inline constexpr int kIntervalResamples = 400;

ComparisonIntervals comparison_intervals(const Image& test, const Image& reference,
                                         double radiance_scale, const ProfileOptions& options = {},
                                         int bands = kIntervalBands,
                                         int resamples = kIntervalResamples,
                                         std::uint64_t seed = 1);

}  // namespace penumbra
