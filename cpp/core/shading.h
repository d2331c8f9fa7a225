// One shading point lit by one light: where the factor methods, the normal
// adjustments and the microfacet models (Schuessler et al. 2017) meet. The
// evaluator and the contour plots call shade() and nothing else, so every
// method is computed in this one place.
#pragma once

#include "core/bsdf.h"
#include "core/enum_names.h"
#include "core/normal_adjust.h"
#include "core/random.h"
#include "core/terminator.h"
#include "core/vec.h"

namespace penumbra {

enum class ReferenceNormal { kGeometric, kInterpolated };
inline constexpr EnumName<ReferenceNormal> kReferenceNormalNames[] = {
    {"Ng", ReferenceNormal::kGeometric}, {"Ni", ReferenceNormal::kInterpolated}};
enum class Lobes { kDiffuse, kAll };
inline constexpr EnumName<Lobes> kLobesNames[] = {{"diffuse", Lobes::kDiffuse},
                                                  {"all", Lobes::kAll}};

// JSON /terminator.
struct TerminatorSettings {
  MethodSettings method;
  // A normal adjustment on top of the method's own (a method may bring one:
  // mitsuba3, cycles45). At most one of the two is not kNone.
  NormalAdjustment normal_adjustment = NormalAdjustment::kNone;
  // Ng or Ni as the factor's reference normal; identical on analytic shapes,
  // different on tessellated meshes.
  ReferenceNormal reference_normal = ReferenceNormal::kGeometric;
  // The lobes a factor scales. The microfacet models replace the whole BSDF
  // and ignore it; each adjustment has its own lobes (normal_adjust.h).
  Lobes lobes = Lobes::kDiffuse;
};

// The adjustment in effect: the method's own, else the scene's.
NormalAdjustment effective_adjustment(const TerminatorSettings& t);

// ng: true geometric normal, on the viewer's side; ni: interpolated smooth
// normal (== ng on analytic shapes); ns: bumped shading normal; wi: towards
// the light; wo: towards the viewer. A ShadingPoint is the AdjustVectors the
// normal adjustments take, so shade() hands them over without a copy.
struct ShadingPoint : AdjustVectors {
  // The height field's ambient visibility (core/height.h), for the
  // micro-shadowing methods; 1 where there is no height field.
  double visibility = 1.0;
};

struct Shaded {
  // Reflected radiance per unit irradiance normal to wi: the lobes' BSDF
  // values (1/sr) times the cosine of the normal that receives the light
  // (Ns for the factors, Ng for the microfacet models, which include the
  // projection themselves). Zero when the light does not contribute.
  double value = 0.0;
  // The method's factor; for adjustments and microfacet models the
  // effective factor value / (raw bump's value), undefined where raw
  // bump's value is zero.
  double factor = 1.0;
  bool factor_defined = true;
};

// rng: used only by the Monte Carlo walk (schuessler2017-walk); may be
// null for every other method.
Shaded shade(const TerminatorSettings& t, const Material& m, const ShadingPoint& p, Pcg32* rng);

// Raw bump: the plain lobes around ns times <ns,wi>, no factor.
double unshadowed_value(const Material& m, const Vec3& ns, const Vec3& wi, const Vec3& wo);

// The part of raw bump's unshadowed_value that a plain factor scales: the
// diffuse lobe's, or every lobe's when the factor applies to all lobes
// (TerminatorSettings::lobes). What the achievable floor's tally splits.
double factor_scaled_value(const Material& m, const Vec3& ns, const Vec3& wi, const Vec3& wo,
                           Lobes lobes);

}  // namespace penumbra
