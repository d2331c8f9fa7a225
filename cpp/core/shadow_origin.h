// Smooth-shading (low-poly) terminator: where a shadow ray leaves a triangle.
//
// A smooth-shaded mesh's vertex normals describe a curved surface that its flat
// triangles do not have; shadow rays leaving the flat triangle hit the
// neighbouring triangles and the lit area ends in a stair-stepped line. Each
// method below moves the shadow-ray origin off the triangle. One enum, one
// table, one switch (shadow_ray_origin in shadow_origin.cpp); sources: the
// pixnblox gist (2020), Hanika 2021 ("Hacking the Shadow Terminator", Ray
// Tracing Gems II ch. 4) and Cycles' Geometry Offset, as cited in the table
// and in docs/lowpoly.md.
//
// Orientation: every vector is given on the side being shaded. A caller that
// hits a triangle from its back flips Ng, Ns and the vertex normals before
// calling, except for cycles-geometry-offset, which reproduces Cycles' own
// handling of back faces and therefore takes the vertex normals as stored
// (see CyclesTriangle below).
#pragma once

#include <optional>
#include <span>
#include <string_view>

#include "core/terminator.h"
#include "core/vec.h"

namespace penumbra {

enum class OffsetMethod {
  kNone,
  kEpsilon,
  kGist2020,
  kHanika2021,
  kCyclesGeometryOffset,
  kOspray,
  kPhong2008,
};

struct OffsetMethodInfo {
  OffsetMethod method;
  std::string_view id;  // what users type; matches the reference sheet
  std::string_view source;
  std::string_view summary;
  std::span<const MethodParameter> parameters;
};

std::span<const OffsetMethodInfo> all_offset_methods();
const OffsetMethodInfo& offset_method_info(OffsetMethod method);
std::optional<OffsetMethod> offset_method_from_id(std::string_view id);

// A method with its parameter values.
struct OffsetSettings {
  OffsetMethod method = OffsetMethod::kNone;
  double epsilon = 0.01;  // epsilon: distance along Ng, scene units, (0, 1e3]
  double cutoff = 0.1;    // cycles-geometry-offset: Cycles' "Geometry Offset", [0, 1]
  // ospray: the epsilon relative to the coordinates' magnitude, OSPRay's
  // ulpEpsilon 0x1.0fp-21 (modules/cpu/common/DifferentialGeometry.ih).
  double ulp = 0x1.0fp-21;
  // phong2008: Phong tessellation's shape factor alpha, [0, 1]; Boubekeur
  // and Alexa recommend 3/4.
  double alpha = 0.75;
};

// The member of `settings` that holds its method's one parameter (the
// table's `parameters`, in the same units), nullptr for a method without
// one: the one place that maps a parameter's name to its field.
double* offset_parameter(OffsetSettings* settings);
const double* offset_parameter(const OffsetSettings& settings);

// The triangle under a hit. Vertex normals are unit length and oriented to
// the shaded side (flipped with Ng when the triangle is seen from its back).
// b[k] are the barycentric weights of v[k] (b0 + b1 + b2 = 1).
struct ShadingTriangle {
  Vec3 v[3];
  Vec3 n[3];
  double b[3];
};

// Everything a method may read at a hit.
//   p:  the hit point on the flat triangle, sum b_k v_k
//   ng: the triangle's geometric normal, on the shaded side
//   ns: the shading normal (Ni, or the bumped Ni), on the shaded side
//   wi: unit direction towards the light
//   backfacing: the triangle was hit from its back (normals were flipped)
struct ShadowQuery {
  ShadingTriangle triangle;
  Vec3 p, ng, ns, wi;
  bool backfacing = false;
};

struct ShadowOrigin {
  Vec3 origin;
  // The shadow ray ignores the triangle it leaves. True when the origin is
  // the hit point itself (the triangle cannot shadow a point on its own
  // plane); after an offset only while the light is above the triangle,
  // since a lifted point with the light below its triangle is meant to be
  // shadowed by it (Cycles' rule, kept for every method).
  bool skip_self = true;
};

ShadowOrigin shadow_ray_origin(const OffsetSettings& settings, const ShadowQuery& query);

// The individual formulas, exposed for tests and benchmarks.
//
// gist2020: p_k = P - dot(P - v_k, n_k) n_k, S = sum b_k p_k; S where
// dot(S - P, Ns) > 0 (the patch is convex), else P.
Vec3 gist2020_origin(const ShadingTriangle& t, const Vec3& p, const Vec3& ns);
// hanika2021: P' = P - sum b_k min(0, dot(P - v_k, n_k)) n_k. Lifts P only
// towards tangent planes it lies below, so points on a shared edge get the
// same lift from both triangles (crack-free), and concave patches none.
Vec3 hanika2021_origin(const ShadingTriangle& t, const Vec3& p);
// phong2008 (Boubekeur and Alexa, "Phong Tessellation", ACM TOG 27(5),
// SIGGRAPH Asia 2008, eq. 3 and 4): the point of the Phong surface over P,
// p* = (1 - alpha) P + alpha sum b_k pi_k(P), pi_k(P) = P - <P - v_k, n_k> n_k
// the projection onto vertex k's tangent plane. alpha = 1 is gist2020's
// point without its convexity test.
Vec3 phong2008_origin(const ShadingTriangle& t, const Vec3& p, double alpha);

// ospray (RenderKit/ospray 675c216b91a7): postIntersect lifts P by epsilon
// along the viewer's Ng (common/World.ih), and next-event estimation moves
// the origin back by 2 epsilon where <Ng,wi> < 0 (render/pathtracer/
// NextEventEstimation.ispc): P + epsilon Ng for a light on Ng's side,
// P - epsilon Ng below. epsilon = ulp * the largest coordinate magnitude of
// the triangle's vertices and of P (geometry/Mesh.ispc calcEpsilon and
// common/DifferentialGeometry.ih calcEpsilon without the hit distance).
double ospray_epsilon(const ShadingTriangle& t, const Vec3& p, double ulp);
Vec3 ospray_origin(const Vec3& p, const Vec3& ng, const Vec3& wi, double epsilon);

// Cycles 3.x (kernel/light/sample.h, shadow_ray_smooth_surface_offset):
// vertices and normals as stored in the mesh (not flipped), u and v the
// weights of v[0] and v[1], Ng the geometric normal after Cycles' flips.
struct CyclesTriangle {
  Vec3 v[3];
  Vec3 n[3];
  double u = 0.0, v_weight = 0.0;
};
// The offset vector n * h of the parabolic surface through the three
// vertices, clamped by the per-vertex linear envelope.
Vec3 cycles_smooth_surface_offset(const CyclesTriangle& t, const Vec3& ng);
// The fraction of that offset applied (shadow_ray_offset): 1 for lights close
// to the triangle's horizon, fading to 0 at dot(Ng, wi) = cutoff.
//   nl = |dot(N, wi)|, ngl = dot(Ng', wi) with Ng' on N's side of the light.
double cycles_offset_amount(double cutoff, double nl, double ngl);

}  // namespace penumbra
