// A triangle mesh as a base surface: a user's asset read from a file
// (scene/mesh_file.h), smooth-shaded by its vertex normals. The bump and
// the ground truth treat it as the analytic shapes are treated, with the
// interpolated normal Ni in the role of the base normal N:
//   base point   P(b) = sum b_k v_k on the flat triangle (barycentrics b),
//   base normal  Ni(b) = m / |m|, m = sum b_k n_k,
//   truth        P'(b) = P + A h(P) Ni(b), the flat triangles subdivided and
//                displaced along Ni (Cycles' "simple" subdivision), so the
//                truth keeps the mesh's facets, as a displaced low-poly
//                asset does in a production renderer.
// Pure math: the scene layer reads the files.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/grid_mesh.h"
#include "core/height.h"
#include "core/shape.h"

namespace penumbra {

struct MeshSurface {
  // Positions after the scene's transform (scene units), unit vertex
  // normals, triangles; side_triangles = the triangle count.
  TriangleMesh mesh;
  // Content digest (hex) of the arrays above: what identifies the mesh in
  // cache keys and mesh keys, wherever its file lies.
  std::string digest;
  std::string file;  // where it was read from, for messages
  Vec3 bounds_min, bounds_max;
};

// The centre and radius of the bounding box's circumscribed sphere: the
// size scale a mesh shape's epsilons and default edge length use.
Vec3 mesh_centre(const MeshSurface& m);
double mesh_radius(const MeshSurface& m);

// Fills bounds_* from the positions.
void measure_mesh(MeshSurface* m);

// The base geometry at barycentrics b of triangle `triangle`: p = P(b),
// n = Ni(b), t1 x t2 = n, curvatures 0 (the bump sees the interpolated
// normal as a smooth surface without the curvature terms, which are of
// relative size A h kappa against 1; the truth's normal has them exactly,
// mesh_displaced_normal). u, v stay 0.
SurfaceGeometry mesh_surface_at(const TriangleMesh& mesh, std::uint32_t triangle,
                                const double b[3]);

// The exact normal of the truth P'(b) at b, on Ni's side:
//   dP'/db_j = (v_j - v_0) + A <grad h, v_j - v_0> Ni + A h (I - Ni Ni^T)(n_j - n_0) / |m|
// (j = 1, 2), Ns = normalize(dP'/db_1 x dP'/db_2).
Vec3 mesh_displaced_normal(const TriangleMesh& mesh, std::uint32_t triangle, const double b[3],
                           double amplitude, const HeightSample& h);

// How the truth splits each triangle, adaptive to an edge length e: every
// edge into n_e = ceil(length / e) parts (at least 1), computed from the
// edge alone so that the two triangles that share it split it alike; a
// triangle's lattice at level n_t = the largest of its edges' n_e, its
// lattice points on an edge moved to the nearest of that edge's n_e + 1
// points. The displaced mesh is then watertight wherever the file shares
// its vertices (a lattice triangle squeezed onto an edge has zero area and
// is never hit).
struct MeshSubdivision {
  std::vector<std::uint32_t> levels;       // n_t per triangle
  std::vector<std::uint32_t> edge_levels;  // 3 per triangle: edges v0v1, v1v2, v2v0
  std::vector<std::uint64_t> first;        // first sub-triangle of each triangle; T + 1 entries
  // Per triangle: its longest sub-triangle edge (scene units, before
  // displacement), bounded by twice its longest edge over its level.
  std::vector<float> sub_edges;
  std::uint64_t triangle_count() const { return first.empty() ? 0 : first.back(); }
};
inline constexpr std::uint32_t kMaxSubdivisionLevel = 65535;
MeshSubdivision plan_subdivision(const TriangleMesh& mesh, double edge);

// How fast Ni turns on `triangle`: the largest angle between two of its
// vertex normals over their distance (radians per scene unit).
double normal_curvature(const TriangleMesh& mesh, std::uint32_t triangle);

// The sub-triangle `prim` of the truth and barycentrics (b1, b2) in it:
// the base triangle and the barycentrics there.
void locate_in_base(const MeshSubdivision& plan, std::uint64_t prim, double b1, double b2,
                    std::uint32_t* base, double b[3]);

// The truth's mesh: every lattice point displaced to P + A h(P) Ni (a point
// on an edge computed from that edge's two vertices in one order, so both
// triangles get its bits), triangle t's sub-triangles at plan.first[t]
// onwards, row by row of its lattice. No normals.
TriangleMesh subdivide_displaced(const TriangleMesh& base, const MeshSubdivision& plan,
                                 const HeightFunction& height, double amplitude);

// The truth's mesh as another renderer is given it (POV-Ray's mesh2,
// Cycles): subdivide_displaced's triangles, but each base triangle with
// vertices of its own, their normals the exact normal of the truth there
// (mesh_displaced_normal), so that the base mesh's facets stay creases as
// the evaluator shades them. A vertex on a base edge keeps the position
// bits its neighbour's copy has, so the surface stays watertight; lattice
// triangles squeezed onto an edge (zero area) are left out.
TriangleMesh displaced_mesh_for_export(const TriangleMesh& base, const MeshSubdivision& plan,
                                       const HeightFunction& height, double amplitude);

}  // namespace penumbra
