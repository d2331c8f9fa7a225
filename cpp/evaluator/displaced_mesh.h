// The displaced surface P' = P + A h(P) N(P) as a fine triangle mesh traced
// with Embree: the ground truth of the bump representations.
//
// The mesh is a regular grid over the shape's (u, v) parameters, so a hit's
// parameters follow from the primitive id and barycentrics without storing
// anything per triangle; shading then evaluates the exact displaced normal at
// those parameters. Only the occlusion test relies on the flat triangles.
// A mesh shape's truth is its triangles split on a barycentric lattice
// (core/mesh_surface.h, subdivide_displaced), decoded the same way.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/shape.h"
#include "evaluator/embree_mesh.h"
#include "scene/scene.h"

namespace penumbra {

struct MeshHit {
  double t = 0.0;
  SurfaceGeometry geometry;  // base-surface geometry under the hit
  // A mesh shape's truth: the base triangle and barycentrics under the hit
  // (mesh_displaced_normal's arguments).
  bool on_mesh = false;
  std::uint32_t base_triangle = 0;
  double base_b[3] = {1.0, 0.0, 0.0};
};

class DisplacedMesh {
 public:
  // Builds the mesh and its BVH. Edge length from scene.displacement.
  explicit DisplacedMesh(const Scene& scene);
  ~DisplacedMesh();
  DisplacedMesh(const DisplacedMesh&) = delete;
  DisplacedMesh& operator=(const DisplacedMesh&) = delete;

  std::optional<MeshHit> intersect(const Ray& ray) const;
  // intersect() of n <= kPacketRays rays at once (one Embree packet); the
  // same hits, found[k] saying whether hits[k] was set.
  static constexpr std::size_t kPacketRays = EmbreeMesh::kPacketRays;
  void intersect_packet(const Ray* rays, std::size_t n, MeshHit* hits, bool* found) const;
  bool occluded(const Ray& ray, double t_max) const;
  // occluded() of n <= kPacketRays rays at once.
  void occluded_packet(const Ray* rays, const double* t_max, std::size_t n, bool* blocked) const;

  std::size_t triangle_count() const { return triangles_; }
  std::size_t vertex_count() const { return vertices_; }
  // Distance by which a shadow ray leaves the exact surface point: an upper
  // bound of how far a triangle's interior deviates from the surface (chord
  // sagitta e^2 kappa / 8), so the ray clears the local facets.
  // A mesh shape's bound is its base triangle's (`triangle`, MeshHit::
  // base_triangle): one curved corner of an asset must not lift every
  // shadow ray of the others over their own detail.
  double shadow_offset(std::uint32_t triangle = 0) const {
    return offsets_.empty() ? shadow_offset_ : offsets_[triangle];
  }

 private:
  void build_mesh_shape(const Scene& scene);

  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::size_t triangles_ = 0, vertices_ = 0;
  double shadow_offset_ = 0.0;
  std::vector<float> offsets_;  // per base triangle of a mesh shape
};

// What a mesh is built from: the shape, the height field, its amplitude and
// the edge length (hex floats, exact). Renders whose keys are equal can share
// one mesh; light, material, camera and method do not enter.
std::string displaced_mesh_key(const Scene& scene);

// The mesh for `scene`, shared with the other renders of this process that
// asked for the same key. A study renders one geometry many times (the
// truth's convergence checks at more samples; variants that differ in light,
// material or method), and the build is most of a truth's cost. The meshes
// built last are kept while they hold at most mesh_cache_triangles()
// triangles together (kMeshBytesPerTriangle each with the BVH, measured); a
// render asking for a key being built waits for that build. Queries on a
// shared mesh are thread-safe (Embree's rtcIntersect1/rtcOccluded1 on a
// committed scene). `reused` says whether it came from the cache.
std::shared_ptr<const DisplacedMesh> shared_displaced_mesh(const Scene& scene,
                                                           bool* reused = nullptr);

// The default limit: half a GiB of meshes.
inline constexpr std::size_t kMeshCacheTriangles = 8'000'000;
inline constexpr double kMeshBytesPerTriangle = 67.0;
// The process's limit (thread-safe); a study sets it from its memory budget
// (StudyOptions::max_memory_bytes), so that the meshes of one round of
// convergence checks are still there for the next.
void set_mesh_cache_triangles(std::size_t triangles);
std::size_t mesh_cache_triangles();

}  // namespace penumbra
