#include "core/normal_adjust.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace penumbra {
namespace {

constexpr std::array<NormalAdjustmentInfo, 10> kAdjustments{{
    {NormalAdjustment::kNone, "none", "-", "Ns as the bump makes it", true, true},
    {NormalAdjustment::kCycles34, "cycles34",
     "blender/cycles v3.4.0 (df60698dd147) src/kernel/closure/bsdf_util.h "
     "ensure_valid_reflection, applied to every SVM closure in src/kernel/svm/closure.h",
     "every lobe: Ns turned towards Ng until the mirror direction of wo clears Ng by "
     "min(0.9 <Ng,wo>, 0.01); Ng itself when no root fits",
     true, false},
    {NormalAdjustment::kCyclesGlossy, "cycles-glossy",
     "blender/cycles 645afc6e32fc (2023-03, Blender 3.6+) src/kernel/closure/bsdf_util.h "
     "ensure_valid_specular_reflection; glossy closures only since e92150bd1cdf",
     "glossy lobe only: as cycles34, the root of the quartic picked by the sign of <wo,X>", false,
     false},
    {NormalAdjustment::kCycles50, "cycles50",
     "blender/cycles 3b1e329ac808 (2025-06, Blender 5.0) src/kernel/closure/bsdf.h "
     "bump_shadowing_term (cosNsI, cosNsN, cosNI: the closure's own N); the glossy closure's N "
     "from maybe_ensure_valid_specular_reflection, src/kernel/svm/closure.h and bsdf_util.h",
     "the glossy lobe's normal Nc as cycles-glossy; each lobe dropped where "
     "<Ni,wi><Ni,Nc><Nc,wi> < 0 with its own normal Nc (Ns for the diffuse lobe)",
     true, false},
    {NormalAdjustment::kCycles50NoCorrection, "cycles50-no-correction",
     "blender/cycles 3b1e329ac808 src/kernel/closure/bsdf.h bump_shadowing_term (the hemisphere "
     "test before the SD_USE_BUMP_MAP_CORRECTION return) and bsdf_util.h "
     "maybe_ensure_valid_specular_reflection (N unchanged without that flag)",
     "Ns unchanged on every lobe; each lobe dropped where <Ni,wi><Ni,Ns><Ns,wi> < 0", true, false},
    {NormalAdjustment::kMitsuba3Flip, "mitsuba3-flip",
     "mitsuba-renderer/mitsuba3 e32d71807c2c src/bsdfs/normalmap_helpers.h "
     "(flip_invalid_normals), normalmap.cpp, bumpmap.cpp",
     "every lobe: Ns's part across Ni mirrored where <Ni,wo><Ns,wo> <= 0; light dropped where "
     "<Ni,wi><Ns,wi> <= 0",
     true, false},
    {NormalAdjustment::kIray2017, "iray2017",
     "Keller et al. 2017, arXiv 1705.01263, appendix A.3, as implemented in "
     "NVIDIAGameWorks/donut 05e015f7fd73 include/donut/shaders/utils.hlsli getBentNormal "
     "(the paper's text was not read)",
     "every lobe: where R = reflect(wo, Ns) lies below Ng, Ns -> normalize(wo + normalize(R - Ns "
     "<Ng,R>/max(0.001, <Ns,Ng>)))",
     true, false},
    {NormalAdjustment::kUnityHdrp, "unity-hdrp",
     "Unity-Technologies/Graphics 5d95227d9d46 com.unity.render-pipelines.high-definition/"
     "Runtime/RenderPipeline/PathTracing/Shaders/PathTracingMaterial.hlsl "
     "ComputeConsistentShadingNormal (PR 4142, 2021)",
     "glossy lobe only: where reflect(wo, Ns) lies below Ng, it is lifted to 0.001 above the "
     "horizon and Ns becomes the half vector",
     false, false},
    {NormalAdjustment::kFalcor, "falcor",
     "NVIDIAGameWorks/Falcor eb540f674877 Source/Falcor/Scene/Material/ShadingUtils.slang "
     "adjustShadingNormal",
     "every lobe: where <wo,Ns> <= 0.1, Ns -> normalize(lerp(Ng, Ns, <wo,Ns>/0.1)); not reciprocal",
     true, false},
    {NormalAdjustment::kOspray, "ospray",
     "RenderKit/ospray 675c216b91a7 modules/cpu/render/pathtracer/PathSampler.ispc "
     "sampleDirection (the sameSide/reflection test)",
     "Ns unchanged on every lobe; a reflected direction dropped where <Ng,wi> < 0 (OSPRay "
     "applies it to BSDF-sampled directions; its light samples keep it and move the shadow "
     "ray's origin below the surface instead)",
     true, false},
}};

// Cycles' thresholds on the squared z of the new normal, in float.
constexpr double kCyclesZ2Epsilon = 1e-5;

double safe_sqrt(double x) {
  return std::sqrt(std::max(x, 0.0));
}

// Degenerate configurations (a vector collapsing to zero) keep the normal
// they started from instead of turning into NaN.
Vec3 normalize_or(const Vec3& v, const Vec3& fallback) {
  const double l = length(v);
  return l > 1e-300 && std::isfinite(l) ? v / l : fallback;
}

}  // namespace

std::span<const NormalAdjustmentInfo> all_normal_adjustments() {
  return kAdjustments;
}

const NormalAdjustmentInfo& normal_adjustment_info(NormalAdjustment adjustment) {
  return kAdjustments[static_cast<std::size_t>(adjustment)];
}

std::optional<NormalAdjustment> normal_adjustment_from_id(std::string_view id) {
  for (const NormalAdjustmentInfo& info : kAdjustments)
    if (info.id == id) return info.adjustment;
  return std::nullopt;
}

Vec3 cycles34_valid_reflection_normal(const Vec3& ng, const Vec3& wo, const Vec3& ns) {
  const Vec3 r = ns * (2.0 * dot(ns, wo)) - wo;
  // A reflection may always be as shallow as the view itself.
  const double threshold = std::min(0.9 * dot(ng, wo), 0.01);
  if (dot(ng, r) >= threshold) return ns;
  // Frame: z = Ng, x = the part of Ns across Ng. The new normal stays in the
  // x-z plane; its z solves 2 <N',wo> N'_z - wo_z = threshold, squared:
  // a quadratic in N'_z^2.
  const Vec3 across = ns - ng * dot(ns, ng);
  const double across_length = length(across);
  if (!(across_length > 0.0)) return ng;
  const Vec3 x = across / across_length;
  const double ix = dot(wo, x), iz = dot(wo, ng);
  const double a = ix * ix + iz * iz;
  if (!(a > 0.0)) return ns;
  const double b = safe_sqrt(ix * ix * (a - threshold * threshold));
  const double c = iz * threshold + a;
  const double z2_first = 0.5 / a * (b + c), z2_second = 0.5 / a * (c - b);
  auto viable = [](double z2) { return z2 > kCyclesZ2Epsilon && z2 <= 1.0 + kCyclesZ2Epsilon; };
  auto normal_of = [](double z2) {
    return std::array<double, 2>{safe_sqrt(1.0 - z2), safe_sqrt(z2)};
  };
  auto reflected_z = [&](const std::array<double, 2>& n) {
    return 2.0 * (n[0] * ix + n[1] * iz) * n[1] - iz;
  };
  std::array<double, 2> chosen;
  const bool first = viable(z2_first), second = viable(z2_second);
  if (first && second) {
    const auto n1 = normal_of(z2_first), n2 = normal_of(z2_second);
    const double r1 = reflected_z(n1), r2 = reflected_z(n2);
    // Both lift the reflection: keep the shallower one, nearer to Ns.
    if (r1 >= kCyclesZ2Epsilon && r2 >= kCyclesZ2Epsilon)
      chosen = r1 < r2 ? n1 : n2;
    else
      chosen = r1 > r2 ? n1 : n2;
  } else if (first || second) {
    chosen = normal_of(first ? z2_first : z2_second);
  } else {
    return ng;
  }
  return normalize_or(x * chosen[0] + ng * chosen[1], ng);
}

Vec3 cycles_valid_specular_normal(const Vec3& ng, const Vec3& wo, const Vec3& ns) {
  const Vec3 r = ns * (2.0 * dot(ns, wo)) - wo;
  const double iz = dot(wo, ng);
  const double threshold = std::min(0.9 * iz, 0.01);
  if (dot(ng, r) >= threshold) return ns;
  const Vec3 across = ns - ng * dot(ns, ng);
  const double across_length = length(across);
  const Vec3 x = across_length > 0.0 ? across / across_length : ns;
  const double ix = dot(wo, x);
  const double a = ix * ix + iz * iz;
  if (!(a > 0.0)) return ns;
  const double b = 2.0 * (a + iz * threshold);
  const double c = (threshold + iz) * (threshold + iz);
  // 4a z^4 - 2b z^2 + c = 0; the unsquared equation needs the root whose
  // sign agrees with ix.
  const double root = safe_sqrt(b * b - 4.0 * a * c);
  const double z2 = 0.25 * (ix < 0.0 ? b + root : b - root) / a;
  return normalize_or(x * safe_sqrt(1.0 - z2) + ng * safe_sqrt(z2), ns);
}

bool cycles_hemisphere_rejects(const Vec3& ni, const Vec3& ns, const Vec3& wi) {
  return dot(ni, wi) * dot(ni, ns) * dot(ns, wi) < 0.0;
}

Vec3 mitsuba3_flipped_normal(const Vec3& ni, const Vec3& ns, const Vec3& wo) {
  if (dot(ni, wo) * dot(wo, ns) > 0.0) return ns;
  // (x, y, z) -> (-x, -y, z) in the frame of ni.
  return normalize_or(ni * (2.0 * dot(ns, ni)) - ns, ns);
}

bool mitsuba3_rejects(const Vec3& ni, const Vec3& ns, const Vec3& wi) {
  return !(dot(ni, wi) * dot(ns, wi) > 0.0);
}

Vec3 iray2017_bent_normal(const Vec3& ng, const Vec3& ns, const Vec3& wo) {
  const Vec3 r = ns * (2.0 * dot(ns, wo)) - wo;
  const double a = dot(ng, r);
  if (!(a < 0.0)) return ns;
  // R moved along Ns onto the plane of Ng (no margin), then the half vector.
  const double b = std::max(0.001, dot(ns, ng));
  return normalize_or(wo + normalize_or(r - ns * (a / b), r), ns);
}

Vec3 unity_hdrp_consistent_normal(const Vec3& ng, const Vec3& ns, const Vec3& wo) {
  const double hi = dot(ng, wo) > 0.0 ? 1.0 : (dot(ng, wo) < 0.0 ? -1.0 : 0.0);
  // A normal facing away from the viewer loses its component along wo.
  const Vec3 n = ns - wo * (hi * std::min(0.0, hi * dot(ns, wo)));
  Vec3 r = n * (2.0 * dot(n, wo)) - wo;
  const double ho = dot(ng, r) > 0.0 ? 1.0 : (dot(ng, r) < 0.0 ? -1.0 : 0.0);
  if (hi == ho) return ns;
  r = normalize_or(r - ng * (dot(ng, r) + ho * 0.001), r);
  if (hi == 0.0) return ns;  // Unity's sign(0) = 0 would zero the normal
  return normalize_or(wo + r, ns) * hi;
}

Vec3 falcor_adjusted_normal(const Vec3& ng, const Vec3& ns, const Vec3& wo) {
  constexpr double kCosThreshold = 0.1;
  // Ns is first turned to Ng's side (ng faces the viewer).
  const double sign = dot(ns, ng) >= 0.0 ? 1.0 : -1.0;
  const Vec3 n = ns * sign;
  const double cos_o = dot(wo, n);
  if (cos_o > kCosThreshold) return ns;
  const double t = std::clamp(cos_o / kCosThreshold, 0.0, 1.0);
  return normalize_or(ng + (n - ng) * t, ng) * sign;
}

bool ospray_side_test_rejects(const Vec3& ng, const Vec3& wi) {
  // sameSide = dot(wi, Ng) >= 0; a reflection is kept only on the same side.
  const bool same_side = dot(wi, ng) >= 0.0;
  constexpr bool kReflection = true;
  return same_side != kReflection;
}

AdjustedNormals adjust_normal(NormalAdjustment adjustment, const AdjustVectors& v) {
  AdjustedNormals out{v.ns, v.ns};
  switch (adjustment) {
    case NormalAdjustment::kNone:
      break;
    case NormalAdjustment::kCycles34:
      out.ns_diffuse = out.ns_specular = cycles34_valid_reflection_normal(v.ng, v.wo, v.ns);
      break;
    case NormalAdjustment::kCyclesGlossy:
      out.ns_specular = cycles_valid_specular_normal(v.ng, v.wo, v.ns);
      break;
    case NormalAdjustment::kCycles50:
      // Each closure is tested with its own normal sc->N (bsdf.h
      // bump_shadowing_term: cosNsN = dot(sd->N, sc->N), cosNI = dot(sc->N, I)),
      // and a glossy closure's N is already
      // maybe_ensure_valid_specular_reflection(sd, N) (svm/closure.h): so the
      // glossy lobe is tested with the adjusted normal, the diffuse with Ns.
      out.ns_specular = cycles_valid_specular_normal(v.ng, v.wo, v.ns);
      out.reject_diffuse = cycles_hemisphere_rejects(v.ni, v.ns, v.wi);
      out.reject_specular = cycles_hemisphere_rejects(v.ni, out.ns_specular, v.wi);
      break;
    case NormalAdjustment::kCycles50NoCorrection:
      // Without the material's flag every closure keeps N = Ns, and the
      // hemisphere test still runs before bump_shadowing_term returns 1.
      out.reject_diffuse = out.reject_specular = cycles_hemisphere_rejects(v.ni, v.ns, v.wi);
      break;
    case NormalAdjustment::kMitsuba3Flip:
      out.ns_diffuse = out.ns_specular = mitsuba3_flipped_normal(v.ni, v.ns, v.wo);
      out.reject_diffuse = out.reject_specular = mitsuba3_rejects(v.ni, out.ns_diffuse, v.wi);
      break;
    case NormalAdjustment::kIray2017:
      out.ns_diffuse = out.ns_specular = iray2017_bent_normal(v.ng, v.ns, v.wo);
      break;
    case NormalAdjustment::kUnityHdrp:
      out.ns_specular = unity_hdrp_consistent_normal(v.ng, v.ns, v.wo);
      break;
    case NormalAdjustment::kFalcor:
      out.ns_diffuse = out.ns_specular = falcor_adjusted_normal(v.ng, v.ns, v.wo);
      break;
    case NormalAdjustment::kOspray:
      // Against the true Ng, not Ni: OSPRay's dg.Ng is the triangle's.
      out.reject_diffuse = out.reject_specular = ospray_side_test_rejects(v.ng, v.wi);
      break;
  }
  return out;
}

}  // namespace penumbra
