// Bump-terminator shadowing factors: one enum, one table, one switch.
//
// Every method is a pure function of the unit vectors at a shading point and
// returns a factor in [0,1] that multiplies the light's contribution (BSDF
// value times the cosine against Ns) of the lobes it is applied to. Formulas
// and sources: shared/reference/terminator-methods.md, section 1.
// Adding a method touches this header's enum and table and the switch in
// terminator.cpp, nothing else.
#pragma once

#include <optional>
#include <span>
#include <string_view>

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
};

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
  // False for methods that change shading even where Ns == Ng (the
  // reference formulas do so by design); tests and docs rely on this flag.
  bool identity_without_deviation;
  std::string_view identity_note;
  // Why the literature rejects the method ("" if it does not): reports keep
  // it in their tables but label it.
  std::string_view rejected = {};
};

std::span<const MethodInfo> all_methods();
const MethodInfo& method_info(TerminatorMethod method);
std::optional<TerminatorMethod> method_from_id(std::string_view id);

// A method with its parameter values (only shading-offset has one so far).
struct MethodSettings {
  TerminatorMethod method = TerminatorMethod::kNone;
  double shading_offset = 0.0;  // shading-offset `s`, dimensionless, [0,1]
};

// Unit vectors at a shading point, all in the same space.
//   ng: reference normal of the factor (Ng or Ni, the caller's choice)
//   ns: shading normal after bump
//   wi: towards the light;  wo: towards the viewer
struct ShadingVectors {
  Vec3 ng, ns, wi, wo;
};

// The factor multiplied into the affected lobes' contribution, in [0,1].
// Finite for every finite unit input, degenerate ones included.
double terminator_factor(const MethodSettings& settings, const ShadingVectors& v);

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
// Cycles' UI mapping of the shading-offset slider s to a frequency.
double shading_offset_frequency(double s);
double shading_offset(double s, const Vec3& ns, const Vec3& wi);

}  // namespace penumbra
