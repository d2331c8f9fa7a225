// A tessellated shape (core/tessellation.h) traced with Embree: what a
// production renderer sees when a modeller exports a low-poly, smooth-shaded
// cylinder or sphere. Hits carry the flat triangle's point and normal, the
// interpolated normal Ni, and the analytic geometry the triangle stands in for
// (for the analysis channels and the bump frame). A mesh shape read from a
// file (core/mesh_surface.h) is traced the same way; its base geometry is
// its own (mesh_surface_at: the point on the triangle, Ni).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "core/shadow_origin.h"
#include "core/tessellation.h"
#include "evaluator/embree_mesh.h"

namespace penumbra {

struct LowPolyHit {
  double t = 0.0;
  std::uint32_t triangle = 0;
  double b[3] = {1.0, 0.0, 0.0};  // barycentric weights of the triangle's vertices
  Vec3 p;                         // on the flat triangle
  Vec3 ng;                        // the triangle's normal, on the vertex normals' side
  Vec3 ni;                        // normalised sum b_k n_k (flat shading: ng)
  double alpha = 0.0;             // consistent shading: sum b_k alpha_k (radians), else 0
  SurfaceGeometry base;           // analytic surface under p
};

class LowPolyMesh {
 public:
  LowPolyMesh(const Shape& shape, const Tessellation& tessellation);
  // A mesh shape (ShapeType::kMesh), smooth-shaded by its vertex normals.
  explicit LowPolyMesh(const Shape& mesh_shape);

  // Consistent shading bends ni for the ray's view (core/consistent_normal.h),
  // on whichever side of the triangle the ray sees.
  std::optional<LowPolyHit> intersect(const Ray& ray) const;
  bool occluded(const Ray& ray, double t_min, double t_max, std::uint32_t skip) const {
    return bvh_.occluded(ray, t_min, t_max, skip);
  }
  // The hit's triangle for the offset methods; `flip` turns the vertex
  // normals to the back side. Flat shading gives every vertex the face normal.
  ShadingTriangle shading_triangle(const LowPolyHit& hit, bool flip) const;

  const TriangleMesh& mesh() const { return mesh_; }
  std::size_t triangle_count() const { return mesh_.triangle_count(); }

 private:
  Vec3 position(unsigned vertex) const;
  Vec3 normal(unsigned vertex) const;

  Shape shape_;
  Tessellation tessellation_;
  TriangleMesh mesh_;
  std::vector<double> alpha_;  // per vertex, consistent shading only
  EmbreeMesh bvh_;
};

}  // namespace penumbra
