// Shading-normal adjustments: the second family of bump-terminator fixes.
// One enum, one table, one switch (normal_adjust.cpp), like the factors in
// terminator.h.
//
// A factor scales the light; an adjustment changes Ns itself (or rejects
// the light outright) before the lobes are evaluated. Production renderers
// combine one adjustment with one factor (Mitsuba 3: flip + Conty; Cycles
// 4.5: hemisphere rejection + Conty). Formulas and sources: reference sheet,
// section 1, "Production variants since 2019", and the method table in
// README.md, which cites file and commit for each.
#pragma once

#include <optional>
#include <span>
#include <string_view>

#include "core/vec.h"

namespace penumbra {

enum class NormalAdjustment {
  kNone,
  kCycles34,
  kCyclesGlossy,
  kCycles50,
  kCycles50NoCorrection,
  kMitsuba3Flip,
  kIray2017,
  kUnityHdrp,
  kFalcor,
  kOspray,
};

struct NormalAdjustmentInfo {
  NormalAdjustment adjustment;
  std::string_view id;  // what users type in /terminator/normal_adjustment
  std::string_view source;
  std::string_view summary;
  // Whether the adjustment acts on the diffuse lobe too (false: the glossy
  // lobe only, as Cycles' ensure_valid_specular_reflection).
  bool touches_diffuse;
  // Whether swapping wi and wo leaves the result unchanged; the sources
  // that depend on wo only say so themselves (Falcor).
  bool reciprocal;
};

std::span<const NormalAdjustmentInfo> all_normal_adjustments();
const NormalAdjustmentInfo& normal_adjustment_info(NormalAdjustment adjustment);
std::optional<NormalAdjustment> normal_adjustment_from_id(std::string_view id);

// Unit vectors at a shading point, all in one space and on the viewer's side:
//   ng: the true geometric normal (the triangle's on a mesh)
//   ni: the smooth normal interpolated from vertex normals (== ng on
//       analytic shapes): the unperturbed shading frame of Mitsuba and Cycles
//   ns: the bumped shading normal
//   wi: towards the light; wo: towards the viewer
struct AdjustVectors {
  Vec3 ng, ni, ns, wi, wo;
};

// The shading normals each lobe uses after the adjustment, and whether the
// adjustment rejects the light altogether for that lobe (Cycles 5.0's
// hemisphere test sets a zero factor on every closure).
struct AdjustedNormals {
  Vec3 ns_diffuse, ns_specular;
  bool reject_diffuse = false, reject_specular = false;
};

// Unit normals out for unit, finite vectors in, degenerate ones included.
AdjustedNormals adjust_normal(NormalAdjustment adjustment, const AdjustVectors& v);

// The individual adjustments, exposed for tests. Each returns a unit normal.
// Cycles' ensure_valid_reflection(Ng, I = wo, N = ns) as in Blender 3.4
// (both roots tried, Ng when neither works) and its 3.6+ form
// ensure_valid_specular_reflection (the root picked by the sign of Ix).
Vec3 cycles34_valid_reflection_normal(const Vec3& ng, const Vec3& wo, const Vec3& ns);
Vec3 cycles_valid_specular_normal(const Vec3& ng, const Vec3& wo, const Vec3& ns);
// Cycles' hemisphere test (in bump_shadowing_term since 4.5): true where the
// light must be dropped.
bool cycles_hemisphere_rejects(const Vec3& ni, const Vec3& ns, const Vec3& wi);
// Mitsuba 3's flip_invalid_normals against the unperturbed frame ni: the
// tangential part of ns mirrored when the viewer lies on opposite sides of
// ni and ns.
Vec3 mitsuba3_flipped_normal(const Vec3& ni, const Vec3& ns, const Vec3& wo);
// Mitsuba 3's normal-map plugins drop a light on opposite sides of ni and ns.
bool mitsuba3_rejects(const Vec3& ni, const Vec3& ns, const Vec3& wi);
Vec3 iray2017_bent_normal(const Vec3& ng, const Vec3& ns, const Vec3& wo);
Vec3 unity_hdrp_consistent_normal(const Vec3& ng, const Vec3& ns, const Vec3& wo);
Vec3 falcor_adjusted_normal(const Vec3& ng, const Vec3& ns, const Vec3& wo);
// OSPRay's side test on a sampled direction (PathSampler.ispc,
// sampleDirection): a reflection that ends below Ng is dropped, whatever Ns
// says. Ng faces the viewer; Penumbra's lobes only reflect.
bool ospray_side_test_rejects(const Vec3& ng, const Vec3& wi);

}  // namespace penumbra
