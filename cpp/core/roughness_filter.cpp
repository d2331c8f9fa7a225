#include "core/roughness_filter.h"

#include <algorithm>
#include <cmath>

namespace penumbra {

namespace {

constexpr FilterParameter kPixarParameters[] = {
    {"gain", "dimensionless", 0.0, 10.0, 1.0,
     "multiplier g of the aggregate roughness (PxrBump2Roughness `gain`)"}};
constexpr FilterParameter kTokuyoshiParameters[] = {
    {"kernel_variance", "pixel^2", 0.0, 1.0, 0.15915494309189535,
     "screen-space filter variance sigma^2; 1/(2 pi) in JCGT 2021 Listing 5, "
     "2 x 0.25 = 0.5 in the I3D 2019 form"},
    {"kernel_clamp", "dimensionless", 0.0, 1.0, 0.18, "clamp kappa on the added alpha^2"}};

constexpr RoughnessFilterInfo kFilters[] = {
    {RoughnessFilter::kMipOnly,
     "mip-only",
     "Schilling 1997, 'Problem' (the failure the pyramid fixes)",
     "mean offset only: filtered bumps vanish and the base lobe is kept (A = alpha^2 I)",
     {},
     FilteredDistribution::kGgx},
    {RoughnessFilter::kBeckmannVariance,
     "beckmann-variance",
     "Conty Estevez et al. 2019 (RTG ch. 12), Fig. 12-6 top: the common mapping",
     "sigma^2 = alpha^2: A = (alpha^2 + tr K) I on the GGX lobe",
     {},
     FilteredDistribution::kGgx},
    {RoughnessFilter::kGgxVarianceEstevez2019,
     "ggx-variance-estevez2019",
     "Conty Estevez et al. 2019 (RTG ch. 12), sec. 12.3.1 and Fig. 12-6 bottom",
     "sigma^2 = 2 alpha^2 (GGX truncated at 4 alpha): A = (alpha^2 + tr K / 2) I",
     {},
     FilteredDistribution::kGgx},
    {RoughnessFilter::kToksvig2005,
     "toksvig2005",
     "Toksvig 2005, 'Mipmapping Normal Maps' (J. Graphics Tools 10(3)); exponent <-> alpha "
     "by Walter et al. 2007, eq. 33",
     "Blinn-Phong exponent s = 2/alpha^2 - 2 scaled by |n|/(|n| + s(1 - |n|)), |n| the "
     "length of the mean unit normal; A = 2/(s' + 2) I",
     {},
     FilteredDistribution::kGgx},
    {RoughnessFilter::kLean2010,
     "lean2010",
     "Olano & Baker 2010, 'LEAN Mapping' (I3D), with the authors' errata",
     "Sigma = M - B B^T + (1/s) I, 1/s = alpha^2/2; anisotropic Beckmann lobe, A = 2 Sigma",
     {},
     FilteredDistribution::kBeckmann},
    {RoughnessFilter::kPixar2014, "pixar2014",
     "Hery, Kass & Ling 2014, 'Geometry into Shading' (Pixar TM 14-04); PxrBump2Roughness "
     "(bumpRoughMapping); OpenImageIO maketx --bumpslopes",
     "Sigma = 2 g^2 (E[d d^T] - E[d] E[d]^T), eigenvalues added to alpha^2 per axis: "
     "A = alpha^2 I + 2 g^2 K on the GGX lobe",
     kPixarParameters, FilteredDistribution::kGgx},
    {RoughnessFilter::kTokuyoshi2021, "tokuyoshi2021",
     "Tokuyoshi & Kaplanyan, I3D 2019 and JCGT 10(2) 2021, Listing 5 "
     "(github.com/yusuketokuyoshi/VSGL, NDFFiltering.hlsli)",
     "A = saturate(alpha^2 + min(sigma^2 (|dn/dx|^2 + |dn/dy|^2), kappa)) I, from the "
     "shading normal's screen-space derivatives, not the pyramid",
     kTokuyoshiParameters, FilteredDistribution::kGgx, true},
    {RoughnessFilter::kSchilling1997,
     "schilling1997",
     "Schilling 1997 (Graphics Hardware workshop), bump-map roughness pyramid, appendix A (seed)",
     "modified Blinn-Phong with the anisotropic roughness K (+ alpha^2/2 I for the base lobe)",
     {},
     FilteredDistribution::kSchillingBlinnPhong},
    {RoughnessFilter::kSchilling1997Isotropic,
     "schilling1997-isotropic",
     "Schilling 1997, 'Isotropic roughness representation' and appendix A (seed)",
     "modified Blinn-Phong with lambda1^2 I, lambda1^2 the largest eigenvalue of K "
     "(+ alpha^2/2)",
     {},
     FilteredDistribution::kSchillingBlinnPhong},
};

Covariance2 isotropic(double alpha2) {
  return {alpha2, 0.0, alpha2};
}

Covariance2 plus(const Covariance2& k, double scale, double diagonal) {
  return {scale * k.a + diagonal, scale * k.b, scale * k.c + diagonal};
}

double toksvig_alpha2(double alpha, double mean_normal_length) {
  const double length = std::clamp(mean_normal_length, 1e-6, 1.0);
  const double s = 2.0 / (alpha * alpha) - 2.0;
  const double s_filtered = s * length / (length + s * (1.0 - length));
  return 2.0 / (s_filtered + 2.0);
}

}  // namespace

std::span<const RoughnessFilterInfo> all_roughness_filters() {
  return kFilters;
}

const RoughnessFilterInfo& roughness_filter_info(RoughnessFilter filter) {
  for (const RoughnessFilterInfo& info : kFilters)
    if (info.filter == filter) return info;
  return kFilters[0];
}

std::optional<RoughnessFilter> roughness_filter_from_id(std::string_view id) {
  for (const RoughnessFilterInfo& info : kFilters)
    if (info.id == id) return info.filter;
  return std::nullopt;
}

FilteredLobe filter_roughness(const FilterSettings& settings, const FootprintStatistics& footprint,
                              double alpha) {
  const double alpha2 = alpha * alpha;
  const Covariance2& k = footprint.slope_covariance;
  const double trace = k.a + k.c;
  const FilteredDistribution distribution = roughness_filter_info(settings.filter).distribution;
  switch (settings.filter) {
    case RoughnessFilter::kMipOnly:
      return {distribution, isotropic(alpha2)};
    case RoughnessFilter::kBeckmannVariance:
      return {distribution, isotropic(alpha2 + trace)};
    case RoughnessFilter::kGgxVarianceEstevez2019:
      return {distribution, isotropic(alpha2 + 0.5 * trace)};
    case RoughnessFilter::kToksvig2005:
      return {distribution, isotropic(toksvig_alpha2(alpha, footprint.mean_normal_length))};
    case RoughnessFilter::kLean2010:
      return {distribution, plus(k, 2.0, alpha2)};
    case RoughnessFilter::kPixar2014:
      return {distribution, plus(k, 2.0 * settings.gain * settings.gain, alpha2)};
    case RoughnessFilter::kTokuyoshi2021: {
      const double kernel = settings.kernel_variance * footprint.normal_derivative2;
      return {distribution,
              isotropic(std::min(alpha2 + std::min(kernel, settings.kernel_clamp), 1.0))};
    }
    case RoughnessFilter::kSchilling1997:
      return {distribution, plus(k, 1.0, 0.5 * alpha2)};
    case RoughnessFilter::kSchilling1997Isotropic: {
      const double lambda1 = isotropic_roughness(k);
      return {distribution, isotropic(lambda1 * lambda1 + 0.5 * alpha2)};
    }
  }
  return {distribution, isotropic(alpha2)};
}

TruncatedMoments ggx_truncated_slope_moments(double radius_over_alpha) {
  // alpha = 1 without loss of generality. Over the slope disc, P22 2 pi r dr
  // = 2 r / (1 + r^2)^2 dr; composite Simpson in r, fine enough that the
  // quadrature error (~1e-12) is far below the chapter's three digits.
  const int intervals = 20000;
  const double h = radius_over_alpha / intervals;
  double mass = 0.0, second = 0.0;
  for (int i = 0; i <= intervals; ++i) {
    const double r = i * h;
    const double weight = (i == 0 || i == intervals) ? 1.0 : (i % 2 ? 4.0 : 2.0);
    const double density = 2.0 * r / ((1.0 + r * r) * (1.0 + r * r));
    mass += weight * density;
    second += weight * density * r * r;
  }
  mass *= h / 3.0;
  second *= h / 3.0;
  return {mass, mass > 0.0 ? second / mass : 0.0};
}

}  // namespace penumbra
