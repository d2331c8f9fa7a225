#include "core/bsdf.h"

#include "core/filtered_lobe.h"

#include <cmath>

namespace penumbra {

double ggx_d(double cos_theta_m, double alpha) {
  if (cos_theta_m <= 0.0) return 0.0;
  const double a2 = alpha * alpha;
  const double c2 = cos_theta_m * cos_theta_m;
  const double denominator = c2 * (a2 - 1.0) + 1.0;
  return a2 / (kPi * denominator * denominator);
}

namespace {
double smith_lambda(double cos_theta, double alpha) {
  const double c2 = cos_theta * cos_theta;
  const double tan2 = (1.0 - c2) / c2;
  return 0.5 * (std::sqrt(1.0 + alpha * alpha * tan2) - 1.0);
}
}  // namespace

double ggx_g2(double cos_theta_i, double cos_theta_o, double alpha) {
  if (cos_theta_i <= 0.0 || cos_theta_o <= 0.0) return 0.0;
  return 1.0 / (1.0 + smith_lambda(cos_theta_i, alpha) + smith_lambda(cos_theta_o, alpha));
}

LobeValues evaluate_lobes(const Material& m, const Vec3& ns, const Vec3& wi, const Vec3& wo) {
  LobeValues out;
  const double cos_theta_i = dot(ns, wi);
  const double cos_theta_o = dot(ns, wo);
  if (cos_theta_i <= 0.0) return out;
  // Lambert does not look at wo, as in POV-Ray and Cycles: a bump normal
  // turned away from the viewer still shows diffuse light.
  out.diffuse = (1.0 - m.specular_weight) * m.albedo * kInvPi;
  if (m.specular_weight > 0.0 && cos_theta_o > 0.0 && m.filtered.active) {
    const Vec3 t = normalize(m.filtered.tangent - ns * dot(ns, m.filtered.tangent));
    const Frame frame{t, cross(ns, t), ns};
    out.specular = m.specular_weight * lobe_brdf(m.filtered.distribution, m.filtered.alpha2,
                                                 frame.to_local(wi), frame.to_local(wo));
  } else if (m.specular_weight > 0.0 && cos_theta_o > 0.0) {
    const Vec3 half = normalize(wi + wo);
    out.specular = m.specular_weight * ggx_d(dot(ns, half), m.specular_roughness) *
                   ggx_g2(cos_theta_i, cos_theta_o, m.specular_roughness) /
                   (4.0 * cos_theta_i * cos_theta_o);
  }
  return out;
}

}  // namespace penumbra
