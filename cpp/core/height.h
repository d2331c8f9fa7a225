// Height functions h(P) over the base surface, evaluated at the base point P
// (scene units in, dimensionless out, |h| bounded by max_abs_height). Every
// family is a combination of 3D sine gratings, so POV-Ray's function syntax
// and Blender's shader math nodes can express it exactly; gradients are
// analytic. The displaced surface is P' = P + A h(P) N(P) (reference, sec. 5).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "core/enum_names.h"
#include "core/vec.h"

namespace penumbra {

// weight * sin(2 pi dot(k, P) + phase); k in cycles per scene unit.
struct SineTerm {
  Vec3 k;
  double phase = 0.0;   // radians
  double weight = 1.0;  // dimensionless
};

enum class HeightCombine { kSum, kProduct };
inline constexpr EnumName<HeightCombine> kHeightCombineNames[] = {
    {"product", HeightCombine::kProduct}, {"sum", HeightCombine::kSum}};

// A product of more factors than this is refused by the scene layer: the
// evaluator keeps the factors on the stack.
inline constexpr int kMaxProductFactors = 8;

struct HeightFunction {
  std::vector<SineTerm> terms;  // no terms: h = 0
  // kSum: h = sum of terms. kProduct: h = product of sin(...), weights unused
  // (so |h| <= 1 whatever the number of factors).
  HeightCombine combine = HeightCombine::kSum;
};

struct HeightSample {
  double h = 0.0;
  Vec3 gradient;  // 3D gradient of h, per scene unit
};

HeightSample evaluate_height(const HeightFunction& f, const Vec3& p);
// Tight upper bound of |h| over all of space.
double max_abs_height(const HeightFunction& f);
// Upper bound of |grad h| over all of space, per scene unit.
double max_gradient_norm(const HeightFunction& f);
// Upper bound of the Hessian's spectral norm, per scene unit squared.
double max_hessian_norm(const HeightFunction& f);

// Ambient visibility of the displaced height field A h around the base point
// p with base normal n, in [0, 1] (1: nothing occludes): the cosine-weighted
// fraction of the hemisphere above the base plane left open by the
// displaced surface, from the horizon angle in kVisibilityAzimuths
// directions, each searched in kVisibilitySteps steps out to two periods of
// the longest wavelength. It assumes a flat base (the tangent plane at p),
// as an ambient-occlusion map baked from the detail does: the macro
// surface's own curvature is not an occluder.
inline constexpr int kVisibilityAzimuths = 8;
inline constexpr int kVisibilitySteps = 24;
double height_field_visibility(const HeightFunction& f, double amplitude, const Vec3& p,
                               const Vec3& n);

// The families a scene can name.
HeightFunction make_grating(const Vec3& direction, double frequency, double phase);
HeightFunction make_weave(std::span<const Vec3> directions, double frequency,
                          HeightCombine combine);
// `terms` gratings, directions uniform on the sphere, frequencies uniform in
// [frequency_min, frequency_max], phases uniform in [0, 2 pi), each weighted
// 1/sqrt(terms) so that the RMS height does not grow with the term count.
HeightFunction make_noise(int terms, double frequency_min, double frequency_max,
                          std::uint64_t seed);

}  // namespace penumbra
