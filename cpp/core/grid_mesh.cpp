#include "core/grid_mesh.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace penumbra {

GridResolution grid_resolution(const Shape& shape, double edge, double reach) {
  const double r = shape.radius + reach;
  GridResolution g;
  if (shape.type == ShapeType::kPlane) {
    g.nu = std::max(1u, static_cast<unsigned>(std::ceil(shape.width / edge)));
    g.nv = std::max(1u, static_cast<unsigned>(std::ceil(shape.height / edge)));
    return g;
  }
  g.nu = std::max(8u, static_cast<unsigned>(std::ceil(2.0 * kPi * r / edge)));
  g.nv = shape.type == ShapeType::kSphere
             ? std::max(4u, static_cast<unsigned>(std::ceil(kPi * r / edge)))
             : std::max(1u, static_cast<unsigned>(std::ceil(shape.height / edge)));
  return g;
}

double grid_u(const Shape& shape, GridResolution r, unsigned i) {
  return shape.type == ShapeType::kPlane ? -0.5 * shape.width + shape.width * i / r.nu
                                         : 2.0 * kPi * i / r.nu;
}

double grid_v(const Shape& shape, GridResolution r, unsigned j) {
  return shape.type == ShapeType::kSphere ? kPi * j / r.nv
                                          : -0.5 * shape.height + shape.height * j / r.nv;
}

namespace {

// Writes vertices and triangles into a mesh sized beforehand.
struct GridWriter {
  const Shape& shape;
  const HeightFunction& height;
  const SurfaceMap* map;
  double amplitude;
  GridResolution res;
  GridNormals normals;
  TriangleMesh mesh;

  void put(std::size_t index, const Vec3& p, const Vec3& n) {
    float* q = &mesh.positions[3 * index];
    q[0] = static_cast<float>(p.x), q[1] = static_cast<float>(p.y), q[2] = static_cast<float>(p.z);
    if (normals == GridNormals::kOmit) return;
    float* m = &mesh.normals[3 * index];
    m[0] = static_cast<float>(n.x), m[1] = static_cast<float>(n.y), m[2] = static_cast<float>(n.z);
  }
  // The displaced surface point and normal at (u, v).
  void vertex(std::size_t index, double u, double v) {
    const SurfaceGeometry g = surface_at(shape, u, v);
    const HeightSample h = height_at(height, map, shape, g);
    put(index, displaced_point(g, amplitude, h),
        normals == GridNormals::kOmit ? Vec3{} : displaced_normal(g, amplitude, h));
  }
  // Vertex (i, j) for i in [0, columns), j in [j0, j1), at row j's offset
  // `first + (j - j0) * columns`; rows run in parallel.
  void rows(unsigned j0, unsigned j1, unsigned columns, std::size_t first) {
    tbb::parallel_for(tbb::blocked_range<unsigned>(j0, j1), [&](const auto& range) {
      for (unsigned j = range.begin(); j != range.end(); ++j)
        for (unsigned i = 0; i < columns; ++i)
          vertex(first + std::size_t(j - j0) * columns + i, grid_u(shape, res, i),
                 grid_v(shape, res, j));
    });
  }
  void tri(std::size_t t, std::size_t a, std::size_t b, std::size_t c) {
    mesh.triangles[3 * t] = static_cast<unsigned>(a);
    mesh.triangles[3 * t + 1] = static_cast<unsigned>(b);
    mesh.triangles[3 * t + 2] = static_cast<unsigned>(c);
  }
  void resize(std::size_t vertices, std::size_t side_triangles, std::size_t triangles) {
    mesh.side_triangles = side_triangles;
    // One spare float: a BVH that reads the vertices in place may load the
    // last one 16 bytes wide (evaluator/embree_mesh.cpp).
    mesh.positions.reserve(3 * vertices + 1);
    mesh.positions.resize(3 * vertices);
    if (normals == GridNormals::kExact) mesh.normals.resize(3 * vertices);
    mesh.triangles.resize(3 * triangles);
  }
};

// Poles, then rings of nu vertices; fans at the poles, quads between rings.
void sphere_grid(GridWriter& w) {
  const unsigned nu = w.res.nu, nv = w.res.nv;
  const std::size_t vertex_count = 2 + std::size_t(nu) * (nv - 1);
  const std::size_t triangles = nu + 2 * std::size_t(nu) * (nv - 2) + nu;
  w.resize(vertex_count, triangles, triangles);
  w.vertex(0, 0.0, 0.0);
  w.vertex(vertex_count - 1, 0.0, kPi);
  w.rows(1, nv, nu, 1);
  auto ring = [&](unsigned j, unsigned i) { return 1 + std::size_t(j - 1) * nu + (i % nu); };
  const std::size_t south = vertex_count - 1;
  for (unsigned i = 0; i < nu; ++i) {
    w.tri(i, 0, ring(1, i), ring(1, i + 1));
    w.tri(nu + 2 * std::size_t(nu) * (nv - 2) + i, south, ring(nv - 1, i + 1), ring(nv - 1, i));
  }
  for (unsigned j = 1; j + 1 < nv; ++j)
    for (unsigned i = 0; i < nu; ++i) {
      const std::size_t t = nu + 2 * (std::size_t(j - 1) * nu + i);
      w.tri(t, ring(j, i), ring(j, i + 1), ring(j + 1, i + 1));
      w.tri(t + 1, ring(j, i), ring(j + 1, i + 1), ring(j + 1, i));
    }
}

// Each cap: a centre vertex, then copies of its rim with the cap's normal.
void cylinder_caps(GridWriter& w, std::size_t side_triangles) {
  const unsigned nu = w.res.nu, nv = w.res.nv;
  const Shape& shape = w.shape;
  auto at = [&](unsigned j, unsigned i) { return std::size_t(j) * nu + (i % nu); };
  for (int side = 0; side < 2; ++side) {
    const unsigned j = side == 0 ? 0 : nv;
    const Vec3 n = shape.axis * (side == 0 ? -1.0 : 1.0);
    const std::size_t centre = std::size_t(nu) * (nv + 1) + std::size_t(side) * (nu + 1);
    w.put(centre, shape.center + shape.axis * (side == 0 ? -0.5 : 0.5) * shape.height, n);
    for (unsigned i = 0; i < nu; ++i) {
      const float* p = &w.mesh.positions[3 * at(j, i)];
      w.put(centre + 1 + i, {p[0], p[1], p[2]}, n);
    }
    auto rim = [&](unsigned i) { return centre + 1 + (i % nu); };
    for (unsigned i = 0; i < nu; ++i) {
      if (side == 0)
        w.tri(side_triangles + i, centre, rim(i + 1), rim(i));
      else
        w.tri(side_triangles + nu + i, centre, rim(i), rim(i + 1));
    }
  }
}

// nv + 1 rings of nu vertices, quads between them, then the caps.
void cylinder_grid(GridWriter& w) {
  const unsigned nu = w.res.nu, nv = w.res.nv;
  const bool caps = w.shape.caps;
  const std::size_t side_triangles = 2 * std::size_t(nu) * nv;
  w.resize(std::size_t(nu) * (nv + 1) + (caps ? 2 * (nu + 1) : 0), side_triangles,
           side_triangles + (caps ? 2 * nu : 0));
  w.rows(0, nv + 1, nu, 0);
  auto at = [&](unsigned j, unsigned i) { return std::size_t(j) * nu + (i % nu); };
  for (unsigned j = 0; j < nv; ++j)
    for (unsigned i = 0; i < nu; ++i) {
      const std::size_t t = 2 * (std::size_t(j) * nu + i);
      w.tri(t, at(j, i), at(j, i + 1), at(j + 1, i + 1));
      w.tri(t + 1, at(j, i), at(j + 1, i + 1), at(j + 1, i));
    }
  if (caps) cylinder_caps(w, side_triangles);
}

// (nu + 1) x (nv + 1) vertices, no wrap.
void plane_grid(GridWriter& w) {
  const unsigned nu = w.res.nu, nv = w.res.nv;
  const std::size_t triangles = 2 * std::size_t(nu) * nv;
  w.resize(std::size_t(nu + 1) * (nv + 1), triangles, triangles);
  w.rows(0, nv + 1, nu + 1, 0);
  auto at = [&](unsigned j, unsigned i) { return std::size_t(j) * (nu + 1) + i; };
  for (unsigned j = 0; j < nv; ++j)
    for (unsigned i = 0; i < nu; ++i) {
      const std::size_t t = 2 * (std::size_t(j) * nu + i);
      w.tri(t, at(j, i), at(j, i + 1), at(j + 1, i + 1));
      w.tri(t + 1, at(j, i), at(j + 1, i + 1), at(j + 1, i));
    }
}

}  // namespace

TriangleMesh make_grid_mesh(const Shape& shape, const HeightFunction& height, double amplitude,
                            GridResolution res, const SurfaceMap* map, GridNormals normals) {
  GridWriter w{shape, height, map, amplitude, res, normals, {}};
  switch (shape.type) {
    case ShapeType::kSphere:
      sphere_grid(w);
      break;
    case ShapeType::kCylinder:
      cylinder_grid(w);
      break;
    case ShapeType::kPlane:
      plane_grid(w);
      break;
    case ShapeType::kMesh:  // core/mesh_surface.h subdivides meshes
      throw std::logic_error("make_grid_mesh: a mesh shape has no (u, v) grid");
  }
  return std::move(w.mesh);
}

}  // namespace penumbra
