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

constexpr std::array<MethodInfo, 24> kMethods{{
    {TerminatorMethod::kNone,
     "none",
     "-",
     "raw bump: light dropped only where dot(Ns,wi) <= 0 or a shadow ray is blocked",
     {},
     MethodKind::kFactor,
     NormalAdjustment::kNone,
     FactorLobes::kScene,
     false,
     true,
     ""},
    {TerminatorMethod::kChiang2019,
     "chiang2019",
     "Chiang, Li, Burley 2019, 'Taming the Shadow Terminator', SIGGRAPH talk, eqs. (1)-(2)",
     "G = min(1, <Ng,wi>/(<Ns,wi><Ng,Ns>)), smoothed by -G^3+G^2+G",
     {},
     MethodKind::kFactor,
     NormalAdjustment::kNone,
     FactorLobes::kScene,
     false,
     true,
     ""},
    {TerminatorMethod::kChiang2019Sine,
     "chiang2019-sine",
     "MoonRay SINE_COMPENSATION",
     "chiang2019 with <Ng,Ns> replaced by |Ng x Ns|; denominators clamped to >= 1e-7",
     {},
     MethodKind::kFactor,
     NormalAdjustment::kNone,
     FactorLobes::kScene,
     false,
     true,
     ""},
    {TerminatorMethod::kEstevez2019,
     "estevez2019",
     "Conty Estevez, Lecocq, Stein 2019, Ray Tracing Gems ch. 12, Listing 12-1",
     "GGX Smith G1 for wi with alpha^2 = tan^2(theta_d)/8 from the Ng-Ns deviation",
     {},
     MethodKind::kFactor,
     NormalAdjustment::kNone,
     FactorLobes::kScene,
     false,
     true,
     ""},
    {TerminatorMethod::kEstevez2019Reciprocal,
     "estevez2019-reciprocal",
     "Ray Tracing Gems ch. 12, Fig. 12-7 right (rejected by the authors)",
     "the estevez2019 G1 for wi times the same G1 for wo; darkens silhouettes",
     {},
     MethodKind::kFactor,
     NormalAdjustment::kNone,
     FactorLobes::kScene,
     false,
     true,
     "",
     "rejected by its authors (Ray Tracing Gems ch. 12, Fig. 12-7): it darkens silhouettes"},
    {TerminatorMethod::kDeshmukh2020,
     "deshmukh2020",
     "Deshmukh & Green 2020, 'Predictable and Targeted Softening of the Shadow Terminator', "
     "SIGGRAPH talk; MoonRay CUSTOM",
     "smoothstep of <Ng,wi>/d with d = lerp(0.14922, 0.01999, <Ns,Ng>)",
     {},
     MethodKind::kFactor,
     NormalAdjustment::kNone,
     FactorLobes::kScene,
     false,
     false,
     "darkens the last 1.15 degrees before the geometric terminator even where Ns == Ng "
     "(<Ng,wi> < 0.01999)"},
    {TerminatorMethod::kShadingOffset, "shading-offset",
     "appleseed (Beaune 2019); Blender Cycles 'Shading Offset' (2.90+)",
     "cos(theta) -> max(cos(f theta), 0), theta = angle(Ns, wi); not energy conserving",
     kShadingOffsetParameters, MethodKind::kFactor, NormalAdjustment::kNone, FactorLobes::kScene,
     false, false, "darkens every surface, bumped or not, for s > 0; the identity only for s = 0"},
    {TerminatorMethod::kCycles34,
     "cycles34",
     "Blender Cycles 2.81-3.5 as Blender 3.4 ships it: blender/cycles v3.4.0 (df60698dd147) "
     "src/kernel/closure/bsdf.h bump_shadowing_term, svm/closure.h",
     "Chiang's G against Ni on the diffuse lobe (Cycles' form: Ni negated where <Ns,wi> < 0, 0 "
     "for a zero denominator), after the cycles34 adjustment of every lobe's normal",
     {},
     MethodKind::kFactorAndAdjustment,
     NormalAdjustment::kCycles34,
     FactorLobes::kDiffuse,
     true,
     true,
     ""},
    {TerminatorMethod::kCycles45,
     "cycles45",
     "Blender Cycles 4.5: blender/cycles 11e282522e12 (2025-03) src/kernel/closure/bsdf.h "
     "bump_shadowing_term; glossy closures as cycles-glossy",
     "0 where <Ni,wi><Ni,Ns><Ns,wi> < 0, else the Conty term with cos_d = |<Ni,Ns>|, cos_i = "
     "|<Ni,wi>| (0 below 1e-6) on the diffuse lobe; cycles-glossy on the glossy lobe",
     {},
     MethodKind::kFactorAndAdjustment,
     NormalAdjustment::kCyclesGlossy,
     FactorLobes::kDiffuse,
     true,
     true,
     ""},
    {TerminatorMethod::kCycles50,
     "cycles50",
     "Blender Cycles 5.0+: blender/cycles 3b1e329ac808 (2025-06) src/kernel/closure/bsdf.h "
     "bump_shadowing_term; glossy closures' N from svm/closure.h "
     "maybe_ensure_valid_specular_reflection",
     "cycles45's diffuse term, and the hemisphere test on every lobe, each with its own normal: "
     "the glossy lobe's after cycles-glossy (the cycles50 adjustment)",
     {},
     MethodKind::kFactorAndAdjustment,
     NormalAdjustment::kCycles50,
     FactorLobes::kDiffuse,
     true,
     true,
     ""},
    {TerminatorMethod::kCycles50NoCorrection,
     "cycles50-no-correction",
     "Blender Cycles 5.0+ with the material's Bump Map Correction off (use_bump_map_correction, "
     "Blender 4.2+, blender/blender cb94c5b83, PR 113480): blender/cycles 3b1e329ac808 "
     "src/kernel/closure/bsdf.h bump_shadowing_term and bsdf_util.h "
     "maybe_ensure_valid_specular_reflection, both returning early without "
     "SD_USE_BUMP_MAP_CORRECTION",
     "no softening term and no glossy normal adjustment; the hemisphere test "
     "<Ni,wi><Ni,Ns><Ns,wi> < 0 kept on every lobe (the cycles50-no-correction adjustment)",
     {},
     MethodKind::kAdjustment,
     NormalAdjustment::kCycles50NoCorrection,
     FactorLobes::kDiffuse,
     true,
     true,
     ""},
    {TerminatorMethod::kMitsuba3,
     "mitsuba3",
     "Mitsuba 3 normalmap/bumpmap defaults: mitsuba-renderer/mitsuba3 e32d71807c2c "
     "src/bsdfs/normalmap_helpers.h",
     "mitsuba3-flip, then alpha^2 = min(tan^2(Ns)/8, 1), G = 2/(1 + sqrt(1 + alpha^2 "
     "tan^2(wi))), angles from Ni, on every lobe",
     {},
     MethodKind::kFactorAndAdjustment,
     NormalAdjustment::kMitsuba3Flip,
     FactorLobes::kAll,
     true,
     true,
     ""},
    {TerminatorMethod::kMitsuba3Flip,
     "mitsuba3-flip",
     "Mitsuba 3 with use_shadowing_function=false (e32d71807c2c)",
     "the mitsuba3-flip adjustment alone: no shadowing function",
     {},
     MethodKind::kAdjustment,
     NormalAdjustment::kMitsuba3Flip,
     FactorLobes::kAll,
     true,
     true,
     ""},
    {TerminatorMethod::kIray2017,
     "iray2017",
     "Keller et al. 2017, 'The Iray Light Transport Simulation and Rendering System', arXiv "
     "1705.01263, appendix A.3 (via NVIDIAGameWorks/donut 05e015f7fd73 getBentNormal)",
     "the iray2017 adjustment alone: Ns bent so that the mirror direction of wo reaches Ng's "
     "horizon",
     {},
     MethodKind::kAdjustment,
     NormalAdjustment::kIray2017,
     FactorLobes::kAll,
     false,
     true,
     ""},
    {TerminatorMethod::kUnityHdrp,
     "unity-hdrp",
     "Unity HDRP path tracer ComputeConsistentShadingNormal (Unity-Technologies/Graphics "
     "5d95227d9d46, PR 4142)",
     "the unity-hdrp adjustment alone (glossy lobe only; diffuse keeps Ns)",
     {},
     MethodKind::kAdjustment,
     NormalAdjustment::kUnityHdrp,
     FactorLobes::kAll,
     false,
     true,
     ""},
    {TerminatorMethod::kFalcor,
     "falcor",
     "Falcor adjustShadingNormal (NVIDIAGameWorks/Falcor eb540f674877 "
     "Source/Falcor/Scene/Material/ShadingUtils.slang)",
     "the falcor adjustment alone: Ns pulled towards Ng where <wo,Ns> <= 0.1; breaks reciprocity "
     "by design",
     {},
     MethodKind::kAdjustment,
     NormalAdjustment::kFalcor,
     FactorLobes::kAll,
     false,
     true,
     ""},
    {TerminatorMethod::kOspray,
     "ospray",
     "OSPRay path tracer: RenderKit/ospray 675c216b91a7 "
     "modules/cpu/render/pathtracer/PathSampler.ispc sampleDirection (side test) and "
     "NextEventEstimation.ispc (shadow ray origin, the ospray offset)",
     "the ospray adjustment alone: Ns unchanged, light dropped where <Ng,wi> < 0; no factor",
     {},
     MethodKind::kAdjustment,
     NormalAdjustment::kOspray,
     FactorLobes::kAll,
     false,
     true,
     ""},
    {TerminatorMethod::kSchuessler2017,
     "schuessler2017",
     "Schuessler, Heitz, Hanika, Dachsbacher 2017, 'Microfacet-based Normal Mapping for Robust "
     "Monte Carlo Path Tracing', ACM TOG 36(6); explicit form as in appleseedhq/appleseed "
     "390d5cda9959 microfacetbrdfwrapper.h",
     "two-facet microsurface (Ns and a mirror tangent facet); explicit paths v-p-l, v-p-t-l, "
     "v-t-p-l; replaces the BSDF",
     {},
     MethodKind::kMicrofacet,
     NormalAdjustment::kNone,
     FactorLobes::kAll,
     false,
     true,
     ""},
    {TerminatorMethod::kSchuessler2017Shadowing,
     "schuessler2017-shadowing",
     "Schuessler et al. 2017 without inter-reflection; Chiang et al. 2019 call it overly dark",
     "the bumped BSDF times the two-facet shadowing G1(wi, Ns) of the tangent facet; no "
     "inter-reflection",
     {},
     MethodKind::kMicrofacet,
     NormalAdjustment::kNone,
     FactorLobes::kAll,
     false,
     true,
     ""},
    {TerminatorMethod::kSchuessler2017Walk,
     "schuessler2017-walk",
     "Schuessler et al. 2017, stochastic evaluation (random walk between the facets; cf. "
     "mizuooon/Xitils 3a4806335647 MicrofacetBasedNormalMapping)",
     "random walk on the two-facet microsurface with next-event estimation on Ns, at most 16 "
     "visits; one walk per camera sample, seeded per pixel",
     {},
     MethodKind::kMicrofacet,
     NormalAdjustment::kNone,
     FactorLobes::kAll,
     false,
     true,
     "",
     {},
     false,
     true},
    {TerminatorMethod::kMicroshadowChan2018,
     "microshadow-chan2018",
     "Chan 2018, 'Material Advances in Call of Duty: WWII', SIGGRAPH course, as "
     "google/filament 2aaabc938675 shaders/src/common_lighting.fs computeMicroShadowing",
     "saturate(<Ns,wi> / sqrt(1 - V))^2 on every lobe, V the height field's ambient visibility "
     "(computed by the evaluator from the height function, flat base)",
     {},
     MethodKind::kFactor,
     NormalAdjustment::kNone,
     FactorLobes::kAll,
     false,
     true,
     "",
     "",
     true},
    {TerminatorMethod::kMicroshadowBrinck2016,
     "microshadow-brinck2016",
     "Brinck & Maximov 2016, 'The Technical Art of Uncharted 4', as Unity-Technologies/Graphics "
     "1c0bbd507c6d com.unity.render-pipelines.core/ShaderLibrary/CommonLighting.hlsl "
     "ComputeMicroShadowing",
     "saturate(<Ns,wi> + 2 V^2 - 1) on every lobe, V the height field's ambient visibility "
     "(opacity 1)",
     {},
     MethodKind::kFactor,
     NormalAdjustment::kNone,
     FactorLobes::kAll,
     false,
     true,
     "",
     "",
     true},
    {TerminatorMethod::kFitted,
     "fitted",
     "Penumbra's `penumbra fit`: a table of G fitted to the displaced ground truth "
     "(docs/achievable.md)",
     "G(theta_i, delta) from /terminator/parameters/table (the table.json of penumbra fit), "
     "multilinear between the cells' centres, 1 outside the table's grid",
     {},
     MethodKind::kFactor,
     NormalAdjustment::kNone,
     FactorLobes::kScene,
     false,
     false,
     "G where Ns == Ng is the table's value at deviation 0, which a fit need not make 1",
     "",
     false,
     false,
     true},
    {TerminatorMethod::kPython,
     "python",
     "a user's function registered from Python with @penumbra.method (docs/python.md); "
     "scenes and studies name it by its own id",
     "G(cos_light, cos_deviation, cos_shading, cos_view, parameters) from the user's vectorised "
     "function, called on batches of samples",
     {},
     MethodKind::kFactor,
     NormalAdjustment::kNone,
     FactorLobes::kScene,
     false,
     false,
     "G where Ns == Ng is whatever the user's function returns there",
     "",
     false,
     false,
     false,
     true},
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
  if (find_user_method(id)) return TerminatorMethod::kPython;
  return std::nullopt;
}

std::string_view method_id(const MethodSettings& settings) {
  if (settings.method == TerminatorMethod::kPython && settings.user) return settings.user->id;
  return method_info(settings.method).id;
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

double cycles34_chiang(const Vec3& ni, const Vec3& ns, const Vec3& wi) {
  const double cos_ns_wi = dot(ns, wi);
  const Vec3 n = cos_ns_wi < 0.0 ? -ni : ni;
  const double denominator = cos_ns_wi * dot(n, ns);
  // Cycles' safe_divide: 0 for a zero denominator.
  const double g = denominator != 0.0 ? dot(n, wi) / denominator : 0.0;
  if (g >= 1.0) return 1.0;
  if (!(g >= 0.0)) return 0.0;
  return chiang2019_smooth(g);
}

double cycles45_conty(const Vec3& ni, const Vec3& ns, const Vec3& wi) {
  const double cos_ni_wi = dot(ni, wi), cos_ni_ns = dot(ni, ns);
  if (cos_ni_wi * cos_ni_ns * dot(ns, wi) < 0.0) return 0.0;
  const double cos_i = std::abs(cos_ni_wi), cos_d = std::abs(cos_ni_ns);
  if (cos_d >= 1.0 || cos_i >= 1.0) return 1.0;
  if (cos_i < 1e-6) return 0.0;
  const double alpha2 = clamp01(0.125 * (1.0 / (cos_d * cos_d) - 1.0));
  const double tan2_i = std::max(1.0 / (cos_i * cos_i) - 1.0, 0.0);
  return 2.0 / (1.0 + std::sqrt(1.0 + alpha2 * tan2_i));
}

double mitsuba3_conty(const Vec3& ni, const Vec3& ns, const Vec3& wi) {
  auto tan2 = [&](const Vec3& v) {
    const double z = dot(ni, v);
    return std::max(1.0 - z * z, 0.0) / (z * z);
  };
  const double alpha2 = std::min(0.125 * tan2(ns), 1.0);
  const double product = alpha2 * tan2(wi);
  // Mitsuba gives NaN for 0 * inf (Ns == Ni, wi on the horizon); the limit
  // along Ns -> Ni is 1.
  if (std::isnan(product)) return 1.0;
  return clamp01(2.0 / (1.0 + std::sqrt(1.0 + product)));
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

double microshadow_chan2018(double cos_theta, double visibility) {
  const double c = clamp01(cos_theta);
  // Filament's inversesqrt(1 - V) is infinite at V = 1: no occlusion.
  if (!(visibility < 1.0)) return c > 0.0 ? 1.0 : 0.0;
  const double g = clamp01(c / std::sqrt(1.0 - std::max(visibility, 0.0)));
  return g * g;
}

double microshadow_brinck2016(double cos_theta, double visibility) {
  const double v = clamp01(visibility);
  return clamp01(cos_theta + 2.0 * v * v - 1.0);
}

double microshadow_chan2018(double cos_theta, double visibility, double p) {
  const double c = clamp01(cos_theta);
  if (!(visibility < 1.0)) return c > 0.0 ? 1.0 : 0.0;
  return std::pow(clamp01(c / std::sqrt(1.0 - std::max(visibility, 0.0))), p);
}

double microshadow_brinck2016(double cos_theta, double visibility, double q) {
  return clamp01(cos_theta + 2.0 * std::pow(clamp01(visibility), q) - 1.0);
}

void shading_offsets(std::span<const double> s, const Vec3& ns, const Vec3& wi, double* out) {
  const double cos_theta = std::min(dot(ns, wi), 1.0);
  const double theta = cos_theta > 0.0 ? std::acos(cos_theta) : 0.0;
  // The least double above pi/2: cos(f theta) <= 0 from it to f theta = pi
  // (f <= 2, theta <= pi/2), so max(cos, 0) is 0 without the cosine.
  constexpr double kAboveHalfPi = 1.5707963267948968;
  for (std::size_t k = 0; k < s.size(); ++k) {
    const double f = shading_offset_frequency(s[k]);
    if (f == 1.0)
      out[k] = 1.0;
    else if (!(cos_theta > 0.0) || f * theta >= kAboveHalfPi)
      out[k] = 0.0;
    else
      out[k] = clamp01(std::max(std::cos(f * theta), 0.0) / cos_theta);
  }
}

namespace {

// x^e[k] for each k of an ascending list (see microshadow_chan2018_exponents).
void powers(double x, std::span<const double> e, double* out) {
  for (std::size_t k = 0; k < e.size(); ++k)
    out[k] = k >= 4 && e[k] == 2.0 * e[k - 4] ? out[k - 4] * out[k - 4] : std::pow(x, e[k]);
}

}  // namespace

void microshadow_chan2018_exponents(double cos_theta, double visibility, std::span<const double> p,
                                    double* out) {
  const double c = clamp01(cos_theta);
  if (!(visibility < 1.0)) {
    std::fill(out, out + p.size(), c > 0.0 ? 1.0 : 0.0);
    return;
  }
  powers(clamp01(c / std::sqrt(1.0 - std::max(visibility, 0.0))), p, out);
}

void microshadow_brinck2016_exponents(double cos_theta, double visibility,
                                      std::span<const double> q, double* out) {
  powers(clamp01(visibility), q, out);
  for (std::size_t k = 0; k < q.size(); ++k) out[k] = clamp01(cos_theta + 2.0 * out[k] - 1.0);
}

// The vectors come by reference, not in a ShadingVectors: shade() would
// copy them out of a ShadingPoint its caller has just written, and those
// wider loads stall on the narrower stores (a fifth of a bump render).
double terminator_factor(const MethodSettings& settings, const Vec3& ng, const Vec3& ns,
                         const Vec3& wi, const Vec3& wo, double visibility) {
  switch (settings.method) {
    case TerminatorMethod::kNone:
      return 1.0;
    case TerminatorMethod::kChiang2019:
      return chiang2019(ng, ns, wi);
    case TerminatorMethod::kChiang2019Sine:
      return chiang2019_sine(ng, ns, wi);
    case TerminatorMethod::kEstevez2019:
      return estevez2019(ng, ns, wi);
    case TerminatorMethod::kEstevez2019Reciprocal: {
      const double alpha2 = estevez2019_alpha2(ng, ns);
      return estevez2019_g1(ng, wi, alpha2) * estevez2019_g1(ng, wo, alpha2);
    }
    case TerminatorMethod::kDeshmukh2020:
      return deshmukh2020(ng, ns, wi);
    case TerminatorMethod::kShadingOffset:
      return shading_offset(settings.shading_offset, ns, wi);
    case TerminatorMethod::kCycles34:
      return cycles34_chiang(ng, ns, wi);
    case TerminatorMethod::kCycles45:
    case TerminatorMethod::kCycles50:
      return cycles45_conty(ng, ns, wi);
    case TerminatorMethod::kMitsuba3:
      return mitsuba3_conty(ng, ns, wi);
    case TerminatorMethod::kCycles50NoCorrection:
    case TerminatorMethod::kMitsuba3Flip:
    case TerminatorMethod::kIray2017:
    case TerminatorMethod::kUnityHdrp:
    case TerminatorMethod::kFalcor:
    case TerminatorMethod::kOspray:
    case TerminatorMethod::kSchuessler2017:
    case TerminatorMethod::kSchuessler2017Shadowing:
    case TerminatorMethod::kSchuessler2017Walk:
      return 1.0;
    case TerminatorMethod::kMicroshadowChan2018:
      return microshadow_chan2018(dot(ns, wi), visibility);
    case TerminatorMethod::kMicroshadowBrinck2016:
      return microshadow_brinck2016(dot(ns, wi), visibility);
    case TerminatorMethod::kFitted:
      return settings.table ? settings.table->at(factor_inputs(ng, ns, wi, wo)) : 1.0;
    case TerminatorMethod::kPython:
      return 1.0;
  }
  return 1.0;
}

}  // namespace penumbra
