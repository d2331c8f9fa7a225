// Camera rays against an analytic shape, a packet at a time: the first hit,
// its base geometry and the bump normal of a height function, in
// structure-of-arrays form so that one SIMD instruction serves several rays
// (Google Highway, the widest vectors the CPU offers, chosen at run time).
//
// The packet gives the bits that intersect(), evaluate_height() and
// displaced_normal() give one ray at a time: it performs the same IEEE
// operations in the same order (no fused multiply-adds; sqrt and division are
// correctly rounded in every vector width) and takes its sines and cosines
// from the same C library. So a render is the same whichever path or CPU
// made it, and the scalar functions stay the reference the tests hold it to.
#pragma once

#include <cstddef>

#include "core/height.h"
#include "core/shape.h"

namespace penumbra {

// Rays per packet; a multiple of every vector width (8 doubles in AVX-512).
inline constexpr std::size_t kPacketSize = 256;
// The length of each array: padded by a cache line so that the arrays do not
// start 4 KiB apart, where loads from one wait on stores to another (4K
// aliasing) and they crowd the same L1 sets.
inline constexpr std::size_t kPacketStride = kPacketSize + 8;

struct RayPacket {
  std::size_t count = 0;  // rays in use, <= kPacketSize
  // Origins and unit directions (scene units).
  alignas(64) double ox[kPacketStride]{}, oy[kPacketStride]{}, oz[kPacketStride]{};
  alignas(64) double dx[kPacketStride]{}, dy[kPacketStride]{}, dz[kPacketStride]{};

  void set(std::size_t i, const Ray& ray) {
    ox[i] = ray.origin.x, oy[i] = ray.origin.y, oz[i] = ray.origin.z;
    dx[i] = ray.direction.x, dy[i] = ray.direction.y, dz[i] = ray.direction.z;
  }
};

// A camera as it makes a packet's rays (the scene's Camera, reference
// sheet section 6): sample (sx + jx, sy + jy) of pixel (i, j), with strata
// sx < nx, sy < ny and jitter jx, jy in [0, 1), is at
//   x0 = (i + (sx + jx) / nx) / width - 0.5,  y0 = 0.5 - (j + (sy + jy) / ny) / height
// orthographic: origin = position + x0 right + y0 up, direction = direction;
// perspective:  origin = position, direction = normalize(direction + x0 right + y0 up).
struct PacketCamera {
  bool perspective = false;
  Vec3 position, direction, right, up;  // direction unit length for an orthographic camera
  double width = 1.0, height = 1.0;     // pixels
  double nx = 1.0, ny = 1.0;            // strata across and down a pixel
};

// The samples of a packet: pixel, stratum and jitter of each lane.
struct SamplePacket {
  alignas(64) double i[kPacketStride]{}, j[kPacketStride]{};
  alignas(64) double sx[kPacketStride]{}, sy[kPacketStride]{};
  alignas(64) double jx[kPacketStride]{}, jy[kPacketStride]{};
};

// The rays of the first rays->count samples.
void camera_rays(const PacketCamera& camera, const SamplePacket& samples, RayPacket* rays);

// The light as a packet's shadow rays and angles see it.
struct PacketLighting {
  bool distant = true;
  Vec3 light;                 // distant: unit direction towards the light; point: its position
  double shadow_t_min = 0.0;  // a shadow ray's hits count beyond this distance (scene units)
};

// What the rays of a packet hit, ray i in lane i: found[i] is 1 for a hit
// with t in (0, inf) and 0 for a miss (the other fields are then undefined).
// The geometry is the base surface's (SurfaceGeometry: p, n, t1, t2; v on a
// cylinder); ns is the bump normal, n itself where there is no bump.
// blocked[i] is 1 where the shadow ray from p towards the light meets the
// shape; theta, deviation and view are the evaluator's analysis angles
// (degrees, acos_approx) between the base normal turned towards the viewer
// and the light, the bump normal and the viewer.
struct HitPacket {
  alignas(64) double found[kPacketStride]{}, t[kPacketStride]{}, v[kPacketStride]{};
  alignas(64) double blocked[kPacketStride]{};
  alignas(64) double theta[kPacketStride]{}, deviation[kPacketStride]{}, view[kPacketStride]{};
  alignas(64) double px[kPacketStride]{}, py[kPacketStride]{}, pz[kPacketStride]{};
  alignas(64) double nx[kPacketStride]{}, ny[kPacketStride]{}, nz[kPacketStride]{};
  alignas(64) double t1x[kPacketStride]{}, t1y[kPacketStride]{}, t1z[kPacketStride]{};
  alignas(64) double t2x[kPacketStride]{}, t2y[kPacketStride]{}, t2z[kPacketStride]{};
  alignas(64) double nsx[kPacketStride]{}, nsy[kPacketStride]{}, nsz[kPacketStride]{};
  // Work space of the height function: h, its gradient, and the sines and
  // cosines of a product's factors.
  alignas(64) double h[kPacketStride]{}, gx[kPacketStride]{}, gy[kPacketStride]{},
      gz[kPacketStride]{};
  alignas(64) double sines[kMaxProductFactors][kPacketStride]{};
  alignas(64) double cosines[kMaxProductFactors][kPacketStride]{};

  // The shape's principal curvatures, the same at every hit (trace_packet).
  double kappa1 = 0.0, kappa2 = 0.0;

  // The hit of ray i as intersect() writes it: its distance, and its
  // geometry into the fields of *g that intersect() sets.
  double hit(std::size_t i, SurfaceGeometry* g) const;
  Vec3 ns(std::size_t i) const { return {nsx[i], nsy[i], nsz[i]}; }
};

// Whether trace_packet handles the shape: a sphere, or a cylinder without
// caps (a cap is not displaceable, which the packet does not track).
bool packet_supports(const Shape& shape);

// The first hit of each ray with t in (0, inf), like intersect(shape, ray,
// 0, inf); when `bump` is true, the bump normal
// displaced_normal(g, amplitude, evaluate_height(height, g.p)) of each hit;
// the shadow ray occluded(shape, {p, wi}, shadow_t_min, distance to the
// light), and the angles. `shape` must satisfy packet_supports and have its
// frame set (with_frame).
void trace_packet(const Shape& shape, const HeightFunction& height, double amplitude, bool bump,
                  const PacketLighting& lighting, const RayPacket& rays, HitPacket* hits);

// The instruction set trace_packet runs on here, as Highway names it
// ("AVX3" is AVX-512; Debian 12's Highway also builds AVX2, SSE4, SSSE3 and SCALAR).
const char* packet_target();

}  // namespace penumbra
