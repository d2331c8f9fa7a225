#include "core/mesh_surface.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

namespace penumbra {

namespace {

Vec3 vertex(const TriangleMesh& m, unsigned k) {
  const float* p = &m.positions[3 * std::size_t(k)];
  return {p[0], p[1], p[2]};
}

Vec3 normal(const TriangleMesh& m, unsigned k) {
  const float* n = &m.normals[3 * std::size_t(k)];
  return {n[0], n[1], n[2]};
}

const unsigned* corners(const TriangleMesh& m, std::uint32_t triangle) {
  return &m.triangles[3 * std::size_t(triangle)];
}

// P + A h(P) Ni with P and Ni from weights w over vertices a (and b, c).
Vec3 displaced(const TriangleMesh& m, const unsigned* index, const double* w, int count,
               const HeightFunction& height, double amplitude) {
  Vec3 p, n;
  for (int k = 0; k < count; ++k) {
    p += vertex(m, index[k]) * w[k];
    n += normal(m, index[k]) * w[k];
  }
  if (amplitude == 0.0) return p;
  const double length_n = length(n);
  if (!(length_n > 0.0)) return p;
  return p + n * (amplitude * evaluate_height(height, p).h / length_n);
}

void append(std::vector<float>* out, const Vec3& p) {
  out->push_back(float(p.x));
  out->push_back(float(p.y));
  out->push_back(float(p.z));
}

}  // namespace

Vec3 mesh_centre(const MeshSurface& m) {
  return (m.bounds_min + m.bounds_max) * 0.5;
}

double mesh_radius(const MeshSurface& m) {
  return 0.5 * length(m.bounds_max - m.bounds_min);
}

void measure_mesh(MeshSurface* m) {
  const double inf = std::numeric_limits<double>::infinity();
  m->bounds_min = {inf, inf, inf};
  m->bounds_max = {-inf, -inf, -inf};
  for (std::size_t k = 0; k < m->mesh.vertex_count(); ++k) {
    const Vec3 p = vertex(m->mesh, unsigned(k));
    m->bounds_min = {std::min(m->bounds_min.x, p.x), std::min(m->bounds_min.y, p.y),
                     std::min(m->bounds_min.z, p.z)};
    m->bounds_max = {std::max(m->bounds_max.x, p.x), std::max(m->bounds_max.y, p.y),
                     std::max(m->bounds_max.z, p.z)};
  }
}

double normal_curvature(const TriangleMesh& mesh, std::uint32_t triangle) {
  const unsigned* c = corners(mesh, triangle);
  double k = 0.0;
  for (int e = 0; e < 3; ++e) {
    const unsigned a = c[e], b = c[(e + 1) % 3];
    const double edge = length(vertex(mesh, a) - vertex(mesh, b));
    if (edge > 0.0) k = std::max(k, angle_between(normal(mesh, a), normal(mesh, b)) / edge);
  }
  return k;
}

SurfaceGeometry mesh_surface_at(const TriangleMesh& mesh, std::uint32_t triangle,
                                const double b[3]) {
  const unsigned* c = corners(mesh, triangle);
  SurfaceGeometry g;
  Vec3 m;
  for (int k = 0; k < 3; ++k) {
    g.p += vertex(mesh, c[k]) * b[k];
    m += normal(mesh, c[k]) * b[k];
  }
  g.n = normalize(m);
  const Frame f = Frame::from_z(g.n);
  g.t1 = f.s;
  g.t2 = f.t;
  return g;
}

Vec3 mesh_displaced_normal(const TriangleMesh& mesh, std::uint32_t triangle, const double b[3],
                           double amplitude, const HeightSample& h) {
  const unsigned* c = corners(mesh, triangle);
  Vec3 m;
  for (int k = 0; k < 3; ++k) m += normal(mesh, c[k]) * b[k];
  const double length_m = length(m);
  const Vec3 ni = m / length_m;
  Vec3 d[2];
  for (int j = 1; j <= 2; ++j) {
    const Vec3 dp = vertex(mesh, c[j]) - vertex(mesh, c[0]);
    const Vec3 dm = normal(mesh, c[j]) - normal(mesh, c[0]);
    const Vec3 dni = (dm - ni * dot(ni, dm)) / length_m;
    d[j - 1] = dp + ni * (amplitude * dot(h.gradient, dp)) + dni * (amplitude * h.h);
  }
  const Vec3 ns = normalize(cross(d[0], d[1]));
  return dot(ns, ni) < 0.0 ? -ns : ns;
}

namespace {

std::uint32_t edge_level(const TriangleMesh& m, unsigned a, unsigned b, double edge) {
  const double level = std::ceil(length(vertex(m, a) - vertex(m, b)) / edge);
  if (!(level >= 1.0)) return 1;
  return static_cast<std::uint32_t>(std::min(level, double(kMaxSubdivisionLevel)));
}

// Lattice point (i, j) of a level-n triangle as base barycentrics (x, y) of
// vertices 1 and 2, moved onto its edge's own points (edge_levels n01,
// n12, n20) where it lies on an edge.
struct LatticePoint {
  int edge = -1;        // 0: v0v1, 1: v1v2, 2: v2v0; -1 inside or a corner
  std::uint32_t k = 0;  // the edge's point k of n_e, counted from its first vertex
  double x = 0.0, y = 0.0;
};

std::uint32_t snap(std::uint32_t along, std::uint32_t n, std::uint32_t n_edge) {
  return static_cast<std::uint32_t>((std::uint64_t(along) * n_edge * 2 + n) /
                                    (2 * std::uint64_t(n)));
}

LatticePoint lattice_point(std::uint32_t i, std::uint32_t j, std::uint32_t n,
                           const std::uint32_t* edge_levels) {
  LatticePoint p;
  if ((i == 0 && j == 0) || i == n || j == n) {
    p.x = i == n ? 1.0 : 0.0;
    p.y = j == n ? 1.0 : 0.0;
    return p;
  }
  if (j == 0) {  // v0 -> v1
    p.edge = 0, p.k = snap(i, n, edge_levels[0]);
    p.x = double(p.k) / edge_levels[0];
  } else if (i + j == n) {  // v1 -> v2
    p.edge = 1, p.k = snap(j, n, edge_levels[1]);
    p.y = double(p.k) / edge_levels[1];
    p.x = 1.0 - p.y;
  } else if (i == 0) {  // v2 -> v0
    p.edge = 2, p.k = snap(n - j, n, edge_levels[2]);
    p.y = 1.0 - double(p.k) / edge_levels[2];
  } else {
    p.x = double(i) / n;
    p.y = double(j) / n;
  }
  return p;
}

// Sub-triangle `local` of a level-n lattice: row j holds n - j triangles
// (i, j), (i+1, j), (i, j+1), then n - j - 1 triangles (i+1, j),
// (i+1, j+1), (i, j+1); row j starts at 2 n j - j^2.
void lattice_corners(std::uint64_t local, std::uint32_t n, std::uint32_t i[3], std::uint32_t j[3]) {
  auto start = [n](std::uint64_t row) { return 2 * std::uint64_t(n) * row - row * row; };
  auto row = static_cast<std::uint64_t>(double(n) -
                                        std::sqrt(std::max(0.0, double(n) * n - double(local))));
  while (row > 0 && start(row) > local) --row;
  while (row + 1 < n && start(row + 1) <= local) ++row;
  const auto r = static_cast<std::uint32_t>(local - start(row));
  const auto jj = static_cast<std::uint32_t>(row);
  if (r < n - jj) {
    i[0] = r, j[0] = jj, i[1] = r + 1, j[1] = jj, i[2] = r, j[2] = jj + 1;
  } else {
    const std::uint32_t ii = r - (n - jj);
    i[0] = ii + 1, j[0] = jj, i[1] = ii + 1, j[1] = jj + 1, i[2] = ii, j[2] = jj + 1;
  }
}

}  // namespace

MeshSubdivision plan_subdivision(const TriangleMesh& mesh, double edge) {
  MeshSubdivision plan;
  const std::size_t count = mesh.triangle_count();
  plan.levels.resize(count);
  plan.edge_levels.resize(3 * count);
  plan.first.resize(count + 1);
  plan.sub_edges.resize(count);
  for (std::size_t t = 0; t < count; ++t) {
    const unsigned* c = corners(mesh, std::uint32_t(t));
    std::uint32_t level = 1;
    double longest = 0.0;
    for (int e = 0; e < 3; ++e) {
      plan.edge_levels[3 * t + e] = edge_level(mesh, c[e], c[(e + 1) % 3], edge);
      level = std::max(level, plan.edge_levels[3 * t + e]);
      longest = std::max(longest, length(vertex(mesh, c[e]) - vertex(mesh, c[(e + 1) % 3])));
    }
    plan.levels[t] = level;
    plan.first[t + 1] = plan.first[t] + std::uint64_t(level) * level;
    plan.sub_edges[t] = float(2.0 * longest / level);
  }
  return plan;
}

void locate_in_base(const MeshSubdivision& plan, std::uint64_t prim, double b1, double b2,
                    std::uint32_t* base, double b[3]) {
  const auto t = static_cast<std::uint32_t>(
      std::upper_bound(plan.first.begin(), plan.first.end(), prim) - plan.first.begin() - 1);
  const std::uint32_t n = plan.levels[t];
  std::uint32_t i[3], j[3];
  lattice_corners(prim - plan.first[t], n, i, j);
  const double w[3] = {1.0 - b1 - b2, b1, b2};
  double x = 0.0, y = 0.0;
  for (int k = 0; k < 3; ++k) {
    const LatticePoint p = lattice_point(i[k], j[k], n, &plan.edge_levels[3 * std::size_t(t)]);
    x += w[k] * p.x;
    y += w[k] * p.y;
  }
  *base = t;
  b[0] = 1.0 - x - y;
  b[1] = x;
  b[2] = y;
}

TriangleMesh subdivide_displaced(const TriangleMesh& base, const MeshSubdivision& plan,
                                 const HeightFunction& height, double amplitude) {
  TriangleMesh out;
  // Corners first: vertex k of the base is vertex k here.
  for (unsigned k = 0; k < base.vertex_count(); ++k) {
    const double w = 1.0;
    append(&out.positions, displaced(base, &k, &w, 1, height, amplitude));
  }
  // Each edge's inner points once, walked from its lower vertex.
  std::unordered_map<std::uint64_t, unsigned> edge_first;
  const auto edge_point = [&](unsigned a, unsigned b, std::uint32_t n, std::uint32_t k) {
    // Point k of n from a to b.
    if (k == 0) return a;
    if (k == n) return b;
    const bool forward = a < b;
    const unsigned index[2] = {std::min(a, b), std::max(a, b)};
    const std::uint64_t key = (std::uint64_t(index[0]) << 32) | index[1];
    auto it = edge_first.find(key);
    if (it == edge_first.end()) {
      const auto first = unsigned(out.vertex_count());
      for (std::uint32_t s = 1; s < n; ++s) {
        const double w[2] = {double(n - s) / n, double(s) / n};
        append(&out.positions, displaced(base, index, w, 2, height, amplitude));
      }
      it = edge_first.emplace(key, first).first;
    }
    return it->second + (forward ? k : n - k) - 1;
  };
  out.triangles.reserve(3 * plan.triangle_count());
  std::vector<unsigned> ids;
  for (std::uint32_t t = 0; t < base.triangle_count(); ++t) {
    const unsigned* c = corners(base, t);
    const std::uint32_t n = plan.levels[t];
    const std::uint32_t* levels = &plan.edge_levels[3 * std::size_t(t)];
    ids.assign(std::size_t(n + 1) * (n + 1), 0);
    for (std::uint32_t j = 0; j <= n; ++j)
      for (std::uint32_t i = 0; i + j <= n; ++i) {
        unsigned& id = ids[std::size_t(j) * (n + 1) + i];
        const LatticePoint p = lattice_point(i, j, n, levels);
        if (p.edge >= 0) {
          id = edge_point(c[p.edge], c[(p.edge + 1) % 3], levels[p.edge], p.k);
        } else if (i == 0 && j == 0) {
          id = c[0];
        } else if (i == n) {
          id = c[1];
        } else if (j == n) {
          id = c[2];
        } else {
          id = unsigned(out.vertex_count());
          const double w[3] = {1.0 - p.x - p.y, p.x, p.y};
          append(&out.positions, displaced(base, c, w, 3, height, amplitude));
        }
      }
    const std::uint64_t per_triangle = std::uint64_t(n) * n;
    for (std::uint64_t local = 0; local < per_triangle; ++local) {
      std::uint32_t i[3], j[3];
      lattice_corners(local, n, i, j);
      for (int k = 0; k < 3; ++k) out.triangles.push_back(ids[std::size_t(j[k]) * (n + 1) + i[k]]);
    }
  }
  out.side_triangles = out.triangle_count();
  return out;
}

namespace {

// The exact normal of the truth at base barycentrics b of `triangle`; Ni
// where it is not finite (a degenerate triangle's cross product).
Vec3 export_normal(const TriangleMesh& base, std::uint32_t triangle, const double b[3],
                   const HeightFunction& height, double amplitude) {
  const SurfaceGeometry g = mesh_surface_at(base, triangle, b);
  const Vec3 n = mesh_displaced_normal(base, triangle, b, amplitude, evaluate_height(height, g.p));
  return std::isfinite(n.x) && std::isfinite(n.y) && std::isfinite(n.z) ? n : g.n;
}

}  // namespace

TriangleMesh displaced_mesh_for_export(const TriangleMesh& base, const MeshSubdivision& plan,
                                       const HeightFunction& height, double amplitude) {
  const TriangleMesh shared = subdivide_displaced(base, plan, height, amplitude);
  TriangleMesh out;
  std::unordered_map<unsigned, unsigned> own;  // shared vertex -> this triangle's copy
  constexpr double kCorner[3][2] = {{0.0, 0.0}, {1.0, 0.0}, {0.0, 1.0}};
  for (std::uint32_t t = 0; t < base.triangle_count(); ++t) {
    own.clear();
    for (std::uint64_t prim = plan.first[t]; prim < plan.first[t + 1]; ++prim) {
      const unsigned* v = &shared.triangles[3 * prim];
      if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) continue;
      for (int k = 0; k < 3; ++k) {
        const auto [it, added] = own.emplace(v[k], unsigned(out.vertex_count()));
        if (added) {
          std::uint32_t in_base = 0;
          double b[3];
          locate_in_base(plan, prim, kCorner[k][0], kCorner[k][1], &in_base, b);
          const float* p = &shared.positions[3 * std::size_t(v[k])];
          out.positions.insert(out.positions.end(), p, p + 3);
          append(&out.normals, export_normal(base, t, b, height, amplitude));
        }
        out.triangles.push_back(it->second);
      }
    }
  }
  out.side_triangles = out.triangle_count();
  return out;
}

}  // namespace penumbra
