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
#include "core/height.h"
#include "core/random.h"
#include "core/shape.h"
#include "core/vec.h"
#include "evaluator/embree_mesh.h"

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

// Whether `mesh` gives `rays` the same bits through the packet kernel as
// through the single-ray kernel.
inline bool packets_round_as_single_rays(const EmbreeMesh& mesh, const std::vector<Ray>& rays) {
  constexpr std::size_t kLanes = EmbreeMesh::kPacketRays;
  for (std::size_t first = 0; first + kLanes <= rays.size(); first += kLanes) {
    TriangleHit hits[kLanes];
    bool found[kLanes];
    mesh.intersect_packet(&rays[first], kLanes, hits, found);
    for (std::size_t k = 0; k < kLanes; ++k) {
      const auto single = mesh.intersect(rays[first + k]);
      if (found[k] != single.has_value()) return false;
      if (single && (hits[k].triangle != single->triangle ||
                     std::memcmp(&hits[k].t, &single->t, sizeof(double)) != 0 ||
                     std::memcmp(&hits[k].b1, &single->b1, sizeof(double)) != 0 ||
                     std::memcmp(&hits[k].b2, &single->b2, sizeof(double)) != 0))
        return false;
    }
  }
  return true;
}

// Whether this machine's Embree kernels round alike, on the two kinds of
// rays the tests compare: random rays at a soup of small triangles, and
// parallel camera rays, eight to a pixel, at a displaced sphere's grid as
// the truth builds it (with Embree's AVX kernels the first agreed and the
// second did not on 10 % of such rays).
inline bool embree_packets_round_as_single_rays() {
  static const bool alike = [] {
    Pcg32 rng(3);
    const auto coordinate = [&] { return 2.0 * rng.next_double() - 1.0; };
    TriangleMesh soup;
    for (unsigned v = 0; v < 3 * 2000; ++v) {
      soup.positions.insert(soup.positions.end(),
                            {float(coordinate()), float(coordinate()), float(coordinate())});
      soup.triangles.push_back(v);
    }
    soup.side_triangles = soup.triangle_count();
    std::vector<Ray> random_rays;
    for (int r = 0; r < 4000; ++r)
      random_rays.push_back({{coordinate(), coordinate(), -2.0},
                             normalize(Vec3{0.3 * coordinate(), 0.3 * coordinate(), 1.0})});
    if (!packets_round_as_single_rays(EmbreeMesh(std::move(soup), BvhBuild::kFastTrace),
                                      random_rays))
      return false;
    Shape sphere;
    sphere.type = ShapeType::kSphere;
    sphere = with_frame(sphere);
    std::vector<Ray> camera_rays;
    for (int pixel = 0; pixel < 500; ++pixel) {
      const double x = 0.9 * coordinate(), y = 0.9 * coordinate();
      for (int sample = 0; sample < 8; ++sample)
        camera_rays.push_back({{x + 0.002 * rng.next_double(), y + 0.002 * rng.next_double(), -3.0},
                               {0.0, 0.0, 1.0}});
    }
    const TriangleMesh grid = make_grid_mesh(sphere, make_grating({1, 0.2, 0}, 8.0, 0.02), 0.02,
                                             GridResolution{400, 200}, nullptr, GridNormals::kOmit);
    return packets_round_as_single_rays(EmbreeMesh(grid, BvhBuild::kFastBuild), camera_rays);
  }();
  return alike;
}

}  // namespace penumbra
