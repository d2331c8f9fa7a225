#include "core/grid_mesh.h"

#include <algorithm>
#include <cmath>

namespace penumbra {

GridResolution grid_resolution(const Shape& shape, double edge, double reach) {
  const double r = shape.radius + reach;
  GridResolution g;
  g.nu = std::max(8u, static_cast<unsigned>(std::ceil(2.0 * kPi * r / edge)));
  g.nv = shape.type == ShapeType::kSphere
             ? std::max(4u, static_cast<unsigned>(std::ceil(kPi * r / edge)))
             : std::max(1u, static_cast<unsigned>(std::ceil(shape.height / edge)));
  return g;
}

double grid_v(const Shape& shape, GridResolution r, unsigned j) {
  return shape.type == ShapeType::kSphere ? kPi * j / r.nv
                                          : -0.5 * shape.height + shape.height * j / r.nv;
}

TriangleMesh make_grid_mesh(const Shape& shape, const HeightFunction& height, double amplitude,
                            GridResolution res) {
  const unsigned nu = res.nu, nv = res.nv;
  const bool sphere = shape.type == ShapeType::kSphere;
  const bool caps = !sphere && shape.caps;
  TriangleMesh mesh;
  std::size_t vertex_count, side_triangles, triangle_count;
  if (sphere) {
    vertex_count = 2 + std::size_t(nu) * (nv - 1);
    side_triangles = nu + 2 * std::size_t(nu) * (nv - 2) + nu;
    triangle_count = side_triangles;
  } else {
    vertex_count = std::size_t(nu) * (nv + 1) + (caps ? 2 * (nu + 1) : 0);
    side_triangles = 2 * std::size_t(nu) * nv;
    triangle_count = side_triangles + (caps ? 2 * nu : 0);
  }
  mesh.side_triangles = side_triangles;
  mesh.positions.resize(3 * vertex_count);
  mesh.normals.resize(3 * vertex_count);
  mesh.triangles.resize(3 * triangle_count);

  auto put = [&](std::size_t index, const Vec3& p, const Vec3& n) {
    float* q = &mesh.positions[3 * index];
    float* m = &mesh.normals[3 * index];
    q[0] = static_cast<float>(p.x), q[1] = static_cast<float>(p.y), q[2] = static_cast<float>(p.z);
    m[0] = static_cast<float>(n.x), m[1] = static_cast<float>(n.y), m[2] = static_cast<float>(n.z);
  };
  auto vertex = [&](std::size_t index, double u, double v) {
    const SurfaceGeometry g = surface_at(shape, u, v);
    const HeightSample h = evaluate_height(height, g.p);
    put(index, displaced_point(g, amplitude, h), displaced_normal(g, amplitude, h));
  };
  auto tri = [&](std::size_t t, std::size_t a, std::size_t b, std::size_t c) {
    mesh.triangles[3 * t] = static_cast<unsigned>(a);
    mesh.triangles[3 * t + 1] = static_cast<unsigned>(b);
    mesh.triangles[3 * t + 2] = static_cast<unsigned>(c);
  };

  if (sphere) {
    vertex(0, 0.0, 0.0);
    vertex(vertex_count - 1, 0.0, kPi);
    for (unsigned j = 1; j < nv; ++j)
      for (unsigned i = 0; i < nu; ++i)
        vertex(1 + std::size_t(j - 1) * nu + i, grid_u(res, i), grid_v(shape, res, j));
    auto ring = [&](unsigned j, unsigned i) { return 1 + std::size_t(j - 1) * nu + (i % nu); };
    const std::size_t south = vertex_count - 1;
    for (unsigned i = 0; i < nu; ++i) {
      tri(i, 0, ring(1, i), ring(1, i + 1));
      tri(nu + 2 * std::size_t(nu) * (nv - 2) + i, south, ring(nv - 1, i + 1), ring(nv - 1, i));
    }
    for (unsigned j = 1; j + 1 < nv; ++j)
      for (unsigned i = 0; i < nu; ++i) {
        const std::size_t t = nu + 2 * (std::size_t(j - 1) * nu + i);
        tri(t, ring(j, i), ring(j, i + 1), ring(j + 1, i + 1));
        tri(t + 1, ring(j, i), ring(j + 1, i + 1), ring(j + 1, i));
      }
    return mesh;
  }
  for (unsigned j = 0; j <= nv; ++j)
    for (unsigned i = 0; i < nu; ++i)
      vertex(std::size_t(j) * nu + i, grid_u(res, i), grid_v(shape, res, j));
  auto at = [&](unsigned j, unsigned i) { return std::size_t(j) * nu + (i % nu); };
  for (unsigned j = 0; j < nv; ++j)
    for (unsigned i = 0; i < nu; ++i) {
      const std::size_t t = 2 * (std::size_t(j) * nu + i);
      tri(t, at(j, i), at(j, i + 1), at(j + 1, i + 1));
      tri(t + 1, at(j, i), at(j + 1, i + 1), at(j + 1, i));
    }
  if (caps) {
    // Each cap: centre vertex, then copies of its rim with the cap's normal.
    for (int side = 0; side < 2; ++side) {
      const unsigned j = side == 0 ? 0 : nv;
      const Vec3 n = shape.axis * (side == 0 ? -1.0 : 1.0);
      const std::size_t centre = std::size_t(nu) * (nv + 1) + std::size_t(side) * (nu + 1);
      put(centre, shape.center + shape.axis * (side == 0 ? -0.5 : 0.5) * shape.height, n);
      for (unsigned i = 0; i < nu; ++i) {
        const float* p = &mesh.positions[3 * at(j, i)];
        put(centre + 1 + i, {p[0], p[1], p[2]}, n);
      }
      auto rim = [&](unsigned i) { return centre + 1 + (i % nu); };
      for (unsigned i = 0; i < nu; ++i) {
        if (side == 0)
          tri(side_triangles + i, centre, rim(i + 1), rim(i));
        else
          tri(side_triangles + nu + i, centre, rim(i), rim(i + 1));
      }
    }
  }
  return mesh;
}

}  // namespace penumbra
