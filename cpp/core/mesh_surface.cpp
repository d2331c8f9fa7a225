#include "core/mesh_surface.h"

#include <algorithm>
#include <cmath>
#include <cstring>
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

// h at a lattice point: of its position, or of its UV where a map is laid
// over the mesh.
double lattice_height(const MeshHeight& height, const Vec3& p, double u, double v) {
  if (!height.map) return evaluate_height(height.function, p).h;
  return sample_map(*height.map, u * height.map->tiles_u, v * height.map->tiles_v).value;
}

// P + A h Ni with P, Ni and the UV from weights w over vertices index[k]
// (uv[k] their coordinates in the triangle that places the point; uv null
// without a map).
Vec3 displaced(const TriangleMesh& m, const unsigned* index, const double* w,
               const float* const* uv, int count, const MeshHeight& height, double amplitude) {
  Vec3 p, n;
  double u = 0.0, v = 0.0;
  for (int k = 0; k < count; ++k) {
    p += vertex(m, index[k]) * w[k];
    n += normal(m, index[k]) * w[k];
    if (uv) {
      u += w[k] * uv[k][0];
      v += w[k] * uv[k][1];
    }
  }
  if (amplitude == 0.0) return p;
  const double length_n = length(n);
  if (!(length_n > 0.0)) return p;
  return p + n * (amplitude * lattice_height(height, p, u, v) / length_n);
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
  g.u = b[1];
  g.v = b[2];
  g.triangle = triangle;
  return g;
}

Vec3 facet_bump_gradient(const Vec3& gradient, const Vec3& ng, const Vec3& ni) {
  // Either side of ng gives the same g'; ni in the triangle's plane (a
  // broken vertex normal) has no such vector, and the projection stands in.
  const double cos_delta = dot(ng, ni);
  if (std::abs(cos_delta) < 1e-9) return gradient - ni * dot(gradient, ni);
  const Vec3 in_plane = gradient - ng * dot(gradient, ng);
  return in_plane - ng * (dot(in_plane, ni) / cos_delta);
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

TriangleMesh subdivide_displaced(const MeshSurface& surface, const MeshSubdivision& plan,
                                 const MeshHeight& height, double amplitude) {
  const TriangleMesh& base = surface.mesh;
  const bool by_uv = height.map != nullptr;
  // A corner's UV where the vertex is first used.
  std::vector<const float*> vertex_uv(by_uv ? base.vertex_count() : 0, nullptr);
  for (std::size_t t = 0; by_uv && t < base.triangle_count(); ++t)
    for (std::size_t k = 0; k < 3; ++k)
      if (!vertex_uv[base.triangles[3 * t + k]])
        vertex_uv[base.triangles[3 * t + k]] = &surface.uvs[6 * t + 2 * k];
  TriangleMesh out;
  // Corners first: vertex k of the base is vertex k here.
  for (unsigned k = 0; k < base.vertex_count(); ++k) {
    const double w = 1.0;
    const float* uv = by_uv ? vertex_uv[k] : nullptr;
    append(&out.positions, displaced(base, &k, &w, by_uv ? &uv : nullptr, 1, height, amplitude));
  }
  // Each edge's inner points once, walked from its lower vertex, with the
  // UVs of the triangle that meets it first.
  std::unordered_map<std::uint64_t, unsigned> edge_first;
  const auto edge_point = [&](unsigned a, unsigned b, const float* uv_a, const float* uv_b,
                              std::uint32_t n, std::uint32_t k) {
    // Point k of n from a to b.
    if (k == 0) return a;
    if (k == n) return b;
    const bool forward = a < b;
    const unsigned index[2] = {std::min(a, b), std::max(a, b)};
    const float* uv[2] = {forward ? uv_a : uv_b, forward ? uv_b : uv_a};
    const std::uint64_t key = (std::uint64_t(index[0]) << 32) | index[1];
    auto it = edge_first.find(key);
    if (it == edge_first.end()) {
      const auto first = unsigned(out.vertex_count());
      for (std::uint32_t s = 1; s < n; ++s) {
        const double w[2] = {double(n - s) / n, double(s) / n};
        append(&out.positions,
               displaced(base, index, w, by_uv ? uv : nullptr, 2, height, amplitude));
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
    const float* uv[3] = {nullptr, nullptr, nullptr};
    for (std::size_t k = 0; by_uv && k < 3; ++k) uv[k] = &surface.uvs[6 * std::size_t(t) + 2 * k];
    ids.assign(std::size_t(n + 1) * (n + 1), 0);
    for (std::uint32_t j = 0; j <= n; ++j)
      for (std::uint32_t i = 0; i + j <= n; ++i) {
        unsigned& id = ids[std::size_t(j) * (n + 1) + i];
        const LatticePoint p = lattice_point(i, j, n, levels);
        if (p.edge >= 0) {
          const int e0 = p.edge, e1 = (p.edge + 1) % 3;
          id = edge_point(c[e0], c[e1], uv[e0], uv[e1], levels[p.edge], p.k);
        } else if (i == 0 && j == 0) {
          id = c[0];
        } else if (i == n) {
          id = c[1];
        } else if (j == n) {
          id = c[2];
        } else {
          id = unsigned(out.vertex_count());
          const double w[3] = {1.0 - p.x - p.y, p.x, p.y};
          append(&out.positions, displaced(base, c, w, by_uv ? uv : nullptr, 3, height, amplitude));
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
Vec3 export_normal(const MeshSurface& base, std::uint32_t triangle, const double b[3],
                   const MeshHeight& height, double amplitude) {
  const SurfaceGeometry g = mesh_surface_at(base.mesh, triangle, b);
  const Vec3 n = mesh_displaced_normal(base.mesh, triangle, b, amplitude,
                                       mesh_height_at(height.function, height.map, base, g));
  return std::isfinite(n.x) && std::isfinite(n.y) && std::isfinite(n.z) ? n : g.n;
}

}  // namespace

TriangleMesh displaced_mesh_for_export(const MeshSurface& base, const MeshSubdivision& plan,
                                       const MeshHeight& height, double amplitude) {
  const TriangleMesh shared = subdivide_displaced(base, plan, height, amplitude);
  TriangleMesh out;
  std::unordered_map<unsigned, unsigned> own;  // shared vertex -> this triangle's copy
  constexpr double kCorner[3][2] = {{0.0, 0.0}, {1.0, 0.0}, {0.0, 1.0}};
  for (std::uint32_t t = 0; t < base.mesh.triangle_count(); ++t) {
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

namespace penumbra {

namespace {

// A MikkTSpace vertex: the welded vertex (position and normal) with one
// UV's bits.
struct TangentKey {
  unsigned vertex = 0;
  std::uint32_t u = 0, v = 0;
  bool operator==(const TangentKey&) const = default;
};

struct TangentKeyHash {
  std::size_t operator()(const TangentKey& k) const {
    std::uint64_t h = k.vertex;
    h = h * 0x9E3779B97F4A7C15ull ^ k.u;
    h = h * 0x9E3779B97F4A7C15ull ^ k.v;
    return std::size_t(h ^ (h >> 29));
  }
};

// v - n <n, v>, normalised (zero stays zero); n unit in all but odd files.
Vec3 project_unit(const Vec3& n, const Vec3& v) {
  const Vec3 p = v - n * dot(n, v);
  const double l = length(p);
  return l > 0.0 ? p / l : p;
}

// One triangle's signed direction of increasing u (MikkTSpace's eq. 18),
// its orientation, and whether it contributes (a nonzero UV area and both
// directions nonzero; otherwise it joins the first group that reaches it).
struct FaceTangent {
  Vec3 tangent;
  bool preserving = false, contributes = false;
};

FaceTangent face_tangent(const TriangleMesh& m, const std::vector<float>& uvs, std::size_t t) {
  // In float, as MikkTSpace computes them: whether a UV area is zero, and its
  // sign, decide a triangle's group, and a nearly collinear UV triangle's
  // area can round to zero or change sign between float and double.
  const unsigned* c = &m.triangles[3 * t];
  const float* uv = &uvs[6 * t];
  const float t21x = uv[2] - uv[0], t21y = uv[3] - uv[1];
  const float t31x = uv[4] - uv[0], t31y = uv[5] - uv[1];
  const float area2 = t21x * t31y - t21y * t31x;
  float d1[3], d2[3], os[3], ot[3];
  for (int a = 0; a < 3; ++a) {
    d1[a] = m.positions[3 * c[1] + a] - m.positions[3 * c[0] + a];
    d2[a] = m.positions[3 * c[2] + a] - m.positions[3 * c[0] + a];
    os[a] = t31y * d1[a] - t21y * d2[a];
    ot[a] = -t31x * d1[a] + t21x * d2[a];
  }
  const float os2 = os[0] * os[0] + os[1] * os[1] + os[2] * os[2];
  const float ot2 = ot[0] * ot[0] + ot[1] * ot[1] + ot[2] * ot[2];
  const auto not_zero = [](float x) { return std::abs(x) > std::numeric_limits<float>::min(); };
  FaceTangent f;
  f.preserving = area2 > 0.0f;
  if (!not_zero(area2)) return f;
  if (not_zero(os2))
    f.tangent = Vec3{os[0], os[1], os[2]} * ((f.preserving ? 1.0 : -1.0) / std::sqrt(double(os2)));
  f.contributes = not_zero(os2) && not_zero(ot2);
  return f;
}

constexpr std::uint32_t kUnset = ~0u;

// MikkTSpace's vertex of every corner.
std::vector<std::uint32_t> tangent_vertices(const TriangleMesh& m, const std::vector<float>& uvs) {
  std::unordered_map<TangentKey, std::uint32_t, TangentKeyHash> ids;
  std::vector<std::uint32_t> out(m.triangles.size());
  for (std::size_t c = 0; c < out.size(); ++c) {
    TangentKey key;
    key.vertex = m.triangles[c];
    std::memcpy(&key.u, &uvs[2 * c], sizeof key.u);
    std::memcpy(&key.v, &uvs[2 * c + 1], sizeof key.v);
    out[c] = ids.emplace(key, std::uint32_t(ids.size())).first->second;
  }
  return out;
}

// The triangle across each corner's edge (corner i to i + 1), kUnset where
// none: the first later edge, in triangle order, that runs the other way
// between the same two vertices.
std::vector<std::uint32_t> edge_neighbours(const std::vector<std::uint32_t>& ids) {
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> by_edge;
  const auto from = [&](std::uint32_t c) { return ids[c]; };
  const auto to = [&](std::uint32_t c) { return ids[c - c % 3 + (c % 3 + 1) % 3]; };
  for (std::uint32_t c = 0; c < ids.size(); ++c) {
    const std::uint32_t lo = std::min(from(c), to(c)), hi = std::max(from(c), to(c));
    by_edge[(std::uint64_t(lo) << 32) | hi].push_back(c);
  }
  std::vector<std::uint32_t> out(ids.size(), kUnset);
  for (const auto& [key, list] : by_edge)
    for (std::size_t a = 0; a < list.size(); ++a) {
      if (out[list[a]] != kUnset) continue;
      for (std::size_t b = a + 1; b < list.size(); ++b)
        if (out[list[b]] == kUnset && from(list[a]) == to(list[b]) &&
            to(list[a]) == from(list[b])) {
          out[list[a]] = list[b] / 3;
          out[list[b]] = list[a] / 3;
          break;
        }
    }
  return out;
}

struct TangentGroup {
  Vec3 tangent;
  std::uint32_t vertex = 0;
  bool preserving = false;
};

// MikkTSpace's groups: the triangles around a vertex reached through shared
// edges with the group's orientation, started in triangle and corner order;
// a triangle that does not contribute takes the orientation of the first
// group that reaches it.
class TangentGrouping {
 public:
  TangentGrouping(const std::vector<std::uint32_t>& ids,
                  const std::vector<std::uint32_t>& neighbours, std::vector<FaceTangent>& faces)
      : ids_(ids), neighbours_(neighbours), faces_(faces), group_(ids.size(), kUnset) {
    for (std::uint32_t t = 0; t < faces.size(); ++t)
      for (std::uint32_t i = 0; i < 3; ++i) {
        if (!faces[t].contributes || group_[3 * t + i] != kUnset) continue;
        const auto g = std::uint32_t(groups.size());
        groups.push_back({{}, ids[3 * t + i], faces[t].preserving});
        group_[3 * t + i] = g;
        assign(neighbours[3 * t + i], g);
        assign(neighbours[3 * t + (i + 2) % 3], g);
      }
  }
  std::uint32_t group_of(std::size_t corner) const { return group_[corner]; }
  std::vector<TangentGroup> groups;

 private:
  void assign(std::uint32_t t, std::uint32_t g) {
    if (t == kUnset) return;
    std::uint32_t i = 0;
    while (i < 3 && ids_[3 * t + i] != groups[g].vertex) ++i;
    if (i == 3 || group_[3 * t + i] != kUnset) return;
    FaceTangent& face = faces_[t];
    if (!face.contributes && group_[3 * t] == kUnset && group_[3 * t + 1] == kUnset &&
        group_[3 * t + 2] == kUnset)
      face.preserving = groups[g].preserving;
    if (face.preserving != groups[g].preserving) return;
    group_[3 * t + i] = g;
    assign(neighbours_[3 * t + i], g);
    assign(neighbours_[3 * t + (i + 2) % 3], g);
  }

  const std::vector<std::uint32_t>& ids_;
  const std::vector<std::uint32_t>& neighbours_;
  std::vector<FaceTangent>& faces_;
  std::vector<std::uint32_t> group_;
};

}  // namespace

namespace {

// Whether triangle t is wound against its vertex normals (its Ng away from
// their sum).
bool wound_against_normals(const TriangleMesh& m, std::size_t t) {
  const unsigned* c = &m.triangles[3 * t];
  const Vec3 ng = cross(vertex(m, c[1]) - vertex(m, c[0]), vertex(m, c[2]) - vertex(m, c[0]));
  return dot(ng, normal(m, c[0]) + normal(m, c[1]) + normal(m, c[2])) < 0.0;
}

std::vector<float> tangents_as_wound(const TriangleMesh& m, const std::vector<float>& uvs);

}  // namespace

std::vector<float> mikktspace_tangents(const TriangleMesh& m, const std::vector<float>& uvs) {
  // MikkTSpace's sign assumes a triangle is wound about its normal; a file
  // that winds some against their normals (the 24-segment UV tessellation
  // winds all but its pole fans inward) gets those rewound first, as the
  // Blender export rewinds them for Cycles, and its corners' tangents back
  // in the file's order.
  std::vector<std::size_t> rewound;
  for (std::size_t t = 0; t < m.triangle_count(); ++t)
    if (wound_against_normals(m, t)) rewound.push_back(t);
  if (rewound.empty()) return tangents_as_wound(m, uvs);
  TriangleMesh wound = m;
  std::vector<float> wound_uvs = uvs;
  for (std::size_t t : rewound) {
    std::swap(wound.triangles[3 * t + 1], wound.triangles[3 * t + 2]);
    std::swap(wound_uvs[6 * t + 2], wound_uvs[6 * t + 4]);
    std::swap(wound_uvs[6 * t + 3], wound_uvs[6 * t + 5]);
  }
  std::vector<float> out = tangents_as_wound(wound, wound_uvs);
  for (std::size_t t : rewound)
    for (std::size_t a = 0; a < 4; ++a) std::swap(out[12 * t + 4 + a], out[12 * t + 8 + a]);
  return out;
}

namespace {

std::vector<float> tangents_as_wound(const TriangleMesh& m, const std::vector<float>& uvs) {
  const std::size_t count = m.triangle_count();
  std::vector<FaceTangent> faces(count);
  for (std::size_t t = 0; t < count; ++t) faces[t] = face_tangent(m, uvs, t);
  const std::vector<std::uint32_t> ids = tangent_vertices(m, uvs);
  TangentGrouping grouping(ids, edge_neighbours(ids), faces);
  std::vector<TangentGroup>& groups = grouping.groups;
  for (std::size_t t = 0; t < count; ++t) {
    if (!faces[t].contributes) continue;
    const unsigned* c = &m.triangles[3 * t];
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t g = grouping.group_of(3 * t + k);
      if (g == kUnset) continue;
      // The normal as stored, not normalised, as MikkTSpace takes it: a
      // file's normal that is not unit tilts the projection the same way
      // in Blender.
      const Vec3 n = normal(m, c[k]);
      const Vec3 p = vertex(m, c[k]);
      const double cos_angle = dot(project_unit(n, vertex(m, c[(k + 1) % 3]) - p),
                                   project_unit(n, vertex(m, c[(k + 2) % 3]) - p));
      groups[g].tangent +=
          project_unit(n, faces[t].tangent) * std::acos(std::clamp(cos_angle, -1.0, 1.0));
    }
  }
  std::vector<float> out(12 * count);
  for (std::size_t c = 0; c < 3 * count; ++c) {
    // A corner no group reached keeps MikkTSpace's default: (1, 0, 0), -1.
    Vec3 tangent{1.0, 0.0, 0.0};
    bool preserving = false;
    if (const std::uint32_t g = grouping.group_of(c); g != kUnset) {
      if (length_squared(groups[g].tangent) > 0.0) tangent = normalize(groups[g].tangent);
      preserving = groups[g].preserving;
    }
    float* o = &out[4 * c];
    o[0] = float(tangent.x);
    o[1] = float(tangent.y);
    o[2] = float(tangent.z);
    o[3] = preserving ? 1.0f : -1.0f;
  }
  return out;
}

}  // namespace

}  // namespace penumbra
