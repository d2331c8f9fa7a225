#include "core/filtered_lobe.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace penumbra {

namespace {

void require_microfacet(FilteredDistribution distribution) {
  if (distribution == FilteredDistribution::kSchillingBlinnPhong)
    throw std::invalid_argument(
        "Schilling's modified Blinn-Phong has no normalised BRDF in its source");
}

// s^T A^-1 s and sqrt(det A) of a tensor clamped away from singular (a
// filter's A always holds the base alpha^2 > 0 on its diagonal).
struct Quadratic {
  double q, sqrt_det;
};
Quadratic quadratic(const Covariance2& a, double s_x, double s_y) {
  const double det = std::max(a.a * a.c - a.b * a.b, 1e-300);
  return {(a.c * s_x * s_x - 2.0 * a.b * s_x * s_y + a.a * s_y * s_y) / det, std::sqrt(det)};
}

}  // namespace

double slope_density(FilteredDistribution distribution, const Covariance2& alpha2, double s_x,
                     double s_y) {
  require_microfacet(distribution);
  const Quadratic q = quadratic(alpha2, s_x, s_y);
  if (distribution == FilteredDistribution::kBeckmann) return std::exp(-q.q) / (kPi * q.sqrt_det);
  const double denominator = 1.0 + q.q;
  return 1.0 / (kPi * q.sqrt_det * denominator * denominator);
}

double lobe_d(FilteredDistribution distribution, const Covariance2& alpha2, const Vec3& m) {
  if (m.z <= 0.0) return 0.0;
  const double cos2 = m.z * m.z;
  return slope_density(distribution, alpha2, -m.x / m.z, -m.y / m.z) / (cos2 * cos2);
}

double lobe_lambda(FilteredDistribution distribution, const Covariance2& alpha2, const Vec3& w) {
  require_microfacet(distribution);
  const double sin2 = w.x * w.x + w.y * w.y;
  if (sin2 <= 0.0 || w.z <= 0.0) return w.z > 0.0 ? 0.0 : INFINITY;
  const double alpha_w2 =
      (alpha2.a * w.x * w.x + 2.0 * alpha2.b * w.x * w.y + alpha2.c * w.y * w.y) / sin2;
  const double tan2 = sin2 / (w.z * w.z);
  if (distribution == FilteredDistribution::kGgx)
    return 0.5 * (std::sqrt(1.0 + alpha_w2 * tan2) - 1.0);
  const double a = 1.0 / std::sqrt(alpha_w2 * tan2);
  return 0.5 * (std::erf(a) - 1.0) + std::exp(-a * a) / (2.0 * a * std::sqrt(kPi));
}

double lobe_brdf(FilteredDistribution distribution, const Covariance2& alpha2, const Vec3& wi,
                 const Vec3& wo) {
  require_microfacet(distribution);
  if (wi.z <= 0.0 || wo.z <= 0.0) return 0.0;
  const Vec3 h = normalize(wi + wo);
  const double g2 =
      1.0 / (1.0 + lobe_lambda(distribution, alpha2, wi) + lobe_lambda(distribution, alpha2, wo));
  return lobe_d(distribution, alpha2, h) * g2 / (4.0 * wi.z * wo.z);
}

}  // namespace penumbra
