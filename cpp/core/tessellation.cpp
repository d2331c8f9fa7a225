#include "core/tessellation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <tuple>

namespace penumbra {

GridResolution uv_resolution(const Shape& shape, const Tessellation& t) {
  GridResolution r;
  r.nu = t.segments;
  r.nv = t.rings;
  if (r.nv == 0) r.nv = shape.type == ShapeType::kSphere ? std::max(2u, t.segments / 2) : 1u;
  return r;
}

std::size_t tessellated_triangle_count(const Shape& shape, const Tessellation& t) {
  if (t.scheme == TessellationScheme::kIcosphere)
    return 20 * std::size_t(t.frequency) * t.frequency;
  const GridResolution r = uv_resolution(shape, t);
  if (shape.type == ShapeType::kSphere) return 2 * std::size_t(r.nu) * (r.nv - 1);
  return 2 * std::size_t(r.nu) * r.nv + (shape.caps ? 2 * std::size_t(r.nu) : 0);
}

namespace {

// Geodesic sphere: every icosahedron face split into f^2 triangles on a
// barycentric lattice, lattice points projected onto the sphere. Vertices on
// shared edges are merged through their exact lattice coordinates, so the
// mesh is watertight.
TriangleMesh icosphere(const Shape& shape, unsigned f) {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  const std::array<Vec3, 12> corners{{{-1, g, 0},
                                      {1, g, 0},
                                      {-1, -g, 0},
                                      {1, -g, 0},
                                      {0, -1, g},
                                      {0, 1, g},
                                      {0, -1, -g},
                                      {0, 1, -g},
                                      {g, 0, -1},
                                      {g, 0, 1},
                                      {-g, 0, -1},
                                      {-g, 0, 1}}};
  static constexpr unsigned kFaces[20][3] = {
      {0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  // A lattice point is identified by its integer weights on the (sorted)
  // corners it lies between, so neighbouring faces name it identically.
  using Key = std::array<std::pair<unsigned, unsigned>, 3>;
  std::map<Key, unsigned> index;
  TriangleMesh mesh;
  auto vertex = [&](const unsigned c[3], unsigned w0, unsigned w1, unsigned w2) {
    Key key{{{c[0], w0}, {c[1], w1}, {c[2], w2}}};
    for (auto& k : key)
      if (k.second == 0) k.first = 0;
    std::sort(key.begin(), key.end());
    const auto [it, inserted] = index.try_emplace(key, static_cast<unsigned>(mesh.vertex_count()));
    if (inserted) {
      const Vec3 d = normalize(corners[c[0]] * w0 + corners[c[1]] * w1 + corners[c[2]] * w2);
      const Vec3 n = shape.frame.to_world(d);
      const Vec3 p = shape.center + n * shape.radius;
      for (double x : {p.x, p.y, p.z}) mesh.positions.push_back(static_cast<float>(x));
      for (double x : {n.x, n.y, n.z}) mesh.normals.push_back(static_cast<float>(x));
    }
    return it->second;
  };
  for (const auto& face : kFaces) {
    for (unsigned i = 0; i < f; ++i)
      for (unsigned j = 0; i + j < f; ++j) {
        // Lattice point (i, j) has weights (f-i-j, i, j) on the face corners.
        const unsigned a = vertex(face, f - i - j, i, j);
        const unsigned b = vertex(face, f - i - j - 1, i + 1, j);
        const unsigned c = vertex(face, f - i - j - 1, i, j + 1);
        for (unsigned k : {a, b, c}) mesh.triangles.push_back(k);
        if (i + j + 1 < f) {
          const unsigned d = vertex(face, f - i - j - 2, i + 1, j + 1);
          for (unsigned k : {b, d, c}) mesh.triangles.push_back(k);
        }
      }
  }
  mesh.side_triangles = mesh.triangle_count();
  return mesh;
}

}  // namespace

TriangleMesh tessellate(const Shape& shape, const Tessellation& t) {
  if (t.scheme == TessellationScheme::kIcosphere) return icosphere(shape, t.frequency);
  return make_grid_mesh(shape, HeightFunction{}, 0.0, uv_resolution(shape, t));
}

}  // namespace penumbra
