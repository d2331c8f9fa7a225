#include "core/terminator.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace penumbra {
namespace {

constexpr std::array<MethodParameter, 1> kShadingOffsetParameters{{
    {"s", "dimensionless", 0.0, 1.0, 0.0,
     "Cycles' Shading Offset slider; cos(theta) becomes max(cos(f theta), 0) with "
     "f = 1/(1 - s/2)"},
}};

constexpr std::array<MethodInfo, 7> kMethods{{
    {TerminatorMethod::kNone,
     "none",
     "-",
     "raw bump: light dropped only where dot(Ns,wi) <= 0 or a shadow ray is blocked",
     {},
     true,
     ""},
    {TerminatorMethod::kChiang2019,
     "chiang2019",
     "Chiang, Li, Burley 2019, 'Taming the Shadow Terminator', SIGGRAPH talk, eqs. (1)-(2)",
     "G = min(1, <Ng,wi>/(<Ns,wi><Ng,Ns>)), smoothed by -G^3+G^2+G",
     {},
     true,
     ""},
    {TerminatorMethod::kChiang2019Sine,
     "chiang2019-sine",
     "MoonRay SINE_COMPENSATION",
     "chiang2019 with <Ng,Ns> replaced by |Ng x Ns|; denominators clamped to >= 1e-7",
     {},
     true,
     ""},
    {TerminatorMethod::kEstevez2019,
     "estevez2019",
     "Conty Estevez, Lecocq, Stein 2019, Ray Tracing Gems ch. 12, Listing 12-1",
     "GGX Smith G1 for wi with alpha^2 = tan^2(theta_d)/8 from the Ng-Ns deviation",
     {},
     true,
     ""},
    {TerminatorMethod::kEstevez2019Reciprocal,
     "estevez2019-reciprocal",
     "Ray Tracing Gems ch. 12, Fig. 12-7 right (rejected by the authors)",
     "the estevez2019 G1 for wi times the same G1 for wo; darkens silhouettes",
     {},
     true,
     "",
     "rejected by its authors (Ray Tracing Gems ch. 12, Fig. 12-7): it darkens silhouettes"},
    {TerminatorMethod::kDeshmukh2020,
     "deshmukh2020",
     "Deshmukh & Green 2020, 'Predictable and Targeted Softening of the Shadow Terminator', "
     "SIGGRAPH talk; MoonRay CUSTOM",
     "smoothstep of <Ng,wi>/d with d = lerp(0.14922, 0.01999, <Ns,Ng>)",
     {},
     false,
     "darkens the last 1.15 degrees before the geometric terminator even where Ns == Ng "
     "(<Ng,wi> < 0.01999)"},
    {TerminatorMethod::kShadingOffset, "shading-offset",
     "appleseed (Beaune 2019); Blender Cycles 'Shading Offset' (2.90+)",
     "cos(theta) -> max(cos(f theta), 0), theta = angle(Ns, wi); not energy conserving",
     kShadingOffsetParameters, false,
     "darkens every surface, bumped or not, for s > 0; the identity only for s = 0"},
}};

double clamp01(double x) {
  return std::clamp(x, 0.0, 1.0);
}

}  // namespace

std::span<const MethodInfo> all_methods() {
  return kMethods;
}

const MethodInfo& method_info(TerminatorMethod method) {
  return kMethods[static_cast<std::size_t>(method)];
}

std::optional<TerminatorMethod> method_from_id(std::string_view id) {
  for (const MethodInfo& info : kMethods)
    if (info.id == id) return info.method;
  return std::nullopt;
}

double chiang2019_raw_g(const Vec3& ng, const Vec3& ns, const Vec3& wi) {
  const double cos_g_i = dot(ng, wi);
  if (!(cos_g_i > 0.0)) return 0.0;
  const double denominator = dot(ns, wi) * dot(ng, ns);
  // A non-positive denominator means Ns faces away from the light or lies
  // below the geometric horizon; the ratio then carries no shadowing
  // information and the limit of eq. (1) for a vanishing denominator is 1.
  if (!(denominator > 0.0)) return 1.0;
  return clamp01(std::min(1.0, cos_g_i / denominator));
}

double chiang2019_smooth(double g) {
  return clamp01(-g * g * g + g * g + g);
}

double chiang2019(const Vec3& ng, const Vec3& ns, const Vec3& wi) {
  return chiang2019_smooth(chiang2019_raw_g(ng, ns, wi));
}

double chiang2019_sine(const Vec3& ng, const Vec3& ns, const Vec3& wi) {
  constexpr double kEpsilon = 1e-7;  // MoonRay's sEpsilon, float machine epsilon
  const double denominator =
      std::max(kEpsilon, dot(ns, wi)) * std::max(kEpsilon, length(cross(ng, ns)));
  const double g = clamp01(std::min(1.0, dot(ng, wi) / denominator));
  return chiang2019_smooth(g);
}

double estevez2019_alpha2(const Vec3& ng, const Vec3& ns) {
  const double cos_d = std::min(std::abs(dot(ng, ns)), 1.0);
  const double tan2_d = (1.0 - cos_d * cos_d) / (cos_d * cos_d);  // +inf for cos_d = 0
  return clamp01(0.125 * tan2_d);
}

double estevez2019_g1(const Vec3& ng, const Vec3& w, double alpha2) {
  const double cos_i = std::max(std::abs(dot(ng, w)), 1e-6);
  const double tan2_i = (1.0 - cos_i * cos_i) / (cos_i * cos_i);
  return clamp01(2.0 / (1.0 + std::sqrt(1.0 + alpha2 * tan2_i)));
}

double estevez2019(const Vec3& ng, const Vec3& ns, const Vec3& wi) {
  return estevez2019_g1(ng, wi, estevez2019_alpha2(ng, ns));
}

double deshmukh2020(const Vec3& ng, const Vec3& ns, const Vec3& wi) {
  const double cos_x = clamp01(dot(ns, ng));
  const double d = 0.14922 + (0.01999 - 0.14922) * cos_x;
  const double t = clamp01(dot(ng, wi) / d);
  return t * t * (3.0 - 2.0 * t);
}

double shading_offset_frequency(double s) {
  return 1.0 / (1.0 - 0.5 * s);
}

double shading_offset(double s, const Vec3& ns, const Vec3& wi) {
  const double f = shading_offset_frequency(s);
  // s = 0 is "off" in Cycles: exactly the identity, not cos(acos(c))/c.
  if (f == 1.0) return 1.0;
  const double cos_theta = std::min(dot(ns, wi), 1.0);
  // At and below the horizon the contribution is zero whatever the factor;
  // report the limit from above so that the factor stays continuous.
  if (!(cos_theta > 0.0)) return 0.0;
  const double theta = std::acos(cos_theta);
  return clamp01(std::max(std::cos(f * theta), 0.0) / cos_theta);
}

double terminator_factor(const MethodSettings& settings, const ShadingVectors& v) {
  switch (settings.method) {
    case TerminatorMethod::kNone:
      return 1.0;
    case TerminatorMethod::kChiang2019:
      return chiang2019(v.ng, v.ns, v.wi);
    case TerminatorMethod::kChiang2019Sine:
      return chiang2019_sine(v.ng, v.ns, v.wi);
    case TerminatorMethod::kEstevez2019:
      return estevez2019(v.ng, v.ns, v.wi);
    case TerminatorMethod::kEstevez2019Reciprocal: {
      const double alpha2 = estevez2019_alpha2(v.ng, v.ns);
      return estevez2019_g1(v.ng, v.wi, alpha2) * estevez2019_g1(v.ng, v.wo, alpha2);
    }
    case TerminatorMethod::kDeshmukh2020:
      return deshmukh2020(v.ng, v.ns, v.wi);
    case TerminatorMethod::kShadingOffset:
      return shading_offset(settings.shading_offset, v.ns, v.wi);
  }
  return 1.0;
}

}  // namespace penumbra
