// EmbreeMesh's packets against its single rays, and its two BVH builds
// against each other: the displacement truth traces in packets, on a BVH
// built for speed, and must see what one ray at a time on either BVH would:
// the same bits where this machine's Embree kernels round alike, else the
// same hits to float rounding (embree_rounding.h).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <vector>

#include "core/grid_mesh.h"
#include "core/height.h"
#include "core/random.h"
#include "evaluator/embree_mesh.h"
#include "evaluator/embree_rounding.h"

namespace penumbra {
namespace {

// A soup of small random triangles in [-1, 1]^3 plus a plane of two large
// ones, so rays hit, miss, graze and cross shared edges.
TriangleMesh triangle_soup(Pcg32& rng, int count) {
  TriangleMesh mesh;
  auto coordinate = [&] { return float(2.0 * rng.next_double() - 1.0); };
  for (int t = 0; t < count; ++t) {
    const float cx = coordinate(), cy = coordinate(), cz = coordinate();
    for (int v = 0; v < 3; ++v) {
      mesh.positions.insert(
          mesh.positions.end(),
          {cx + 0.2f * coordinate(), cy + 0.2f * coordinate(), cz + 0.2f * coordinate()});
      mesh.triangles.push_back(unsigned(3 * t + v));
    }
  }
  const unsigned base = unsigned(mesh.vertex_count());
  mesh.positions.insert(mesh.positions.end(), {-2, -2, 0.5f, 2, -2, 0.5f, 2, 2, 0.5f, -2, 2, 0.5f});
  mesh.triangles.insert(mesh.triangles.end(),
                        {base, base + 1, base + 2, base, base + 2, base + 3});  // shared edge
  mesh.side_triangles = mesh.triangle_count();
  return mesh;
}

// Random rays, a quarter of them with a direction component exactly zero
// (as the default light's y), and some along the shared diagonal.
std::vector<Ray> random_rays(Pcg32& rng, int count) {
  std::vector<Ray> rays;
  for (int r = 0; r < count; ++r) {
    Vec3 d{2.0 * rng.next_double() - 1.0, 2.0 * rng.next_double() - 1.0,
           2.0 * rng.next_double() - 1.0};
    if (r % 4 == 1) d.y = 0.0;
    if (r % 4 == 2) d = {0.0, 0.0, 1.0};
    Vec3 o{1.5 * rng.next_double() - 0.75, 1.5 * rng.next_double() - 0.75,
           3.0 * rng.next_double() - 1.5};
    if (r % 16 == 3) o = {0.25 * rng.next_double(), 0.0, -2.0}, o.y = o.x, d = {0.0, 0.0, 1.0};
    rays.push_back({o, normalize(d)});
  }
  return rays;
}

// Vertex k of triangle `triangle` of `mesh`.
Vec3 vertex_of(const TriangleMesh& mesh, std::uint32_t triangle, int k) {
  const float* p = &mesh.positions[3 * std::size_t(mesh.triangles[3 * triangle + k])];
  return Vec3{p[0], p[1], p[2]};
}
Vec3 point_of(const TriangleMesh& mesh, const TriangleHit& h) {
  return (1.0 - h.b1 - h.b2) * vertex_of(mesh, h.triangle, 0) +
         h.b1 * vertex_of(mesh, h.triangle, 1) + h.b2 * vertex_of(mesh, h.triangle, 2);
}
Vec3 normal_of(const TriangleMesh& mesh, std::uint32_t triangle) {
  const Vec3 v0 = vertex_of(mesh, triangle, 0);
  return cross(vertex_of(mesh, triangle, 1) - v0, vertex_of(mesh, triangle, 2) - v0);
}

// Two hits of `ray` on the same triangle: the same bits, or (`exact` false)
// the same t and surface point to float rounding.
void expect_same_hit(const TriangleMesh& mesh, const Ray& ray, const TriangleHit& a,
                     const TriangleHit& b, bool exact, const std::string& what) {
  if (exact) {
    EXPECT_EQ(std::memcmp(&a.t, &b.t, sizeof(double)), 0) << what;
    EXPECT_EQ(std::memcmp(&a.b1, &b.b1, sizeof(double)), 0) << what;
    EXPECT_EQ(std::memcmp(&a.b2, &b.b2, sizeof(double)), 0) << what;
    return;
  }
  const double tolerance = hit_tolerance(ray, a.t, normal_of(mesh, a.triangle));
  EXPECT_NEAR(a.t, b.t, tolerance) << what;
  EXPECT_LT(length(point_of(mesh, a) - point_of(mesh, b)), tolerance) << what;
}

TEST(EmbreeMesh, PacketsSeeWhatSingleRaysSee) {
  const bool exact = embree_packets_round_as_single_rays();
  RecordProperty("embree_packets_round_as_single_rays", exact ? "yes" : "no");
  Pcg32 rng(7);
  const TriangleMesh soup = triangle_soup(rng, 3000);
  const EmbreeMesh mesh(TriangleMesh(soup), BvhBuild::kFastBuild);
  const std::vector<Ray> rays = random_rays(rng, 4000);
  std::size_t hits = 0, blocked_count = 0;
  for (std::size_t first = 0, n = 1; first < rays.size(); first += n, n = n % 8 + 1) {
    n = std::min(n, rays.size() - first);  // every packet fill from 1 to 8 lanes
    const Ray* packet = &rays[first];
    TriangleHit packet_hits[EmbreeMesh::kPacketRays];
    bool found[EmbreeMesh::kPacketRays], blocked[EmbreeMesh::kPacketRays];
    double t_max[EmbreeMesh::kPacketRays];
    mesh.intersect_packet(packet, n, packet_hits, found);
    for (std::size_t k = 0; k < n; ++k) {
      const auto single = mesh.intersect(packet[k]);
      ASSERT_EQ(found[k], single.has_value()) << "ray " << first + k;
      t_max[k] = k % 3 == 0 ? std::numeric_limits<double>::infinity() : 2.0 * rng.next_double();
      if (!single) continue;
      ++hits;
      ASSERT_EQ(packet_hits[k].triangle, single->triangle) << "ray " << first + k;
      expect_same_hit(soup, packet[k], packet_hits[k], *single, exact,
                      "ray " + std::to_string(first + k));
    }
    mesh.occluded_packet(packet, t_max, n, blocked);
    for (std::size_t k = 0; k < n; ++k) {
      EXPECT_EQ(blocked[k], mesh.occluded(packet[k], 0.0, t_max[k])) << "ray " << first + k;
      blocked_count += blocked[k];
    }
  }
  // Neither all nor none: the comparison covers both answers.
  EXPECT_GT(hits, rays.size() / 10);
  EXPECT_LT(hits, rays.size() * 9 / 10);
  EXPECT_GT(blocked_count, rays.size() / 10);
  EXPECT_LT(blocked_count, rays.size() * 9 / 10);
}

// A displaced sphere's grid, as the truth builds it, under both builds. The
// BVH decides which triangles a ray visits first; where two triangles answer
// a ray at the same t (a ray through a shared vertex or edge: aimed at one,
// as here; of 10.9 M parallel rays that hit this sphere at random points,
// 5), the first one found keeps the hit. So a ray aimed inside a triangle
// must get the same hit, bit for bit, from both builds (the same kernel on
// the same triangle); one aimed at a vertex or an edge the same point of the
// surface, up to float rounding (hit_tolerance: on an AVX2 machine a grazing
// ray aimed at a vertex met the two triangles' hits 4.9e-4 apart); every
// occlusion verdict must agree.
TEST(EmbreeMesh, BothBuildsFindTheSameSurfacePoints) {
  Shape shape;
  shape.type = ShapeType::kSphere;
  shape = with_frame(shape);
  const TriangleMesh grid = make_grid_mesh(shape, make_grating({1, 0.2, 0}, 8.0, 0.3), 0.02,
                                           GridResolution{160, 80}, nullptr, GridNormals::kOmit);
  const EmbreeMesh fast_build(grid, BvhBuild::kFastBuild), fast_trace(grid, BvhBuild::kFastTrace);
  Pcg32 rng(11);
  std::size_t hits = 0, ties = 0, blocked = 0, rays = 0;
  for (std::uint32_t t = 0; t < grid.triangle_count(); t += 7, ++rays) {
    const int kind = int(t % 3);  // aimed at a vertex, an edge's midpoint, the centroid
    const Vec3 target =
        kind == 0   ? vertex_of(grid, t, 0)
        : kind == 1 ? 0.5 * (vertex_of(grid, t, 0) + vertex_of(grid, t, 1))
                    : (vertex_of(grid, t, 0) + vertex_of(grid, t, 1) + vertex_of(grid, t, 2)) / 3.0;
    const Vec3 from{4.0 * rng.next_double() - 2.0, 4.0 * rng.next_double() - 2.0, -3.0};
    const Ray ray{from, normalize(target - from)};
    const auto a = fast_build.intersect(ray), b = fast_trace.intersect(ray);
    ASSERT_EQ(a.has_value(), b.has_value()) << "ray " << t;
    const double t_max = length(target - from) * (0.5 + rng.next_double());
    const bool occluded = fast_build.occluded(ray, 0.0, t_max, t);
    EXPECT_EQ(occluded, fast_trace.occluded(ray, 0.0, t_max, t)) << "ray " << t;
    blocked += occluded;
    if (!a) continue;
    ++hits;
    if (kind == 2 || a->triangle == b->triangle) {
      EXPECT_EQ(a->triangle, b->triangle) << "ray " << t;
      EXPECT_EQ(std::memcmp(&a->t, &b->t, sizeof(double)), 0) << "ray " << t;
      EXPECT_EQ(std::memcmp(&a->b1, &b->b1, sizeof(double)), 0) << "ray " << t;
      EXPECT_EQ(std::memcmp(&a->b2, &b->b2, sizeof(double)), 0) << "ray " << t;
      continue;
    }
    ++ties;
    // Float t and barycentrics: float ulps of the ray's extent, more where
    // the ray grazes either triangle.
    const double tolerance = std::max(hit_tolerance(ray, a->t, normal_of(grid, a->triangle)),
                                      hit_tolerance(ray, b->t, normal_of(grid, b->triangle)));
    EXPECT_NEAR(a->t, b->t, tolerance) << "ray " << t;
    EXPECT_LT(length(point_of(grid, *a) - point_of(grid, *b)), tolerance) << "ray " << t;
  }
  EXPECT_GT(hits, rays / 2);  // most rays reach the sphere's near side
  EXPECT_GT(ties, 0u);        // the vertex- and edge-aimed rays do meet ties
  EXPECT_GT(blocked, rays / 10);
  EXPECT_LT(blocked, rays * 9 / 10);
}

// The build follows the mesh alone, at the documented threshold.
TEST(EmbreeMesh, BuildChosenByTriangleCount) {
  EXPECT_EQ(bvh_build_for(kFastBuildTriangles - 1), BvhBuild::kFastTrace);
  EXPECT_EQ(bvh_build_for(kFastBuildTriangles), BvhBuild::kFastBuild);
}

}  // namespace
}  // namespace penumbra
