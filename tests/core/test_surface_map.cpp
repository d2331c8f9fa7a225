// Image maps on shapes: the cubic B-spline against what it must reproduce,
// its derivatives against differences of its values, the shapes' map
// parameters against surface_at, and the texel bounds against samples.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <utility>
#include <vector>

#include "core/normal_integration.h"
#include "core/random.h"
#include "core/surface_map.h"

namespace penumbra {
namespace {

SurfaceMap height_map(int width, int height, auto&& texel, MapEdge edge = MapEdge::kWrap) {
  SurfaceMap m;
  m.width = width, m.height = height, m.edge = edge;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) m.texels.push_back(static_cast<float>(texel(x, y)));
  return m;
}

Shape cylinder() {
  Shape s;
  s.type = ShapeType::kCylinder;
  s.axis = normalize(Vec3{0.3, 1.0, -0.2});
  s.center = {0.1, -0.2, 0.3};
  s.radius = 0.8;
  s.height = 1.7;
  return with_frame(s);
}

Shape sphere() {
  Shape s;
  s.type = ShapeType::kSphere;
  s.axis = normalize(Vec3{-0.4, 1.0, 0.1});
  s.radius = 1.3;
  return with_frame(s);
}

Shape plane() {
  Shape s;
  s.type = ShapeType::kPlane;
  s.axis = normalize(Vec3{0.2, 0.1, -1.0});
  s.center = {0.3, 0.1, 0.0};
  s.width = 1.5;
  s.height = 0.9;
  s.radius = 0.75;
  return with_frame(s);
}

TEST(SurfaceMap, SplineReproducesConstantsAndRampsExactly) {
  // Partition of unity and linear precision of the uniform cubic B-spline:
  // a constant map is that constant with zero slope everywhere, and a ramp
  // in x away from a clamped edge is the ramp, slope width * step per unit s.
  const SurfaceMap flat = height_map(7, 5, [](int, int) { return 0.375; });
  const SurfaceMap ramp = height_map(
      16, 4, [](int x, int) { return 0.25 * x; }, MapEdge::kClamp);
  Pcg32 rng(3);
  for (int i = 0; i < 200; ++i) {
    const double s = rng.next_double() * 3.0 - 1.0, t = rng.next_double() * 3.0 - 1.0;
    const MapSample f = sample_map(flat, s, t);
    EXPECT_NEAR(f.value, 0.375, 1e-12);
    EXPECT_NEAR(f.d_ds, 0.0, 1e-10);
    EXPECT_NEAR(f.d_dt, 0.0, 1e-10);
    // Texel centres 2..13 are two texels from either edge.
    const double x = 2.0 + 11.0 * rng.next_double();
    const MapSample r = sample_map(ramp, (x + 0.5) / 16.0, rng.next_double());
    EXPECT_NEAR(r.value, 0.25 * x, 1e-12);
    EXPECT_NEAR(r.d_ds, 0.25 * 16.0, 1e-10);
    EXPECT_NEAR(r.d_dt, 0.0, 1e-10);
  }
  // At a texel centre the spline is (c[-1] + 4 c[0] + c[1]) / 6 per axis.
  const SurfaceMap spike = height_map(5, 5, [](int x, int y) { return x == 2 && y == 2 ? 36 : 0; });
  EXPECT_NEAR(sample_map(spike, 2.5 / 5, 1.0 - 2.5 / 5).value, 36.0 * 16.0 / 36.0, 1e-12);
  EXPECT_NEAR(sample_map(spike, 1.5 / 5, 1.0 - 2.5 / 5).value, 36.0 * 4.0 / 36.0, 1e-12);
}

TEST(SurfaceMap, DerivativesAreTheSlopesOfTheValues) {
  Pcg32 rng(11);
  const SurfaceMap m = height_map(9, 6, [&](int, int) { return rng.next_double() * 2.0 - 1.0; });
  const double step = 1e-6;
  for (int i = 0; i < 300; ++i) {
    const double s = rng.next_double() * 2.0, t = rng.next_double() * 2.0;
    const MapSample c = sample_map(m, s, t);
    const double ds =
        (sample_map(m, s + step, t).value - sample_map(m, s - step, t).value) / (2 * step);
    const double dt =
        (sample_map(m, s, t + step).value - sample_map(m, s, t - step).value) / (2 * step);
    EXPECT_NEAR(c.d_ds, ds, 1e-5 * (1.0 + std::abs(ds)));
    EXPECT_NEAR(c.d_dt, dt, 1e-5 * (1.0 + std::abs(dt)));
  }
}

TEST(SurfaceMap, ParametersInvertTheShapeAndCarryItsDerivatives) {
  Pcg32 rng(5);
  for (const Shape& shape : {cylinder(), sphere(), plane()}) {
    for (int i = 0; i < 200; ++i) {
      const double u = rng.next_double(), v = 0.05 + 0.9 * rng.next_double();
      const SurfaceGeometry g = surface_at_parameters(shape, u, v);
      const SurfaceParameters q = surface_parameters(shape, g.p);
      EXPECT_NEAR(q.u, u, 1e-12);
      EXPECT_NEAR(q.v, v, 1e-12);
      // Off the surface along the normal the parameters do not change.
      const SurfaceParameters lifted = surface_parameters(shape, g.p + g.n * 0.05);
      EXPECT_NEAR(lifted.u, u, 1e-12);
      EXPECT_NEAR(lifted.v, v, 1e-12);
      const double h = 1e-6;
      const Vec3 du =
          (surface_at_parameters(shape, u + h, v).p - surface_at_parameters(shape, u - h, v).p) /
          (2 * h);
      const Vec3 dv =
          (surface_at_parameters(shape, u, v + h).p - surface_at_parameters(shape, u, v - h).p) /
          (2 * h);
      EXPECT_LT(length(du - q.dp_du), 1e-6 * length(q.dp_du));
      EXPECT_LT(length(dv - q.dp_dv), 1e-6 * length(q.dp_dv));
      EXPECT_NEAR(dot(q.dp_du, q.dp_dv), 0.0, 1e-9);  // orthogonal
      // (dP/du, dP/dv, N) is right-handed, as a tangent-space frame must be.
      EXPECT_GT(dot(cross(q.dp_du, q.dp_dv), g.n), 0.0);
    }
  }
}

TEST(SurfaceMap, TexelBoundsHoldEverywhereTheyClaimTo) {
  Pcg32 rng(17);
  const SurfaceMap m = height_map(24, 12, [&](int, int) { return rng.next_double() * 2.0 - 1.0; });
  for (const Shape& shape : {cylinder(), sphere(), plane()}) {
    const HeightBounds b = height_bounds({}, &m, shape);
    double max_h = 0.0, max_g = 0.0;
    for (int i = 0; i < 20000; ++i) {
      const double u = rng.next_double();
      // The sphere's bound holds within latitude +-60 degrees (v in [1/6, 5/6]).
      const double v = shape.type == ShapeType::kSphere ? (1.0 + 4.0 * rng.next_double()) / 6.0
                                                        : rng.next_double();
      const SurfaceGeometry g = surface_at_parameters(shape, u, v);
      const HeightSample h = height_at({}, &m, shape, g);
      max_h = std::max(max_h, std::abs(h.h));
      max_g = std::max(max_g, length(h.gradient));
      // The gradient lies in the tangent plane.
      EXPECT_NEAR(dot(h.gradient, g.n), 0.0, 1e-9 * (1.0 + length(h.gradient)));
    }
    EXPECT_LE(max_h, b.max_abs * (1 + 1e-12));
    EXPECT_LE(max_g, b.max_gradient * (1 + 1e-12));
    // And they are not loose by orders of magnitude on random texels.
    EXPECT_GT(max_h, 0.3 * b.max_abs);
    EXPECT_GT(max_g, 0.05 * b.max_gradient);
  }
}

TEST(Plane, RaysHitTheRectangleOnlyAndItsGeometryIsFlat) {
  const Shape s = plane();
  Pcg32 rng(23);
  int hits = 0;
  for (int i = 0; i < 2000; ++i) {
    const double x = 2.0 * rng.next_double() - 1.0, y = 2.0 * rng.next_double() - 1.0;
    const Vec3 target = s.center + s.frame.s * x + s.frame.t * y;
    const Vec3 origin = target + normalize(Vec3{0.3, -0.2, -1.0}) * 3.0;
    const Ray ray{origin, normalize(target - origin)};
    Hit hit;
    const bool inside = std::abs(x) <= 0.75 && std::abs(y) <= 0.45;
    ASSERT_EQ(intersect(s, ray, 0.0, 1e9, &hit), inside) << x << "," << y;
    ASSERT_EQ(occluded(s, ray, 0.0, 1e9), inside);
    if (!inside) continue;
    ++hits;
    EXPECT_LT(length(hit.geometry.p - target), 1e-12);
    EXPECT_NEAR(hit.t, 3.0, 1e-12);
    EXPECT_EQ(hit.geometry.n, s.axis);
    EXPECT_EQ(hit.geometry.kappa1, 0.0);
    EXPECT_LT(length(cross(hit.geometry.t1, hit.geometry.t2) - s.axis), 1e-12);
    // A point above the plane projects back onto the hit.
    const SurfaceGeometry under = base_geometry_under(s, target + s.axis * 0.2);
    EXPECT_LT(length(under.p - target), 1e-12);
    // A hit beyond t_max is none.
    EXPECT_FALSE(occluded(s, ray, 0.0, 2.9));
  }
  EXPECT_GT(hits, 200);
}

TEST(SurfaceMap, DigestFollowsContentNotPlacement) {
  SurfaceMap a = height_map(4, 4, [](int x, int y) { return x + 10 * y; });
  SurfaceMap b = a;
  b.tiles_u = 3.0;
  EXPECT_EQ(map_digest(a), map_digest(b));
  b.texels[5] += 1e-3f;
  EXPECT_NE(map_digest(a), map_digest(b));
  SurfaceMap c = a;
  c.width = 8, c.height = 2;  // same texels, other shape
  EXPECT_NE(map_digest(a), map_digest(c));
}

// A normal map of the slopes (g_u, g_v) (per scene unit along u and v) over
// width x height texels, wrapped.
SurfaceMap slope_normal_map(int width, int height,
                            const std::function<std::pair<double, double>(double, double)>& slope) {
  SurfaceMap m;
  m.kind = MapKind::kNormal;
  m.width = width;
  m.height = height;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const double s = (x + 0.5) / width, t = 1.0 - (y + 0.5) / height;
      const auto [gu, gv] = slope(s, t);
      const Vec3 n = normalize(Vec3{-gu, -gv, 1.0});
      for (double c : {n.x, n.y, n.z}) m.texels.push_back(float(0.5 * c + 0.5));
    }
  return m;
}

// The integrated height of an exact height's normal map is that height up
// to the averaging of texel slopes onto edges: for H = A sin(omega X) at
// texel pitch tau the relative slope error is (omega tau)^2 / 12, and the
// height's with it (its RMS within twice that here); the map's normals are
// the height's within a tenth of a degree (the centred differences that
// measure it are off by (omega tau)^2 / 6 of slopes up to 0.13 rad, 0.05
// degrees). A slope field with curl and
// no divergence, (sin 2 pi v, 0), has no height at all: the integration
// gives zero and says how far the map is from any height (RMS angle
// atan-sized, here atan(0.2) / sqrt 2 = 8.0 degrees).
TEST(NormalIntegration, AHeightsNormalMapIntegratesBackAndCurlIsReported) {
  const double length = 2.0, amplitude = 0.01, cycles = 4.0;
  const double omega = 2.0 * kPi * cycles / length;  // per scene unit
  const int size = 128;
  const SurfaceMap exact = slope_normal_map(size, size, [&](double s, double) {
    return std::pair{amplitude * omega * std::cos(2.0 * kPi * cycles * s), 0.0};
  });
  const IntegratedHeight h = integrate_normal_map(exact, length, length);
  double error = 0.0, norm = 0.0;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const double want = amplitude * std::sin(2.0 * kPi * cycles * (x + 0.5) / size);
      error += std::pow(h.heights[std::size_t(y) * size + x] - want, 2);
      norm += want * want;
    }
  const double tau = length / size;
  const double bound = std::pow(omega * tau, 2) / 12.0;
  std::printf(
      "exact map: relative RMS height error %.3g (bound 2 x %.3g), RMS angle %.3g deg, "
      "%d iterations\n",
      std::sqrt(error / norm), bound, h.rms_angle_deg, h.iterations);
  EXPECT_LT(std::sqrt(error / norm), 2.0 * bound);
  EXPECT_LT(h.rms_angle_deg, 0.1);
  EXPECT_EQ(h.clamped, 0);

  const SurfaceMap curl = slope_normal_map(size, size, [](double, double t) {
    return std::pair{0.2 * std::sin(2.0 * kPi * t), 0.0};
  });
  const IntegratedHeight c = integrate_normal_map(curl, length, length);
  double largest = 0.0;
  for (float v : c.heights) largest = std::max(largest, double(std::abs(v)));
  const double expected = std::atan(0.2) / std::sqrt(2.0) * 180.0 / kPi;
  std::printf("curl map: largest |H| %.3g, RMS angle %.3g deg (expected %.3g)\n", largest,
              c.rms_angle_deg, expected);
  EXPECT_LT(largest, 1e-9);
  EXPECT_NEAR(c.rms_angle_deg, expected, 0.05 * expected);
}

}  // namespace
}  // namespace penumbra
