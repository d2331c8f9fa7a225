#include "evaluator/displaced_mesh.h"

#include "core/grid_mesh.h"
#include "core/mesh_surface.h"

#include <algorithm>
#include <cmath>
#include <future>
#include <limits>
#include <list>
#include <mutex>
#include <stdexcept>

#include <fmt/format.h>

#include "evaluator/embree_mesh.h"

namespace penumbra {

// Primitive ids are decoded with the layout documented in core/grid_mesh.h.
struct DisplacedMesh::Impl {
  std::unique_ptr<EmbreeMesh> bvh;
  Shape shape;
  double amplitude = 0.0;
  HeightFunction height;
  std::shared_ptr<const SurfaceMap> map;
  unsigned nu = 0, nv = 0;
  unsigned side_primitives = 0;
  // Mesh shapes: how each base triangle is split.
  MeshSubdivision plan;

  MeshHit decode_mesh(const TriangleHit& triangle) const;

  double u_at(unsigned i) const { return grid_u(shape, {nu, nv}, i); }
  double v_at(unsigned j) const { return grid_v(shape, {nu, nv}, j); }

  MeshHit decode(const Ray& ray, const TriangleHit& triangle) const;

  // (u, v) of the three corners of a side primitive, in Embree's vertex order.
  void corners(unsigned prim, double u[3], double v[3]) const {
    if (shape.type != ShapeType::kSphere) {  // cylinder side and plane: the same quads
      const unsigned quad = prim / 2, i = quad % nu, j = quad / nu;
      const double u0 = u_at(i), u1 = u_at(i + 1), v0 = v_at(j), v1 = v_at(j + 1);
      if (prim % 2 == 0) {
        u[0] = u0, v[0] = v0, u[1] = u1, v[1] = v0, u[2] = u1, v[2] = v1;
      } else {
        u[0] = u0, v[0] = v0, u[1] = u1, v[1] = v1, u[2] = u0, v[2] = v1;
      }
      return;
    }
    if (prim < nu) {  // top fan; the pole takes the middle azimuth
      const unsigned i = prim;
      u[0] = 0.5 * (u_at(i) + u_at(i + 1)), v[0] = 0.0;
      u[1] = u_at(i), v[1] = v_at(1), u[2] = u_at(i + 1), v[2] = v_at(1);
      return;
    }
    const unsigned quads = 2 * nu * (nv - 2);
    if (prim < nu + quads) {
      const unsigned local = prim - nu, quad = local / 2, i = quad % nu, j = 1 + quad / nu;
      const double u0 = u_at(i), u1 = u_at(i + 1), v0 = v_at(j), v1 = v_at(j + 1);
      if (local % 2 == 0) {
        u[0] = u0, v[0] = v0, u[1] = u1, v[1] = v0, u[2] = u1, v[2] = v1;
      } else {
        u[0] = u0, v[0] = v0, u[1] = u1, v[1] = v1, u[2] = u0, v[2] = v1;
      }
      return;
    }
    const unsigned i = prim - nu - quads;  // bottom fan
    u[0] = 0.5 * (u_at(i) + u_at(i + 1)), v[0] = kPi;
    u[1] = u_at(i + 1), v[1] = v_at(nv - 1), u[2] = u_at(i), v[2] = v_at(nv - 1);
  }
};

DisplacedMesh::DisplacedMesh(const Scene& scene) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.shape = scene.shape;
  m.amplitude = scene.height.amplitude;
  m.height = scene.height.function;
  if (scene.height.height_map()) m.map = scene.height.map;
  if (m.shape.type == ShapeType::kMesh) {
    build_mesh_shape(scene);
    return;
  }
  const double e = scene.displacement.edge_length;
  const HeightBounds bounds = height_bounds(m.height, m.map.get(), m.shape);
  const double reach = m.amplitude * bounds.max_abs;
  const GridResolution resolution = grid_resolution(m.shape, e, reach);
  m.nu = resolution.nu, m.nv = resolution.nv;
  TriangleMesh mesh =
      make_grid_mesh(m.shape, m.height, m.amplitude, resolution, m.map.get(), GridNormals::kOmit);
  m.side_primitives = static_cast<unsigned>(mesh.side_triangles);
  vertices_ = mesh.vertex_count();
  triangles_ = mesh.triangle_count();
  const double kappa =
      1.0 / std::max(m.shape.radius - reach, 1e-12) + m.amplitude * bounds.max_hessian;
  shadow_offset_ = e * e * kappa / 8.0 + 1e-9 * m.shape.radius;

  m.bvh = std::make_unique<EmbreeMesh>(std::move(mesh), bvh_build_for(triangles_));
}

void DisplacedMesh::build_mesh_shape(const Scene& scene) {
  Impl& m = *impl_;
  const MeshSurface& base = *m.shape.mesh;
  const double e = scene.displacement.edge_length;
  m.plan = plan_subdivision(base.mesh, e);
  TriangleMesh mesh = subdivide_displaced(base, m.plan, {m.height, m.map.get()}, m.amplitude);
  m.side_primitives = static_cast<unsigned>(mesh.triangle_count());
  vertices_ = mesh.vertex_count();
  triangles_ = mesh.triangle_count();
  // How far a flat sub-triangle of side e' strays from P + A h Ni, per
  // base triangle: e'^2 kappa / 8 with kappa bounding |d2P'/ds2| along it,
  // from the turn of Ni there (k), h's gradient and Hessian:
  //   (1 + A|h|) k + 2 A |grad h| k + A |Hess h|.
  const double a = m.amplitude;
  const HeightBounds function_bounds{max_abs_height(m.height), max_gradient_norm(m.height),
                                     max_hessian_norm(m.height)};
  const std::vector<HeightBounds> map_bounds =
      m.map ? mesh_height_bounds(*m.map, base) : std::vector<HeightBounds>{};
  offsets_.resize(base.mesh.triangle_count());
  for (std::uint32_t t = 0; t < offsets_.size(); ++t) {
    const HeightBounds& bounds = m.map ? map_bounds[t] : function_bounds;
    const double h_max = bounds.max_abs, gradient = bounds.max_gradient,
                 hessian = bounds.max_hessian;
    const double k = normal_curvature(base.mesh, t);
    const double kappa = (1.0 + a * h_max) * k + 2.0 * a * gradient * k + a * hessian;
    const double e2 = double(m.plan.sub_edges[t]) * m.plan.sub_edges[t];
    offsets_[t] = float(e2 * kappa / 8.0 + 1e-9 * m.shape.radius);
  }
  m.bvh = std::make_unique<EmbreeMesh>(std::move(mesh), bvh_build_for(triangles_));
}

DisplacedMesh::~DisplacedMesh() = default;

// The base triangle under sub-triangle prim and the hit's barycentrics in it.
MeshHit DisplacedMesh::Impl::decode_mesh(const TriangleHit& triangle) const {
  MeshHit hit;
  hit.t = triangle.t;
  locate_in_base(plan, triangle.triangle, triangle.b1, triangle.b2, &hit.base_triangle, hit.base_b);
  hit.on_mesh = true;
  hit.geometry = mesh_surface_at(shape.mesh->mesh, hit.base_triangle, hit.base_b);
  return hit;
}

// The hit of `ray` on primitive triangle.triangle, from its barycentrics.
MeshHit DisplacedMesh::Impl::decode(const Ray& ray, const TriangleHit& triangle) const {
  if (shape.type == ShapeType::kMesh) return decode_mesh(triangle);
  MeshHit hit;
  hit.t = triangle.t;
  const unsigned prim = triangle.triangle;
  if (prim >= side_primitives) {  // a flat cap
    const Vec3 p = ray.origin + ray.direction * hit.t;
    const bool top = prim >= side_primitives + nu;
    SurfaceGeometry& g = hit.geometry;
    g.n = shape.axis * (top ? 1.0 : -1.0);
    g.p = p;
    const Frame f = Frame::from_z(g.n);
    g.t1 = f.s, g.t2 = f.t;
    g.displaceable = false;
    return hit;
  }
  double u[3], v[3];
  corners(prim, u, v);
  const double b1 = triangle.b1, b2 = triangle.b2, b0 = 1.0 - b1 - b2;
  hit.geometry =
      surface_at(shape, b0 * u[0] + b1 * u[1] + b2 * u[2], b0 * v[0] + b1 * v[1] + b2 * v[2]);
  return hit;
}

std::optional<MeshHit> DisplacedMesh::intersect(const Ray& ray) const {
  const auto triangle = impl_->bvh->intersect(ray);
  if (!triangle) return std::nullopt;
  return impl_->decode(ray, *triangle);
}

void DisplacedMesh::intersect_packet(const Ray* rays, std::size_t n, MeshHit* hits,
                                     bool* found) const {
  TriangleHit triangles[kPacketRays];
  impl_->bvh->intersect_packet(rays, n, triangles, found);
  for (std::size_t k = 0; k < n; ++k)
    if (found[k]) hits[k] = impl_->decode(rays[k], triangles[k]);
}

bool DisplacedMesh::occluded(const Ray& ray, double t_max) const {
  return impl_->bvh->occluded(ray, 0.0, t_max);
}

void DisplacedMesh::occluded_packet(const Ray* rays, const double* t_max, std::size_t n,
                                    bool* blocked) const {
  impl_->bvh->occluded_packet(rays, t_max, n, blocked);
}

std::string displaced_mesh_key(const Scene& scene) {
  const Shape& s = scene.shape;
  std::string key =
      fmt::format("{} {:a} {:a} {:a} {:a} {:a} {:a} {:a} {:a} {} | {:a} {:a} {}",
                  static_cast<int>(s.type), s.center.x, s.center.y, s.center.z, s.axis.x, s.axis.y,
                  s.axis.z, s.radius, s.height, s.caps, scene.displacement.edge_length,
                  scene.height.amplitude, static_cast<int>(scene.height.function.combine));
  for (const SineTerm& t : scene.height.function.terms)
    key += fmt::format(" {:a} {:a} {:a} {:a} {:a}", t.k.x, t.k.y, t.k.z, t.phase, t.weight);
  if (s.mesh) key += " | mesh " + s.mesh->digest;
  if (const SurfaceMap* map = scene.height.height_map())
    key += fmt::format(" | map {} {:a} {:a} {}", map->digest, map->tiles_u, map->tiles_v,
                       static_cast<int>(map->edge));
  return key;
}

namespace {

using MeshFuture = std::shared_future<std::shared_ptr<const DisplacedMesh>>;

struct CachedMesh {
  std::string key;
  MeshFuture mesh;
  std::size_t triangles = 0;  // 0 while it is being built
};

// Most recent first.
std::mutex cache_mutex;
std::list<CachedMesh> cached_meshes;
std::size_t cache_limit = kMeshCacheTriangles;  // under cache_mutex

void trim_cache() {
  std::size_t total = 0;
  for (auto it = cached_meshes.begin(); it != cached_meshes.end();) {
    total += it->triangles;
    // Never drop a build in flight (triangles 0): others may wait on it.
    if (it->triangles > 0 && total > cache_limit && it != cached_meshes.begin())
      it = cached_meshes.erase(it);
    else
      ++it;
  }
}

}  // namespace

void set_mesh_cache_triangles(std::size_t triangles) {
  std::lock_guard<std::mutex> lock(cache_mutex);
  cache_limit = triangles;
  trim_cache();
}

std::size_t mesh_cache_triangles() {
  std::lock_guard<std::mutex> lock(cache_mutex);
  return cache_limit;
}

std::shared_ptr<const DisplacedMesh> shared_displaced_mesh(const Scene& scene, bool* reused) {
  const std::string key = displaced_mesh_key(scene);
  std::promise<std::shared_ptr<const DisplacedMesh>> promise;
  std::optional<MeshFuture> found;
  {
    std::lock_guard<std::mutex> lock(cache_mutex);
    const auto it = std::find_if(cached_meshes.begin(), cached_meshes.end(),
                                 [&](const CachedMesh& c) { return c.key == key; });
    if (it != cached_meshes.end()) {
      cached_meshes.splice(cached_meshes.begin(), cached_meshes, it);
      found = it->mesh;
    } else {
      cached_meshes.push_front({key, promise.get_future().share(), 0});
    }
  }
  if (reused) *reused = found.has_value();
  if (found) return found->get();  // waits, outside the lock, for a build in flight
  std::shared_ptr<const DisplacedMesh> mesh;
  try {
    mesh = std::make_shared<const DisplacedMesh>(scene);
  } catch (...) {
    promise.set_exception(std::current_exception());
    std::lock_guard<std::mutex> lock(cache_mutex);
    cached_meshes.remove_if([&](const CachedMesh& c) { return c.key == key; });
    throw;
  }
  promise.set_value(mesh);
  std::lock_guard<std::mutex> lock(cache_mutex);
  for (CachedMesh& c : cached_meshes)
    if (c.key == key) c.triangles = std::max<std::size_t>(mesh->triangle_count(), 1);
  trim_cache();
  return mesh;
}

}  // namespace penumbra
