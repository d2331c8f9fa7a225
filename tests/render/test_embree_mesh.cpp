// EmbreeMesh's packets against its single rays: the displacement truth
// traces in packets and must see what one ray at a time would.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "core/random.h"
#include "render/embree_mesh.h"

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

TEST(EmbreeMesh, PacketsSeeWhatSingleRaysSee) {
  Pcg32 rng(7);
  const EmbreeMesh mesh(triangle_soup(rng, 3000));
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
      EXPECT_EQ(packet_hits[k].triangle, single->triangle) << "ray " << first + k;
      EXPECT_EQ(std::memcmp(&packet_hits[k].t, &single->t, sizeof(double)), 0);
      EXPECT_EQ(std::memcmp(&packet_hits[k].b1, &single->b1, sizeof(double)), 0);
      EXPECT_EQ(std::memcmp(&packet_hits[k].b2, &single->b2, sizeof(double)), 0);
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

}  // namespace
}  // namespace penumbra
