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

namespace {

std::size_t flat_triangle_count(const Shape& shape, const Tessellation& t) {
  if (t.scheme == TessellationScheme::kIcosphere)
    return 20 * std::size_t(t.frequency) * t.frequency;
  const GridResolution r = uv_resolution(shape, t);
  if (shape.type == ShapeType::kSphere) return 2 * std::size_t(r.nu) * (r.nv - 1);
  return 2 * std::size_t(r.nu) * r.nv + (shape.caps ? 2 * std::size_t(r.nu) : 0);
}

}  // namespace

std::size_t tessellated_triangle_count(const Shape& shape, const Tessellation& t) {
  return flat_triangle_count(shape, t) * t.phong_level * t.phong_level;
}

namespace {

// The points of faces split on barycentric lattices, each named by its
// integer weights on the (sorted) corners it lies between, so that faces
// sharing an edge or a corner name a point identically and the split mesh
// is watertight where the mesh was.
class LatticePoints {
 public:
  // The index of the point of weights (w0, w1, w2) on corners c; make(c,
  // w0, w1, w2) appends it to the mesh the first time.
  template <typename Make>
  unsigned at(const unsigned c[3], unsigned w0, unsigned w1, unsigned w2, unsigned next,
              Make&& make) {
    Key key{{{c[0], w0}, {c[1], w1}, {c[2], w2}}};
    for (auto& k : key)
      if (k.second == 0) k.first = 0;
    std::sort(key.begin(), key.end());
    const auto [it, inserted] = index_.try_emplace(key, next);
    if (inserted) make(c, w0, w1, w2);
    return it->second;
  }

 private:
  using Key = std::array<std::pair<unsigned, unsigned>, 3>;
  std::map<Key, unsigned> index_;
};

// The f^2 triangles of face c's lattice, in the face's winding, into `out`;
// point(c, w0, w1, w2) is a lattice point's index.
template <typename Point>
void split_face(const unsigned c[3], unsigned f, Point&& point, std::vector<unsigned>* out) {
  for (unsigned i = 0; i < f; ++i)
    for (unsigned j = 0; i + j < f; ++j) {
      // Lattice point (i, j) has weights (f-i-j, i, j) on the face corners.
      const unsigned a = point(c, f - i - j, i, j);
      const unsigned b = point(c, f - i - j - 1, i + 1, j);
      const unsigned d = point(c, f - i - j - 1, i, j + 1);
      for (unsigned k : {a, b, d}) out->push_back(k);
      if (i + j + 1 < f) {
        const unsigned e = point(c, f - i - j - 2, i + 1, j + 1);
        for (unsigned k : {b, e, d}) out->push_back(k);
      }
    }
}

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
  LatticePoints points;
  TriangleMesh mesh;
  auto make = [&](const unsigned c[3], unsigned w0, unsigned w1, unsigned w2) {
    const Vec3 d = normalize(corners[c[0]] * w0 + corners[c[1]] * w1 + corners[c[2]] * w2);
    const Vec3 n = shape.frame.to_world(d);
    const Vec3 p = shape.center + n * shape.radius;
    for (double x : {p.x, p.y, p.z}) mesh.positions.push_back(static_cast<float>(x));
    for (double x : {n.x, n.y, n.z}) mesh.normals.push_back(static_cast<float>(x));
  };
  auto vertex = [&](const unsigned c[3], unsigned w0, unsigned w1, unsigned w2) {
    return points.at(c, w0, w1, w2, static_cast<unsigned>(mesh.vertex_count()), make);
  };
  for (const auto& face : kFaces) split_face(face, f, vertex, &mesh.triangles);
  mesh.side_triangles = mesh.triangle_count();
  return mesh;
}

}  // namespace

TriangleMesh tessellate(const Shape& shape, const Tessellation& t) {
  TriangleMesh mesh = t.scheme == TessellationScheme::kIcosphere
                          ? icosphere(shape, t.frequency)
                          : make_grid_mesh(shape, HeightFunction{}, 0.0, uv_resolution(shape, t));
  if (t.phong_level > 1) return phong_refine(mesh, t.phong_level, t.phong_alpha);
  return mesh;
}

namespace {

Vec3 vertex_of(const std::vector<float>& v, unsigned k) {
  return {v[3 * k], v[3 * k + 1], v[3 * k + 2]};
}

}  // namespace

TriangleMesh phong_refine(const TriangleMesh& mesh, unsigned level, double alpha) {
  LatticePoints points;
  TriangleMesh out;
  const double inv = 1.0 / level;
  auto make = [&](const unsigned c[3], unsigned w0, unsigned w1, unsigned w2) {
    const double b[3] = {w0 * inv, w1 * inv, w2 * inv};
    Vec3 p, projected, n;
    for (int k = 0; k < 3; ++k) p += vertex_of(mesh.positions, c[k]) * b[k];
    for (int k = 0; k < 3; ++k) {
      const Vec3 v = vertex_of(mesh.positions, c[k]), nk = vertex_of(mesh.normals, c[k]);
      projected += (p - nk * dot(p - v, nk)) * b[k];
      n += nk * b[k];
    }
    const Vec3 q = p * (1.0 - alpha) + projected * alpha;
    n = normalize(n);
    for (double x : {q.x, q.y, q.z}) out.positions.push_back(static_cast<float>(x));
    for (double x : {n.x, n.y, n.z}) out.normals.push_back(static_cast<float>(x));
  };
  auto point = [&](const unsigned c[3], unsigned w0, unsigned w1, unsigned w2) {
    return points.at(c, w0, w1, w2, static_cast<unsigned>(out.vertex_count()), make);
  };
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    split_face(&mesh.triangles[3 * t], level, point, &out.triangles);
    if (t + 1 == mesh.side_triangles) out.side_triangles = out.triangle_count();
  }
  if (mesh.side_triangles == 0) out.side_triangles = 0;
  return out;
}

}  // namespace penumbra
