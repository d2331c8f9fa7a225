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

class EmbreeMesh {
 public:
  // Copies the positions and indices into Embree's buffers and builds the BVH.
  explicit EmbreeMesh(const TriangleMesh& mesh);
  ~EmbreeMesh();
  EmbreeMesh(const EmbreeMesh&) = delete;
  EmbreeMesh& operator=(const EmbreeMesh&) = delete;

  std::optional<TriangleHit> intersect(const Ray& ray) const;
  // The closest hits of n <= kPacketRays rays at once, through Embree's
  // packet traversal (worth it for coherent rays, such as one pixel's
  // samples): the same hits as intersect(), found[k] saying whether hits[k]
  // was set. Eight lanes, not sixteen: Embree 3.13.5's rtcOccluded16 (the
  // Debian 12 build, AVX-512) never returned for one shadow ray of the
  // default sphere's truth, where rtcOccluded8 and rtcOccluded1 answered
  // alike (tests/test_embree_mesh.cpp keeps that ray).
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
