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
#include "core/surface_map.h"

namespace penumbra {

struct MeshSurface {
  // Positions after the scene's transform (scene units), unit vertex
  // normals, triangles; side_triangles = the triangle count.
  TriangleMesh mesh;
  // Content digest (hex) of the arrays above: what identifies the mesh in
  // cache keys and mesh keys, wherever its file lies.
  std::string digest;
  std::string file;  // where it was read from, for messages
  // The normal texture its materials name (glTF normalTexture, an OBJ
  // material's `norm`), a path; empty with the reason in
  // normal_texture_why_not when they name none, several, or one Penumbra
  // cannot read (embedded, or over another UV set).
  std::string normal_texture, normal_texture_why_not;
  Vec3 bounds_min, bounds_max;
  // The file's first texture coordinates per corner (u, v; 6 per triangle;
  // v up, as OBJ, Blender and Assimp's glTF reader give them), empty when it
  // has none. Per corner, not per vertex: a UV seam gives one welded vertex
  // two coordinates without splitting the surface.
  std::vector<float> uvs;
  // The MikkTSpace tangent of each corner (x, y, z, bitangent sign; 12 per
  // triangle), mikktspace_tangents of the arrays above; empty without uvs.
  std::vector<float> tangents;
  bool has_uvs() const { return !uvs.empty(); }
};

// Tangents by Mikkelsen's MikkTSpace (Mikkelsen 2008, "Simulation of
// wrinkled surfaces revisited"), the algorithm of Blender's calc_tangents
// and Cycles' Normal Map node (blender/blender
// intern/mikktspace/mikktspace.hh at 9918488), for triangles wound about
// their normals (a triangle wound against the sum of its vertex normals is
// rewound first, as the Blender export rewinds it for Cycles: MikkTSpace's
// sign, and so the bitangent, assumes a front face):
//  - a MikkTSpace vertex is a welded vertex (position and normal) with one
//    UV's bits;
//  - per triangle, the direction of increasing u (eq. 18),
//    T_f = s_f normalize((t31.v) d1 - (t21.v) d2), s_f = sign of the UV
//    area, computed in float as MikkTSpace does (a nearly collinear UV
//    triangle's area can round to zero or change sign);
//  - groups: the triangles around a vertex reached through shared edges
//    (the first later edge that runs the other way) with one orientation,
//    started in triangle and corner order; a triangle with a zero UV area
//    or direction takes the orientation of the first group that reaches it
//    and adds nothing;
//  - a group's tangent: the sum of its triangles' T_f projected off the
//    corner's normal (as stored, not normalised) and normalised, weighted
//    by the triangle's angle at the vertex in that tangent plane, then
//    normalised; the sign is the group's s_f. A corner no group reaches
//    keeps MikkTSpace's default, (1, 0, 0) and -1.
// Checked against Blender 3.4's own tangents on a real asset
// (Renderers.MikkTSpaceTangentsMatchBlendersOnARealAsset).
std::vector<float> mikktspace_tangents(const TriangleMesh& mesh, const std::vector<float>& uvs);

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
// mesh_displaced_normal). u, v = b1, b2 and triangle = `triangle`: a mesh's
// parameters, from which surface_map.h reads the texture coordinates.
SurfaceGeometry mesh_surface_at(const TriangleMesh& mesh, std::uint32_t triangle,
                                const double b[3]);

// The gradient the bump of a mesh uses, given h's gradient `gradient` at a
// point of a flat triangle of unit normal `ng`, shaded by the unit
// interpolated normal `ni` (<ng, ni> > 0): the vector orthogonal to ni whose
// derivative along every direction in the triangle's plane is h's,
//   g' = g_t - ng <g_t, ni> / <ng, ni>,  g_t = g - ng <g, ng>.
// h is only defined on the triangle, so its derivative along ng must not
// count, and the truth P + A h Ni tilts the facet by exactly these
// derivatives: to first order in A, dP'/db_1 x dP'/db_2 = e1 x e2 - A s and
// Ni - A g' = (det Ni - A s) / det with s = <g, e1> (e2 x Ni) + <g, e2>
// (Ni x e1), det = <e1 x e2, Ni>, so the bump turns Ni by the displacement's
// own turn of the facet. Cycles' Bump node computes the same from its
// differentials on the triangle (blender/blender
// intern/cycles/kernel/svm/displace.h, svm_node_set_bump: Rx = dPdy x N,
// Ry = N x dPdx, surfgrad / det). Projecting g onto the plane normal to ni
// instead differs by up to A |g| sin(delta) tan(delta), delta the angle
// between ng and ni.
Vec3 facet_bump_gradient(const Vec3& gradient, const Vec3& ng, const Vec3& ni);

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

// What displaces a mesh: the analytic function of P, or a height map laid
// over the mesh's UVs (the surface needs them).
struct MeshHeight {
  const HeightFunction& function;
  const SurfaceMap* map = nullptr;  // a kHeight map, or null
};

// The truth's mesh: every lattice point displaced to P + A h Ni (a point
// on an edge computed from that edge's two vertices in one order, so both
// triangles get its bits), triangle t's sub-triangles at plan.first[t]
// onwards, row by row of its lattice. No normals. With a map, h is read at
// the point's UV: a corner's from the first triangle that uses the vertex,
// an edge point's from the first triangle that has the edge, so a UV seam
// stays watertight (where the map differs across the seam, the strip of
// sub-triangles along it blends the two sides).
TriangleMesh subdivide_displaced(const MeshSurface& base, const MeshSubdivision& plan,
                                 const MeshHeight& height, double amplitude);

// The truth's mesh as another renderer is given it (POV-Ray's mesh2,
// Cycles): subdivide_displaced's triangles, but each base triangle with
// vertices of its own, their normals the exact normal of the truth there
// (mesh_displaced_normal), so that the base mesh's facets stay creases as
// the evaluator shades them. A vertex on a base edge keeps the position
// bits its neighbour's copy has, so the surface stays watertight; lattice
// triangles squeezed onto an edge (zero area) are left out.
TriangleMesh displaced_mesh_for_export(const MeshSurface& base, const MeshSubdivision& plan,
                                       const MeshHeight& height, double amplitude);

}  // namespace penumbra
