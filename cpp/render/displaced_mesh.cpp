#include "render/displaced_mesh.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <embree3/rtcore.h>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

namespace penumbra {

// Grid layout (primitive ids are decoded, not stored):
//  cylinder side: vertex (i, j) = j*nu + i, i in [0, nu) wrapping around,
//    j in [0, nv]; quad (i, j) -> primitives 2 (j nu + i) + {0, 1};
//    caps, if any, follow as two fans around a centre vertex.
//  sphere: pole 0, rings j = 1..nv-1 at 1 + (j-1) nu + i, pole last;
//    primitives: top fan [0, nu), quads, bottom fan.
struct DisplacedMesh::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  Shape shape;
  double amplitude = 0.0;
  HeightFunction height;
  unsigned nu = 0, nv = 0;
  unsigned side_primitives = 0;

  double u_at(unsigned i) const { return 2.0 * kPi * i / nu; }
  double v_at(unsigned j) const {
    return shape.type == ShapeType::kSphere ? kPi * j / nv
                                            : -0.5 * shape.height + shape.height * j / nv;
  }

  // (u, v) of the three corners of a side primitive, in Embree's vertex order.
  void corners(unsigned prim, double u[3], double v[3]) const {
    if (shape.type == ShapeType::kCylinder) {
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

  Vec3 vertex(double u, double v) const {
    const SurfaceGeometry g = surface_at(shape, u, v);
    return displaced_point(g, amplitude, evaluate_height(height, g.p));
  }
};

DisplacedMesh::DisplacedMesh(const Scene& scene) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.shape = scene.shape;
  m.amplitude = scene.height.amplitude;
  m.height = scene.height.function;
  const double e = scene.displacement.edge_length;
  const double reach = m.amplitude * max_abs_height(m.height);
  const double r = m.shape.radius + reach;
  const bool sphere = m.shape.type == ShapeType::kSphere;
  m.nu = std::max(8u, static_cast<unsigned>(std::ceil(2.0 * kPi * r / e)));
  m.nv = sphere ? std::max(4u, static_cast<unsigned>(std::ceil(kPi * r / e)))
                : std::max(1u, static_cast<unsigned>(std::ceil(m.shape.height / e)));
  const unsigned nu = m.nu, nv = m.nv;
  const bool caps = !sphere && m.shape.caps;

  std::size_t vertex_count, triangle_count;
  if (sphere) {
    vertex_count = 2 + std::size_t(nu) * (nv - 1);
    m.side_primitives = nu + 2 * nu * (nv - 2) + nu;
    triangle_count = m.side_primitives;
  } else {
    vertex_count = std::size_t(nu) * (nv + 1) + (caps ? 2 : 0);
    m.side_primitives = 2 * nu * nv;
    triangle_count = m.side_primitives + (caps ? 2 * nu : 0);
  }
  vertices_ = vertex_count;
  triangles_ = triangle_count;
  const double kappa =
      1.0 / std::max(m.shape.radius - reach, 1e-12) + m.amplitude * max_hessian_norm(m.height);
  shadow_offset_ = e * e * kappa / 8.0 + 1e-9 * m.shape.radius;

  m.device = rtcNewDevice(nullptr);
  if (!m.device) throw std::runtime_error("Embree: cannot create a device");
  m.scene = rtcNewScene(m.device);
  rtcSetSceneFlags(m.scene, RTC_SCENE_FLAG_ROBUST);
  RTCGeometry geometry = rtcNewGeometry(m.device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* positions = static_cast<float*>(rtcSetNewGeometryBuffer(
      geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), vertex_count));
  auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
      geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), triangle_count));
  if (!positions || !indices) throw std::runtime_error("Embree: cannot allocate the mesh buffers");

  auto put = [&](std::size_t index, const Vec3& p) {
    positions[3 * index] = static_cast<float>(p.x);
    positions[3 * index + 1] = static_cast<float>(p.y);
    positions[3 * index + 2] = static_cast<float>(p.z);
  };
  auto tri = [&](std::size_t t, unsigned a, unsigned b, unsigned c) {
    indices[3 * t] = a, indices[3 * t + 1] = b, indices[3 * t + 2] = c;
  };

  if (sphere) {
    put(0, m.vertex(0.0, 0.0));
    put(vertex_count - 1, m.vertex(0.0, kPi));
    tbb::parallel_for(1u, nv, [&](unsigned j) {
      for (unsigned i = 0; i < nu; ++i)
        put(1 + std::size_t(j - 1) * nu + i, m.vertex(m.u_at(i), m.v_at(j)));
    });
    auto ring = [&](unsigned j, unsigned i) { return 1 + (j - 1) * nu + (i % nu); };
    const unsigned south = static_cast<unsigned>(vertex_count - 1);
    tbb::parallel_for(0u, nu, [&](unsigned i) {
      tri(i, 0, ring(1, i), ring(1, i + 1));
      tri(nu + 2 * nu * (nv - 2) + i, south, ring(nv - 1, i + 1), ring(nv - 1, i));
    });
    tbb::parallel_for(1u, nv - 1, [&](unsigned j) {
      for (unsigned i = 0; i < nu; ++i) {
        const std::size_t t = nu + 2 * (std::size_t(j - 1) * nu + i);
        tri(t, ring(j, i), ring(j, i + 1), ring(j + 1, i + 1));
        tri(t + 1, ring(j, i), ring(j + 1, i + 1), ring(j + 1, i));
      }
    });
  } else {
    tbb::parallel_for(0u, nv + 1, [&](unsigned j) {
      for (unsigned i = 0; i < nu; ++i)
        put(std::size_t(j) * nu + i, m.vertex(m.u_at(i), m.v_at(j)));
    });
    auto at = [&](unsigned j, unsigned i) { return j * nu + (i % nu); };
    tbb::parallel_for(0u, nv, [&](unsigned j) {
      for (unsigned i = 0; i < nu; ++i) {
        const std::size_t t = 2 * (std::size_t(j) * nu + i);
        tri(t, at(j, i), at(j, i + 1), at(j + 1, i + 1));
        tri(t + 1, at(j, i), at(j + 1, i + 1), at(j + 1, i));
      }
    });
    if (caps) {
      const unsigned bottom = nu * (nv + 1), top = bottom + 1;
      put(bottom, m.shape.center - m.shape.axis * (0.5 * m.shape.height));
      put(top, m.shape.center + m.shape.axis * (0.5 * m.shape.height));
      for (unsigned i = 0; i < nu; ++i) {
        tri(m.side_primitives + i, bottom, at(0, i + 1), at(0, i));
        tri(m.side_primitives + nu + i, top, at(nv, i), at(nv, i + 1));
      }
    }
  }
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(m.scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(m.scene);
  if (rtcGetDeviceError(m.device) != RTC_ERROR_NONE)
    throw std::runtime_error(
        fmt::format("Embree could not build the displaced mesh ({} triangles): out of memory?",
                    triangle_count));
}

DisplacedMesh::~DisplacedMesh() {
  if (impl_->scene) rtcReleaseScene(impl_->scene);
  if (impl_->device) rtcReleaseDevice(impl_->device);
}

std::optional<MeshHit> DisplacedMesh::intersect(const Ray& ray) const {
  const Impl& m = *impl_;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh{};
  rh.ray.org_x = static_cast<float>(ray.origin.x);
  rh.ray.org_y = static_cast<float>(ray.origin.y);
  rh.ray.org_z = static_cast<float>(ray.origin.z);
  rh.ray.dir_x = static_cast<float>(ray.direction.x);
  rh.ray.dir_y = static_cast<float>(ray.direction.y);
  rh.ray.dir_z = static_cast<float>(ray.direction.z);
  rh.ray.tnear = 0.0f;
  rh.ray.tfar = std::numeric_limits<float>::infinity();
  rh.ray.mask = ~0u;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(m.scene, &context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
  MeshHit hit;
  hit.t = rh.ray.tfar;
  if (rh.hit.primID >= m.side_primitives) {  // a flat cap
    const Vec3 p = ray.origin + ray.direction * hit.t;
    const bool top = rh.hit.primID >= m.side_primitives + m.nu;
    SurfaceGeometry& g = hit.geometry;
    g.n = m.shape.axis * (top ? 1.0 : -1.0);
    g.p = p;
    const Frame f = Frame::from_z(g.n);
    g.t1 = f.s, g.t2 = f.t;
    g.displaceable = false;
    return hit;
  }
  double u[3], v[3];
  m.corners(rh.hit.primID, u, v);
  const double b1 = rh.hit.u, b2 = rh.hit.v, b0 = 1.0 - b1 - b2;
  hit.geometry =
      surface_at(m.shape, b0 * u[0] + b1 * u[1] + b2 * u[2], b0 * v[0] + b1 * v[1] + b2 * v[2]);
  return hit;
}

bool DisplacedMesh::occluded(const Ray& ray, double t_max) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay r{};
  r.org_x = static_cast<float>(ray.origin.x);
  r.org_y = static_cast<float>(ray.origin.y);
  r.org_z = static_cast<float>(ray.origin.z);
  r.dir_x = static_cast<float>(ray.direction.x);
  r.dir_y = static_cast<float>(ray.direction.y);
  r.dir_z = static_cast<float>(ray.direction.z);
  r.tnear = 0.0f;
  r.tfar = static_cast<float>(std::min(t_max, double(std::numeric_limits<float>::max())));
  r.mask = ~0u;
  rtcOccluded1(impl_->scene, &context, &r);
  return r.tfar < 0.0f;
}

}  // namespace penumbra
