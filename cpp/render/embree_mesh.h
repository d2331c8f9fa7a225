// One triangle mesh in an Embree BVH: closest hits and occlusion, with the
// option to ignore one triangle (the one a shadow ray leaves), as Cycles does.
#pragma once

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
  // Any hit with t in (t_min, t_max), ignoring triangle `skip`.
  bool occluded(const Ray& ray, double t_min, double t_max, std::uint32_t skip = kNoTriangle) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace penumbra
