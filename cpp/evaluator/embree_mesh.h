// One triangle mesh in an Embree BVH: closest hits and occlusion, with the
// option to ignore one triangle (the one a shadow ray leaves), as Cycles does.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>

#include "core/grid_mesh.h"
#include "core/shape.h"

namespace penumbra {

inline constexpr std::uint32_t kNoTriangle = 0xffffffffu;

struct TriangleHit {
  double t = 0.0;
  std::uint32_t triangle = 0;
  double b1 = 0.0, b2 = 0.0;  // weights of the triangle's 2nd and 3rd vertex
};

// How Embree builds the BVH: the time to build and to trace, not the hits.
// Both test the same triangles with the same intersector; only where two
// triangles answer a ray at the same t (through a shared vertex or edge: 5
// of 10.9 M random rays on a 25,600-triangle sphere) may they keep
// different ones of the two, which are the same surface point to float
// rounding (tests/evaluator/test_embree_mesh.cpp).
// - kFastBuild: Embree's Morton builder (RTC_BUILD_QUALITY_LOW). On the
//   default sphere at edge 0.0015 (17.9 M triangles, 2 cores, with the
//   shared buffers below) it builds in 5.1 to 6.1 CPU-s against 8.8 to 12.9,
//   and peaks at 1.33 GB against 1.24;
// - kFastTrace: the binned SAH builder (Embree's default), whose rays run
//   about 10 % faster.
// A truth meets few rays per triangle (128x128 at 64 to 1024 spp: 0.06 to
// 15 camera samples per triangle), and the fast build won at every one
// measured, from 1.1 to 17.9 M triangles; a small mesh builds in a blink
// either way.
enum class BvhBuild { kFastBuild, kFastTrace };
inline constexpr std::size_t kFastBuildTriangles = 1'000'000;
// The build for a mesh of `triangles`: from the mesh alone, not the render,
// so that renders sharing a mesh never depend on which of them built it.
BvhBuild bvh_build_for(std::size_t triangles);

class EmbreeMesh {
 public:
  // Takes the mesh's positions and indices, which Embree reads in place
  // (no copy: on an 18 M-triangle truth they are 320 MB), and builds the BVH.
  explicit EmbreeMesh(TriangleMesh mesh, BvhBuild build);
  ~EmbreeMesh();
  EmbreeMesh(const EmbreeMesh&) = delete;
  EmbreeMesh& operator=(const EmbreeMesh&) = delete;

  std::optional<TriangleHit> intersect(const Ray& ray) const;
  // The closest hits of n <= kPacketRays rays at once, through Embree's
  // packet traversal (worth it for coherent rays, such as one pixel's
  // samples): the same hits as intersect(), found[k] saying whether hits[k]
  // was set; the same bits too where Embree's packet and single-ray kernels
  // round alike (its AVX-512 kernels, not its AVX2 ones with compact
  // leaves: there t differs by float ulps; tests/evaluator/embree_rounding.h).
  // Eight lanes, not sixteen: Embree 3.13.5's rtcOccluded16 (the Debian 12
  // build, AVX-512) never returned for one shadow ray of the default
  // sphere's truth, where rtcOccluded8 and rtcOccluded1 answered alike
  // (tests/test_embree_mesh.cpp keeps that ray).
  static constexpr std::size_t kPacketRays = 8;
  void intersect_packet(const Ray* rays, std::size_t n, TriangleHit* hits, bool* found) const;
  // Any hit with t in (t_min, t_max), ignoring triangle `skip`.
  bool occluded(const Ray& ray, double t_min, double t_max, std::uint32_t skip = kNoTriangle) const;
  // occluded() of n <= kPacketRays rays (t_min 0, no skipped triangle) at
  // once: blocked[k] for rays[k] up to t_max[k].
  void occluded_packet(const Ray* rays, const double* t_max, std::size_t n, bool* blocked) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace penumbra
