// Filtered bumps back into roughness: the mappings from a texel footprint's
// slope statistics (bump_pyramid.h) to the lobe a renderer shades with.
// One enum, one table, one switch, as for the terminator methods. Sources
// and formulas: each paper or its public code, as cited in the table's
// `source` (Schilling 1997, Graphics Hardware workshop; Conty Estevez et al.
// 2019, Ray Tracing Gems ch. 12; Toksvig 2005; Olano & Baker 2010; Hery,
// Kass & Ling 2014; Tokuyoshi & Kaplanyan 2021); docs/filtering.md.
//
// Units: slopes are offsets (height per scene unit, bump_pyramid.h); a
// lobe's roughness is a slope-space alpha^2 tensor A, so that the GGX slope
// density is 1 / (pi sqrt(det A) (1 + s^T A^-1 s)^2) and Beckmann's is
// exp(-s^T A^-1 s) / (pi sqrt(det A)); isotropic A = alpha^2 I.
#pragma once

#include <optional>
#include <span>
#include <string_view>

#include "core/bump_pyramid.h"
#include "core/terminator.h"

namespace penumbra {

enum class RoughnessFilter {
  kMipOnly,
  kBeckmannVariance,
  kGgxVarianceEstevez2019,
  kToksvig2005,
  kLean2010,
  kPixar2014,
  kTokuyoshi2021,
  kSchilling1997,
  kSchilling1997Isotropic,
};

// The lobe shape a filter hands to shading.
enum class FilteredDistribution { kGgx, kBeckmann, kSchillingBlinnPhong };

// A filter's parameters are documented like the terminator methods'.
using FilterParameter = MethodParameter;

struct RoughnessFilterInfo {
  RoughnessFilter filter;
  std::string_view id;  // what users type
  std::string_view source;
  std::string_view summary;
  std::span<const FilterParameter> parameters;
  FilteredDistribution distribution;
  // Reads the screen-space derivatives of the normal (ray differentials),
  // not the roughness pyramid.
  bool needs_normal_derivatives = false;
};

std::span<const RoughnessFilterInfo> all_roughness_filters();
const RoughnessFilterInfo& roughness_filter_info(RoughnessFilter filter);
std::optional<RoughnessFilter> roughness_filter_from_id(std::string_view id);

// What a filter may read about the footprint, all in the bump frame.
struct FootprintStatistics {
  Covariance2 slope_covariance;     // K from the roughness pyramid, offset^2
  double mean_normal_length = 1.0;  // |mean of the unit bumped normals|, (0, 1]
  // Screen-space derivatives of the unit shading normal, per pixel:
  // |dn/dx|^2 + |dn/dy|^2 (Tokuyoshi and Kaplanyan's kernel input).
  double normal_derivative2 = 0.0;
};

// Parameter values; defaults are the sources' own (see the table).
struct FilterSettings {
  RoughnessFilter filter = RoughnessFilter::kGgxVarianceEstevez2019;
  double gain = 1.0;                             // pixar2014 `gain` g
  double kernel_variance = 0.15915494309189535;  // tokuyoshi2021 sigma^2, 1/(2 pi)
  double kernel_clamp = 0.18;                    // tokuyoshi2021 kappa
};

// The lobe after filtering.
struct FilteredLobe {
  FilteredDistribution distribution = FilteredDistribution::kGgx;
  // Slope-space alpha^2 tensor A (see top). For kSchillingBlinnPhong the
  // covariance the modified Blinn-Phong reads (schilling_cos2_alpha): K
  // plus the base lobe's per-axis slope variance alpha^2 / 2.
  Covariance2 alpha2;
};

// The lobe that shades a footprint of a material with isotropic base GGX
// roughness `alpha` (> 0) under `settings`.
FilteredLobe filter_roughness(const FilterSettings& settings, const FootprintStatistics& footprint,
                              double alpha);

// The truncated moments of GGX's slope distribution that the Ray Tracing
// Gems chapter (ch. 12, Fig. 12-5) rests on, by numerical quadrature: keep
// slopes of radius <= radius_over_alpha * alpha; `mass` is the fraction of
// the distribution kept and `mean_tan2_over_alpha2` the kept part's mean of
// tan^2(theta_m) = |s|^2, over alpha^2 (the chapter: 94.1 % and 2.01 at 4).
struct TruncatedMoments {
  double mass = 0.0;
  double mean_tan2_over_alpha2 = 0.0;
};
TruncatedMoments ggx_truncated_slope_moments(double radius_over_alpha);

}  // namespace penumbra
