// What the tests may ask of Embree's float arithmetic. Embree picks its
// kernels when it starts, by the machine's instruction set, and promises
// the same closest hit from each, not the same rounding. Measured with
// Debian 12's Embree 3.13.5 and this project's scene flags (robust, compact
// leaves): on AVX-512 machines the packet kernels (rtcIntersect8,
// rtcOccluded8) and the single-ray ones gave the same bits on every ray the
// tests try; on an AVX2-only machine (2-core AMD EPYC) they differ on most
// hits by float rounding (t by a few ulps, the barycentrics by more on
// thin triangles), and a ray aimed exactly at a vertex at a grazing angle
// got t 46 float ulps from the exact value. So a test demands the same
// bits only where this machine's kernels round alike, and otherwise the
// same hit to float rounding, scaled by how ill-conditioned the hit is.
#pragma once

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <vector>

#include "core/grid_mesh.h"
#include "core/random.h"
#include "core/vec.h"
#include "render/embree_mesh.h"

namespace penumbra {

// How far two float evaluations of one ray-triangle hit (its t, or the
// surface point) may lie apart: Embree works in float, so each carries
// float ulps of the ray's extent (origin and distance, in scene units),
// amplified by 1 / |cos| of the angle between the ray and the triangle's
// normal (a grazing ray's hit slides along the triangle). 64 ulps: the
// grazing vertex hit above needed 27 before the cosine.
inline double hit_tolerance(const Ray& ray, double t, const Vec3& triangle_normal) {
  const double cos_theta = std::abs(dot(normalize(triangle_normal), ray.direction));
  return 64.0 * FLT_EPSILON * (length(ray.origin) + t) / std::max(cos_theta, 1e-3);
}

// Whether this machine's Embree kernels round alike: 4,000 random rays at a
// soup of small triangles, through the packet and the single-ray kernel.
inline bool embree_packets_round_as_single_rays() {
  static const bool alike = [] {
    Pcg32 rng(3);
    const auto coordinate = [&] { return float(2.0 * rng.next_double() - 1.0); };
    TriangleMesh soup;
    for (unsigned v = 0; v < 3 * 2000; ++v) {
      soup.positions.insert(soup.positions.end(), {coordinate(), coordinate(), coordinate()});
      soup.triangles.push_back(v);
    }
    soup.side_triangles = soup.triangle_count();
    const EmbreeMesh mesh(std::move(soup), BvhBuild::kFastTrace);
    for (int packet = 0; packet < 500; ++packet) {
      Ray rays[EmbreeMesh::kPacketRays];
      for (Ray& r : rays)
        r = {{coordinate(), coordinate(), -2.0},
             normalize(Vec3{0.3 * coordinate(), 0.3 * coordinate(), 1.0})};
      TriangleHit hits[EmbreeMesh::kPacketRays];
      bool found[EmbreeMesh::kPacketRays];
      mesh.intersect_packet(rays, EmbreeMesh::kPacketRays, hits, found);
      for (std::size_t k = 0; k < EmbreeMesh::kPacketRays; ++k) {
        const auto single = mesh.intersect(rays[k]);
        if (found[k] != single.has_value()) return false;
        if (single && (hits[k].triangle != single->triangle ||
                       std::memcmp(&hits[k].t, &single->t, sizeof(double)) != 0 ||
                       std::memcmp(&hits[k].b1, &single->b1, sizeof(double)) != 0 ||
                       std::memcmp(&hits[k].b2, &single->b2, sizeof(double)) != 0))
          return false;
      }
    }
    return true;
  }();
  return alike;
}

}  // namespace penumbra
