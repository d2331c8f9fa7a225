// Image maps on a shape: a height map or a tangent-space normal map laid over
// the shape's (u, v) parameterisation and sampled by the uniform cubic
// B-spline of its texels (Cycles' "Cubic" image interpolation). The spline is
// C2, so heights, slopes and normals are continuous, and its convex-hull
// property gives exact bounds of h and of its derivatives from the texels.
// Pure math: the scene layer reads the files.
#pragma once

#include <string>
#include <vector>

#include "core/bump_pyramid.h"
#include "core/height.h"
#include "core/shape.h"
#include "core/vec.h"

namespace penumbra {

struct MeshSurface;  // core/mesh_surface.h

enum class MapKind {
  kHeight,  // one channel: h (dimensionless; the scene's amplitude scales it)
  kNormal,  // three channels: a tangent-space normal encoded as 0.5 n + 0.5
};

// Texel (x, y), y = 0 the top row, has its centre at map coordinates
//   s = (x + 0.5) / width,   t = 1 - (y + 0.5) / height,
// (t up, as Blender's and POV-Ray's image textures). The shape's (u, v) in
// [0, 1]^2 map to s = tiles_u u, t = tiles_v v.
struct SurfaceMap {
  MapKind kind = MapKind::kHeight;
  int width = 0, height = 0;
  std::vector<float> texels;  // row-major from the top row, 1 or 3 channels interleaved
  double tiles_u = 1.0;       // repeats around the shape, > 0
  double tiles_v = 1.0;       // repeats along v, > 0
  MapEdge edge = MapEdge::kWrap;
  // Content digest (hex) of the texels and size: what identifies the map in
  // cache keys and mesh keys, wherever the file lies.
  std::string digest;

  int channels() const { return kind == MapKind::kHeight ? 1 : 3; }
};

// The shape's map parameters at a point on (or radially above) its
// displaceable part, and their derivatives (scene units per unit of u, v).
//   cylinder: u = azimuth / 2 pi, v = (axial + height/2) / height
//   sphere:   u = azimuth / 2 pi, v = 1 - polar angle / pi (v = 1 on +axis)
//   plane:    u = x / width + 1/2, v = y / height + 1/2 along frame.s, frame.t
// The azimuth is measured as surface_at() measures it. Both
// parameterisations are orthogonal; on the sphere dP/du vanishes at the poles.
struct SurfaceParameters {
  double u = 0.0, v = 0.0;
  Vec3 dp_du, dp_dv;
};
SurfaceParameters surface_parameters(const Shape& shape, const Vec3& p);
// The map parameters of a triangle's corners (points on or near the shape)
// as one triangle of a mesh carries them: u unwrapped past 1 where the
// triangle straddles the u seam, and at a sphere's pole (where u is
// undefined) the other corners' mean u.
void triangle_parameters(const Shape& shape, const Vec3 corners[3], double u[3], double v[3]);
// The inverse: the base surface at map parameters (u, v) in [0, 1]^2.
SurfaceGeometry surface_at_parameters(const Shape& shape, double u, double v);
// Lengths of the u and v lines at their longest (scene units): the
// circumference (equator) and the height or half meridian; a plane's sides.
struct MapLengths {
  double u = 0.0, v = 0.0;
};
MapLengths map_lengths(const Shape& shape);
// A mesh's: the area-weighted means over its triangles of 1 / |grad u| and
// 1 / |grad v| (scene units per unit of u, v), triangles with a zero UV
// area left out; a mesh whose UV scale varies has no single length, and
// what uses this one is exact only where the scale is the mean.
MapLengths mesh_map_lengths(const MeshSurface& mesh);

// The spline at map coordinates (s, t): channel c's value and its derivatives
// per unit of s and of t.
struct MapSample {
  double value = 0.0, d_ds = 0.0, d_dt = 0.0;
};
MapSample sample_map(const SurfaceMap& map, double s, double t, int channel = 0);

// A height map's h at the point of `g` (g.p, g.n), with the 3D gradient in
// the tangent plane (per scene unit), as evaluate_height gives it for the
// analytic families. `map` null: the analytic function at g.p. On a mesh
// the map is read at the UV interpolated over triangle g.triangle and the
// gradient lies in that triangle's plane: h_s grad(u) + h_t grad(v), with
// grad(u), grad(v) the gradients of the triangle's affine UVs (no
// orthogonality assumed; zero where its UV area is zero).
HeightSample height_at(const HeightFunction& function, const SurfaceMap* map, const Shape& shape,
                       const SurfaceGeometry& g);
// height_at on a mesh surface, g from mesh_surface_at.
HeightSample mesh_height_at(const HeightFunction& function, const SurfaceMap* map,
                            const MeshSurface& mesh, const SurfaceGeometry& g);

// A normal map's shading normal at the point of `g`: the decoded tangent-space
// normal 2c - 1 in the frame (dP/du, dP/dv, N), unit length; the green
// channel follows +v, as Blender's Normal Map node reads it. On a mesh the
// frame is MikkTSpace's, as Cycles' Normal Map node builds it
// (blender/blender intern/cycles/kernel/svm/tex_coord.h,
// svm_node_normal_map): T and N interpolated and not normalised,
// B = sign (N x T), n = normalize(x T + y B + z N).
Vec3 normal_map_normal(const SurfaceMap& map, const Shape& shape, const SurfaceGeometry& g);

// Bounds of h and its derivatives over the whole surface, for the mesh
// resolution and the shadow-ray lift. From the texels: |h| <= max|texel|,
// |dh/dx| <= max first difference per texel, and so on (the B-spline is a
// convex combination of its control points and its derivatives of their
// differences). Per scene unit with the texel pitch of the shape's
// parameterisation; on the sphere that pitch is taken at latitude +-60
// degrees (dP/du shrinks towards the poles, where no bound holds).
struct HeightBounds {
  double max_abs = 0.0;       // dimensionless
  double max_gradient = 0.0;  // per scene unit
  double max_hessian = 0.0;   // per scene unit squared
};
HeightBounds height_bounds(const HeightFunction& function, const SurfaceMap* map,
                           const Shape& shape);
// The same bounds per triangle of a mesh with UVs: texels per scene unit
// from each triangle's |grad u| and |grad v| (its UVs are affine, so no
// curvature term).
std::vector<HeightBounds> mesh_height_bounds(const SurfaceMap& map, const MeshSurface& mesh);

// Hex digest of a map's size, kind and texels (FNV-1a, two seeds).
std::string map_digest(const SurfaceMap& map);

}  // namespace penumbra
