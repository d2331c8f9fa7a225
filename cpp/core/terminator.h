// Bump-terminator shadowing factors: one enum, one table, one switch.
//
// A method is what users type in /terminator/method and in a study's
// "methods". Most are factors: pure functions of the unit vectors at a
// shading point with a value in [0,1] that multiplies the light's
// contribution (BSDF value times the cosine against Ns) of the lobes it is
// applied to. Some bring a normal adjustment (normal_adjust.h) as their
// renderer ships it, and the microfacet models (Schuessler et al. 2017)
// replace the BSDF; shading.cpp composes them. Sources: the publication
// (or renderer commit) in each row's `source`, cited in full in
// docs/methods.md and CITATION.cff (e.g. Chiang, Li, Burley 2019, "Taming
// the Shadow Terminator", SIGGRAPH Talks; Conty Estevez, Lecocq, Stein 2019,
// Ray Tracing Gems ch. 12). Adding a method: docs/extending.md lists every
// place to touch (the enum and table here, the switches in terminator.cpp
// and shading.cpp, the scene reader for a parameter, the tests, the studies).
#pragma once

#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "core/factor_table.h"
#include "core/normal_adjust.h"
#include "core/user_method.h"
#include "core/vec.h"

namespace penumbra {

enum class TerminatorMethod {
  kNone,
  kChiang2019,
  kChiang2019Sine,
  kEstevez2019,
  kEstevez2019Reciprocal,
  kDeshmukh2020,
  kShadingOffset,
  kCycles34,
  kCycles45,
  kCycles50,
  kCycles50NoCorrection,
  kMitsuba3,
  kMitsuba3Flip,
  kIray2017,
  kUnityHdrp,
  kFalcor,
  kOspray,
  kSchuessler2017,
  kSchuessler2017Shadowing,
  kSchuessler2017Walk,
  kMicroshadowChan2018,
  kMicroshadowBrinck2016,
  kFitted,
  kPython,
};

// How a method acts: a factor on the lobes' contribution, a factor plus the
// normal adjustment its renderer applies, an adjustment alone, or a
// microfacet model that replaces the BSDF.
enum class MethodKind { kFactor, kFactorAndAdjustment, kAdjustment, kMicrofacet };

// The lobes a factor scales: the scene's /terminator/lobes, or fixed by the
// renderer the method reproduces (Cycles: diffuse closures; Mitsuba 3: the
// whole nested BSDF).
enum class FactorLobes { kScene, kDiffuse, kAll };

// A scalar parameter of a method, documented where it is declared.
struct MethodParameter {
  std::string_view name;
  std::string_view unit;
  double min_value;
  double max_value;
  double default_value;
  std::string_view description;
};

struct MethodInfo {
  TerminatorMethod method;
  std::string_view id;  // what users type; matches the reference sheet
  std::string_view source;
  std::string_view summary;
  std::span<const MethodParameter> parameters;
  MethodKind kind;
  // The adjustment the method brings (kNone for plain factors and models).
  NormalAdjustment adjustment;
  FactorLobes lobes;
  // The renderer's own reference normal is the smooth Ni (Cycles, Mitsuba
  // 3); false: the scene's /terminator/reference_normal decides.
  bool reference_is_ni;
  // False for methods that change shading even where Ns == Ng (the
  // reference formulas do so by design); tests and docs rely on this flag.
  bool identity_without_deviation;
  std::string_view identity_note;
  // Why the literature rejects the method ("" if it does not): reports keep
  // it in their tables but label it.
  std::string_view rejected = {};
  // The factor needs the height field's ambient visibility (micro-shadowing);
  // the evaluator computes it only for these methods.
  bool needs_visibility = false;
  // Shading draws random numbers from the pixel's stream (a stochastic
  // model): its samples cannot be shared with other methods' renders
  // (evaluator/evaluator.h, render_methods).
  bool draws_random = false;
  // The factor is a table read from a file (/terminator/parameters/table,
  // the table.json that `penumbra fit` writes): a study or bench that takes
  // every method leaves it out unless a table is given.
  bool needs_table = false;
  // The row that stands for the user methods (core/user_method.h): a scene
  // names one by its own id; a study takes none unless it names it.
  bool user_defined = false;
};

std::span<const MethodInfo> all_methods();
const MethodInfo& method_info(TerminatorMethod method);
std::optional<TerminatorMethod> method_from_id(std::string_view id);

// A method with its parameter values.
struct MethodSettings {
  TerminatorMethod method = TerminatorMethod::kNone;
  double shading_offset = 0.0;  // shading-offset `s`, dimensionless, [0,1]
  // fitted: G over (light, deviation, ...) angles, multilinear between the
  // cells' centres (core/factor_table.h), with its content digest.
  std::shared_ptr<const FactorTable> table = nullptr;
  // python: the user's method and its parameters' values, in the order of
  // its `parameters`. Its factor is evaluated in batches by the evaluator
  // (evaluator.h, render_methods), never by terminator_factor.
  std::shared_ptr<const UserMethod> user = nullptr;
  std::vector<double> user_values = {};
};

// The id a method is named by: the user method's own for `python`.
std::string_view method_id(const MethodSettings& settings);

// Unit vectors at a shading point, all in the same space.
//   ng: reference normal of the factor (Ng or Ni, the caller's choice)
//   ns: shading normal after bump
//   wi: towards the light;  wo: towards the viewer
struct ShadingVectors {
  Vec3 ng, ns, wi, wo;
};

// The factor multiplied into the affected lobes' contribution, in [0,1]
// (fitted: in the table's range, which may exceed 1 where raw bump is too
// dark). Finite for every finite unit input, degenerate ones included. 1 for the
// adjustment-only methods and for `python` (evaluated in batches instead); the microfacet models
// have no factor (1 here; shading.cpp evaluates them). `visibility`: the height field's ambient
// visibility at the point, in [0,1] (core/height.h); only the micro-shadowing methods read it.
double terminator_factor(const MethodSettings& settings, const Vec3& ng, const Vec3& ns,
                         const Vec3& wi, const Vec3& wo, double visibility = 1.0);
inline double terminator_factor(const MethodSettings& settings, const ShadingVectors& v,
                                double visibility = 1.0) {
  return terminator_factor(settings, v.ng, v.ns, v.wi, v.wo, visibility);
}

// The individual formulas, exposed for tests, contour plots and benchmarks.
// Each takes unit vectors and returns a value in [0,1].
double chiang2019_raw_g(const Vec3& ng, const Vec3& ns, const Vec3& wi);  // eq. (1)
double chiang2019_smooth(double g);                                       // eq. (2)
double chiang2019(const Vec3& ng, const Vec3& ns, const Vec3& wi);
double chiang2019_sine(const Vec3& ng, const Vec3& ns, const Vec3& wi);
double estevez2019_alpha2(const Vec3& ng, const Vec3& ns);
double estevez2019_g1(const Vec3& ng, const Vec3& w, double alpha2);
double estevez2019(const Vec3& ng, const Vec3& ns, const Vec3& wi);
double deshmukh2020(const Vec3& ng, const Vec3& ns, const Vec3& wi);
// Cycles' bump_shadowing_term against the smooth normal ni: Blender 3.4's
// Chiang form and the Conty form of 4.5+ (with its hemisphere test).
double cycles34_chiang(const Vec3& ni, const Vec3& ns, const Vec3& wi);
double cycles45_conty(const Vec3& ni, const Vec3& ns, const Vec3& wi);
// Micro-shadowing from an ambient visibility (1 - occlusion) and
// cos_theta = <Ns,wi>: Chan 2018 as Filament computes it,
// saturate(cos / sqrt(1 - visibility))^2, and Brinck & Maximov 2016 as
// Unity's SRP Core does, saturate(cos + 2 visibility^2 - 1).
double microshadow_chan2018(double cos_theta, double visibility);
double microshadow_brinck2016(double cos_theta, double visibility);
// The same with an exponent free, for `penumbra fit` to refit: Chan's
// saturate(cos / sqrt(1 - V))^p (published p = 2, the square) and Brinck's
// saturate(cos + 2 V^q - 1) (published q = 2, the square of V). Both keep
// the published ends: no occlusion at V = 1, all of it at V = 0.
double microshadow_chan2018(double cos_theta, double visibility, double p);
double microshadow_brinck2016(double cos_theta, double visibility, double q);
// The same at every value of an ascending list, for `penumbra fit`'s probes
// (out[k] at values[k]). shading_offsets gives shading_offset's bits: the
// angle once, and no cosine once f theta passes pi/2, where every larger s
// gives 0 too. The exponents' forms take x^(2a) as (x^a)^2 where the list
// holds a four places earlier (its quarter octaves), a fifth of the pow
// calls: at the published 2 the published factors' bits (x * x; glibc's
// pow(x, 2) can differ from it by an ulp), elsewhere within 33 ulp of pow.
void shading_offsets(std::span<const double> s, const Vec3& ns, const Vec3& wi, double* out);
void microshadow_chan2018_exponents(double cos_theta, double visibility, std::span<const double> p,
                                    double* out);
void microshadow_brinck2016_exponents(double cos_theta, double visibility,
                                      std::span<const double> q, double* out);
// Mitsuba 3's eval_shadow_terminator against the unperturbed frame ni.
double mitsuba3_conty(const Vec3& ni, const Vec3& ns, const Vec3& wi);
// Cycles' UI mapping of the shading-offset slider s to a frequency.
double shading_offset_frequency(double s);
double shading_offset(double s, const Vec3& ns, const Vec3& wi);

}  // namespace penumbra
