#include "evaluator/lowpoly_mesh.h"

#include "core/consistent_normal.h"
#include "core/mesh_surface.h"

namespace penumbra {

LowPolyMesh::LowPolyMesh(const Shape& shape, const Tessellation& tessellation)
    : shape_(shape),
      tessellation_(tessellation),
      mesh_(tessellate(shape, tessellation)),
      alpha_(tessellation.shading == NormalShading::kConsistent ? consistent_normal_alphas(mesh_)
                                                                : std::vector<double>{}),
      bvh_(mesh_, bvh_build_for(mesh_.triangle_count())) {}

LowPolyMesh::LowPolyMesh(const Shape& mesh_shape)
    : shape_(mesh_shape),
      mesh_(mesh_shape.mesh->mesh),
      bvh_(mesh_, bvh_build_for(mesh_.triangle_count())) {}

Vec3 LowPolyMesh::position(unsigned vertex) const {
  const float* p = &mesh_.positions[3 * std::size_t(vertex)];
  return {p[0], p[1], p[2]};
}

Vec3 LowPolyMesh::normal(unsigned vertex) const {
  const float* n = &mesh_.normals[3 * std::size_t(vertex)];
  return {n[0], n[1], n[2]};
}

std::optional<LowPolyHit> LowPolyMesh::intersect(const Ray& ray) const {
  const auto found = bvh_.intersect(ray);
  if (!found) return std::nullopt;
  LowPolyHit hit;
  hit.t = found->t;
  hit.triangle = found->triangle;
  hit.b[1] = found->b1;
  hit.b[2] = found->b2;
  hit.b[0] = 1.0 - found->b1 - found->b2;
  const unsigned* index = &mesh_.triangles[3 * std::size_t(hit.triangle)];
  Vec3 v[3], n[3];
  for (int k = 0; k < 3; ++k) {
    v[k] = position(index[k]);
    n[k] = normal(index[k]);
    hit.p += v[k] * hit.b[k];
  }
  // The winding is not trusted: Ng takes the side of the vertex normals.
  hit.ng = normalize(cross(v[1] - v[0], v[2] - v[0]));
  if (dot(hit.ng, n[0] + n[1] + n[2]) < 0.0) hit.ng = -hit.ng;
  hit.ni = tessellation_.shading == NormalShading::kFlat
               ? hit.ng
               : normalize(n[0] * hit.b[0] + n[1] * hit.b[1] + n[2] * hit.b[2]);
  if (!alpha_.empty()) {
    for (int k = 0; k < 3; ++k) hit.alpha += alpha_[index[k]] * hit.b[k];
    // Seen from behind (inside an open cylinder) every vector turns over.
    const Vec3 wo = -ray.direction;
    const double side = dot(hit.ng, wo) < 0.0 ? -1.0 : 1.0;
    hit.ni = side * consistent_normal(wo, hit.ni * side, hit.alpha);
  }
  if (shape_.type == ShapeType::kMesh) {
    hit.base = mesh_surface_at(mesh_, hit.triangle, hit.b);
    return hit;
  }
  int cap = 0;
  if (hit.triangle >= mesh_.side_triangles)
    cap = hit.triangle >= mesh_.side_triangles + (mesh_.triangle_count() - mesh_.side_triangles) / 2
              ? 1
              : -1;
  hit.base = base_geometry_under(shape_, hit.p, cap);
  return hit;
}

ShadingTriangle LowPolyMesh::shading_triangle(const LowPolyHit& hit, bool flip) const {
  ShadingTriangle t;
  const unsigned* index = &mesh_.triangles[3 * std::size_t(hit.triangle)];
  const double sign = flip ? -1.0 : 1.0;
  for (int k = 0; k < 3; ++k) {
    t.v[k] = position(index[k]);
    t.n[k] = (tessellation_.shading == NormalShading::kFlat ? hit.ng : normal(index[k])) * sign;
    t.b[k] = hit.b[k];
  }
  return t;
}

}  // namespace penumbra
