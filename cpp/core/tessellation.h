// Low-poly tessellations of the analytic shapes: what a modeller exports and a
// production renderer traces with smooth shading. Vertices lie on the exact
// surface and carry its exact normal; the triangles between them are flat,
// which is what makes the smooth-shading terminator (shadow_origin.h).
#pragma once

#include "core/enum_names.h"
#include "core/grid_mesh.h"
#include "core/shape.h"

namespace penumbra {

enum class TessellationScheme {
  kUv,         // cylinder: segments x rings grid (+ cap fans); sphere: UV sphere
  kIcosphere,  // sphere only: geodesic subdivision of the icosahedron
};
inline constexpr EnumName<TessellationScheme> kTessellationSchemeNames[] = {
    {"uv", TessellationScheme::kUv}, {"icosphere", TessellationScheme::kIcosphere}};

enum class NormalShading {
  kSmooth,  // shading normal Ni interpolated from the vertex normals
  kFlat,    // shading normal = the triangle's Ng
  // Ni bent towards the view so that mirror reflections stay above the
  // triangle (Reshetov et al. 2010, core/consistent_normal.h)
  kConsistent,
};
inline constexpr EnumName<NormalShading> kNormalShadingNames[] = {
    {"smooth", NormalShading::kSmooth},
    {"flat", NormalShading::kFlat},
    {"consistent", NormalShading::kConsistent}};

struct Tessellation {
  TessellationScheme scheme = TessellationScheme::kUv;
  unsigned segments = 16;  // uv: segments around the axis, [3, 65536]
  // uv: segments along the cylinder side or from pole to pole, [1, 65536]
  // (sphere: >= 2); 0 asks for the default: cylinder 1 (the side is straight
  // along the axis, so one row is exact), sphere segments / 2.
  unsigned rings = 0;
  unsigned frequency =
      1;  // icosphere: each icosahedron edge in `frequency` parts, 20 f^2 triangles
  NormalShading shading = NormalShading::kSmooth;
  // Phong tessellation (Boubekeur and Alexa 2008) of the mesh above: each
  // triangle split into phong_level^2 on a barycentric lattice whose points
  // move onto the triangle's Phong surface with shape factor phong_alpha.
  // 1: the flat mesh. [1, 64]; alpha [0, 1], 3/4 as the paper recommends.
  unsigned phong_level = 1;
  double phong_alpha = 0.75;
};

// The grid of a uv tessellation, defaults resolved.
GridResolution uv_resolution(const Shape& shape, const Tessellation& t);

// Number of triangles tessellate() makes, without making them.
std::size_t tessellated_triangle_count(const Shape& shape, const Tessellation& t);

// The mesh; its normals are the exact surface normals at the vertices (flat
// shading ignores them), or with phong_level > 1 the Phong-refined mesh
// (phong_refine). Cylinder caps keep their own rim vertices. Shape must
// carry its frame (with_frame).
TriangleMesh tessellate(const Shape& shape, const Tessellation& t);

// Boubekeur and Alexa, "Phong Tessellation", ACM TOG 27(5), SIGGRAPH Asia
// 2008: each triangle of `mesh` split into level^2 on a barycentric lattice,
// each lattice point moved to (1 - alpha) P + alpha sum b_k pi_k(P) (pi_k
// the projection onto vertex k's tangent plane, as phong2008_origin in
// shadow_origin.h) with the normal sum b_k n_k normalised. A point on an
// edge depends on that edge's two vertices alone, so triangles that share
// the edge share the point: the refined mesh is watertight where the mesh
// is. Triangles keep their order (side triangles first).
TriangleMesh phong_refine(const TriangleMesh& mesh, unsigned level, double alpha);

}  // namespace penumbra
