// Analytic base shapes: ray intersection and the differential geometry the
// bump and displacement representations need. Scene units throughout.
#pragma once

#include <cstdint>
#include <memory>

#include "core/enum_names.h"
#include "core/height.h"
#include "core/vec.h"

namespace penumbra {

struct Ray {
  Vec3 origin;
  Vec3 direction;  // unit length
};

enum class ShapeType { kCylinder, kSphere, kPlane, kMesh };
inline constexpr EnumName<ShapeType> kShapeTypeNames[] = {{"cylinder", ShapeType::kCylinder},
                                                          {"sphere", ShapeType::kSphere},
                                                          {"plane", ShapeType::kPlane},
                                                          {"mesh", ShapeType::kMesh}};

struct MeshSurface;  // core/mesh_surface.h

// Cylinder: side of the given radius around `axis` through `center`, from
// -height/2 to +height/2 along the axis, optionally closed by flat caps.
// Sphere: `radius` around `center`; `axis` only fixes its (u, v)
// parameterisation (poles on the axis).
// Plane: a width x height rectangle through `center` with normal `axis`,
// spanning frame.s (width) and frame.t (height); its `radius` is half its
// longer side, the size scale every epsilon and default edge length uses.
// Mesh: triangles read from a file (core/mesh_surface.h), traced by the
// evaluator's mesh tracers only (intersect() and the other functions here
// refuse it); `center` and `radius` are its bounding sphere's.
struct Shape {
  ShapeType type = ShapeType::kSphere;
  Vec3 center;
  Vec3 axis{0, 1, 0};  // unit length
  double radius = 1.0;
  double height = 2.0;
  double width = 2.0;  // plane only
  bool caps = false;
  std::shared_ptr<const MeshSurface> mesh;  // mesh only

  // Frame whose n is the axis; set by with_frame() before intersecting.
  Frame frame = Frame::from_z({0, 1, 0});
};

Shape with_frame(Shape shape);

// Local geometry at a base-surface point. t1 x t2 = n, and t1, t2 are the
// principal directions with curvatures kappa1, kappa2 (1/scene units,
// positive where the surface bends away from n, i.e. convex).
struct SurfaceGeometry {
  Vec3 p, n, t1, t2;
  double kappa1 = 0.0, kappa2 = 0.0;
  // Parameters of the displaceable part: cylinder side u = azimuth in
  // [0, 2 pi), v = axial coordinate in [-height/2, height/2]; sphere
  // u = azimuth in [0, 2 pi), v = polar angle from +axis in [0, pi];
  // plane u, v = coordinates along frame.s and frame.t from the centre;
  // mesh u, v = barycentrics b1, b2 in triangle `triangle`.
  // Set by surface_at() and mesh_surface_at(); intersect() leaves them 0 (no
  // renderer needs them there, and the azimuth costs an atan2 per camera ray).
  double u = 0.0, v = 0.0;
  std::uint32_t triangle = 0;  // meshes only
  bool displaceable = true;    // false on cylinder caps: h applies to the side only
};

struct Hit {
  double t = 0.0;
  SurfaceGeometry geometry;
};

// Closest hit with t in (t_min, t_max), from outside or inside; *hit is
// written only when there is one.
bool intersect(const Shape& shape, const Ray& ray, double t_min, double t_max, Hit* hit);
// Any hit with t in (t_min, t_max); cheaper than intersect() for shadow rays.
bool occluded(const Shape& shape, const Ray& ray, double t_min, double t_max);

// Geometry of the displaceable part at parameters (u, v).
SurfaceGeometry surface_at(const Shape& shape, double u, double v);

// Geometry of the base surface under a point near it: its radial projection
// onto the sphere or the cylinder side (cap = 0), or onto a cap (cap = +1 top,
// -1 bottom); on the plane, the orthogonal projection, clamped to the
// rectangle. For mesh hits: the analytic point a tessellation approximates.
// Leaves u and v at 0, like intersect().
SurfaceGeometry base_geometry_under(const Shape& shape, const Vec3& p, int cap = 0);

// Normal of the displaced surface P' = P + A h(P) N(P) at the base point, in
// closed form from the principal frame (exact, not first order):
//   Ns ~ c1 c2 N - A g1 c2 t1 - A g2 c1 t2,  ci = 1 + A h kappa_i,  gi = grad h . ti.
Vec3 displaced_normal(const SurfaceGeometry& g, double amplitude, const HeightSample& h);

// The displaced point P + A h N.
inline Vec3 displaced_point(const SurfaceGeometry& g, double amplitude, const HeightSample& h) {
  return g.p + g.n * (amplitude * h.h);
}

}  // namespace penumbra
