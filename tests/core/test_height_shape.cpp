// Height functions and shape geometry against finite differences and closed
// forms computed here.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <tbb/task_arena.h>

#include "core/grid_mesh.h"
#include "core/height.h"
#include "core/random.h"
#include "core/shape.h"
#include "core/sin_cos.h"
#include "core/surface_map.h"

namespace penumbra {
namespace {

std::vector<HeightFunction> families() {
  const Vec3 dirs[] = {{1, 0, 0}, {0, 1, 0.3}};
  return {make_grating({1, 0.2, 0}, 8.0, 0.3), make_weave(dirs, 6.0, HeightCombine::kProduct),
          make_weave(dirs, 6.0, HeightCombine::kSum), make_noise(8, 4.0, 12.0, 7)};
}

// Error of `value` in units in the last place of the long double reference
// rounded to double.
double ulps(double value, long double reference) {
  const double r = std::abs(static_cast<double>(reference));
  const double ulp = std::nextafter(r, INFINITY) - r;
  return static_cast<double>(std::fabs(static_cast<long double>(value) - reference)) / ulp;
}

// sin_cos (core/sin_cos.h) against glibc's long double sinl and cosl (64-bit
// mantissa, so an error of 2^-11 ulp at most): within the 3 ulp its header
// promises, also next to the zeros of sin and cos where the argument
// reduction decides the relative error; the C library's own beyond it.
TEST(SinCos, WithinThreeUlpOfLongDouble) {
  Pcg32 rng(12);
  double worst_sin = 0.0, worst_cos = 0.0;
  for (int i = 0; i < 400000; ++i) {
    const double u = 2.0 * rng.next_double() - 1.0;
    double x = 0.0;
    switch (i % 4) {
      case 0:
        x = 10.0 * u;
        break;
      case 1:
        x = 1e4 * u;
        break;
      case 2:
        x = 9.9e5 * u;
        break;
      case 3:  // next to a multiple of pi/2, where sin or cos nearly vanishes
        x = std::round(2e4 * u) * (kPi / 2) + 1e-7 * (2.0 * rng.next_double() - 1.0);
        break;
    }
    const SinCos sc = sin_cos(x);
    worst_sin = std::max(worst_sin, ulps(sc.sin, sinl(static_cast<long double>(x))));
    worst_cos = std::max(worst_cos, ulps(sc.cos, cosl(static_cast<long double>(x))));
  }
  EXPECT_LE(worst_sin, 3.0);
  EXPECT_LE(worst_cos, 3.0);
  for (const double x : {0.0, -0.0, 1e-300, kPi / 4, -kPi / 4})
    EXPECT_LE(ulps(sin_cos(x).sin, sinl(static_cast<long double>(x))), 1.0) << x;
  for (const double x : {2e6, -3.5e7, 1e300}) {
    EXPECT_EQ(sin_cos(x).sin, std::sin(x)) << x;
    EXPECT_EQ(sin_cos(x).cos, std::cos(x)) << x;
  }
}

TEST(Height, AnalyticGradientMatchesCentralDifferences) {
  Pcg32 rng(10);
  for (const HeightFunction& f : families())
    for (int i = 0; i < 1000; ++i) {
      const Vec3 p{rng.next_double() * 2 - 1, rng.next_double() * 2 - 1, rng.next_double() * 2 - 1};
      const HeightSample s = evaluate_height(f, p);
      const double h = 1e-6;
      for (int axis = 0; axis < 3; ++axis) {
        Vec3 e;
        (axis == 0 ? e.x : axis == 1 ? e.y : e.z) = h;
        const double fd = (evaluate_height(f, p + e).h - evaluate_height(f, p - e).h) / (2 * h);
        EXPECT_NEAR(s.gradient[axis], fd, 1e-5 * (1 + std::abs(fd)));
      }
    }
}

TEST(Height, BoundsHoldOnSamples) {
  Pcg32 rng(11);
  for (const HeightFunction& f : families()) {
    double max_h = 0, max_g = 0;
    for (int i = 0; i < 20000; ++i) {
      const Vec3 p{rng.next_double() * 4 - 2, rng.next_double() * 4 - 2, rng.next_double() * 4 - 2};
      const HeightSample s = evaluate_height(f, p);
      max_h = std::max(max_h, std::abs(s.h));
      max_g = std::max(max_g, length(s.gradient));
    }
    EXPECT_LE(max_h, max_abs_height(f));
    EXPECT_GT(max_h, 0.5 * max_abs_height(f) / std::sqrt(double(f.terms.size())));
    EXPECT_LE(max_g, max_gradient_norm(f));
  }
}

TEST(Height, NoiseIsDeterministicPerSeed) {
  const HeightFunction a = make_noise(8, 4, 12, 7), b = make_noise(8, 4, 12, 7),
                       c = make_noise(8, 4, 12, 8);
  ASSERT_EQ(a.terms.size(), 8u);
  for (std::size_t i = 0; i < a.terms.size(); ++i) {
    EXPECT_EQ(a.terms[i].k, b.terms[i].k);
    EXPECT_EQ(a.terms[i].phase, b.terms[i].phase);
    const double f = length(a.terms[i].k);
    EXPECT_GE(f, 4.0);
    EXPECT_LE(f, 12.0);
  }
  EXPECT_NE(a.terms[0].k, c.terms[0].k);
}

Shape cylinder(bool caps) {
  Shape s;
  s.type = ShapeType::kCylinder;
  s.center = {0.1, -0.2, 0.3};
  s.axis = normalize(Vec3{0.2, 1, 0.1});
  s.radius = 0.9;
  s.height = 1.7;
  s.caps = caps;
  return with_frame(s);
}

Shape sphere() {
  Shape s;
  s.type = ShapeType::kSphere;
  s.center = {0.1, -0.2, 0.3};
  s.axis = normalize(Vec3{0.3, 1, -0.2});
  s.radius = 1.1;
  return with_frame(s);
}

TEST(Height, VisibilityOfAGratingAgainstABruteForceHorizon) {
  // h = sin(2 pi f x) over the plane z = 0: nothing rises above a crest; a
  // trough sees the neighbouring crests. The reference searches 720
  // azimuths and 4000 steps out to the same reach (two wavelengths).
  const double f = 10.0, amplitude = 0.02;
  const HeightFunction grating = make_grating({1, 0, 0}, f, 0.0);
  const Vec3 n{0, 0, 1};
  const Vec3 crest{0.25 / f, 0.3, 0.0}, trough{-0.25 / f, 0.3, 0.0};
  EXPECT_EQ(height_field_visibility(grating, amplitude, crest, n), 1.0);
  EXPECT_EQ(height_field_visibility(grating, 0.0, trough, n), 1.0);
  auto reference = [&](const Vec3& p) {
    const double reach = 2.0 / f, h0 = std::sin(2.0 * kPi * f * p.x);
    double open = 0.0;
    constexpr int kAzimuths = 720, kSteps = 4000;
    for (int a = 0; a < kAzimuths; ++a) {
      const double phi = 2.0 * kPi * (a + 0.5) / kAzimuths;
      double tan_horizon =
          std::max(0.0, amplitude * 2.0 * kPi * f * std::cos(2.0 * kPi * f * p.x) * std::cos(phi));
      for (int j = 1; j <= kSteps; ++j) {
        const double t = reach * j / kSteps;
        const double x = p.x + t * std::cos(phi);
        tan_horizon = std::max(tan_horizon, amplitude * (std::sin(2.0 * kPi * f * x) - h0) / t);
      }
      open += std::cos(std::atan(tan_horizon)) * std::cos(std::atan(tan_horizon));
    }
    return open / kAzimuths;
  };
  for (const Vec3& p : {trough, Vec3{0.1 / f, 0.0, 0.0}, Vec3{-0.4 / f, 0.0, 0.0}}) {
    const double v = height_field_visibility(grating, amplitude, p, n);
    const double r = reference(p);
    EXPECT_LT(v, 1.0);
    // 8 azimuths and 24 steps (and the slope at the point): within 1 % of
    // the occlusion's own size here.
    EXPECT_NEAR(v, r, 0.01 * (1.0 - r) + 1e-4) << p.x;
  }
  // More relief, less visibility.
  EXPECT_LT(height_field_visibility(grating, 2.0 * amplitude, trough, n),
            height_field_visibility(grating, amplitude, trough, n));
}

// The march, one direction at a time, as it was written before the
// directions ran side by side (height.cpp): the visibility must keep its
// bits, which the micro-shadowing methods' renders and the study's cache
// depend on.
double visibility_one_direction_at_a_time(const HeightFunction& f, double amplitude, const Vec3& p,
                                          const Vec3& n) {
  double shortest_k = 0.0;
  for (const SineTerm& term : f.terms) {
    const double k = length(term.k);
    if (k > 0.0 && (shortest_k == 0.0 || k < shortest_k)) shortest_k = k;
  }
  const double dt = 2.0 / shortest_k / kVisibilitySteps;
  const Frame frame = Frame::from_z(n);
  const HeightSample here = evaluate_height(f, p);
  const bool sum = f.combine == HeightCombine::kSum;
  const std::size_t m =
      sum ? f.terms.size() : std::min<std::size_t>(f.terms.size(), kMaxProductFactors);
  double open = 0.0;
  for (int a = 0; a < kVisibilityAzimuths; ++a) {
    const double phi = 2.0 * kPi * (a + 0.5) / kVisibilityAzimuths;
    const Vec3 d = frame.s * std::cos(phi) + frame.t * std::sin(phi);
    double rise[kVisibilitySteps];
    for (double& r : rise) r = sum ? 0.0 : 1.0;
    for (std::size_t i = 0; i < m; ++i) {
      const double arg = 2.0 * kPi * dot(f.terms[i].k, p) + f.terms[i].phase;
      double s = std::sin(arg), c = std::cos(arg);
      const double delta = 2.0 * kPi * dot(f.terms[i].k, d) * dt;
      const double cos_delta = std::cos(delta), sin_delta = std::sin(delta);
      for (double& r : rise) {
        const double s_next = s * cos_delta + c * sin_delta;
        c = c * cos_delta - s * sin_delta;
        s = s_next;
        r = sum ? r + f.terms[i].weight * s : r * s;
      }
    }
    double tan_horizon = std::max(0.0, amplitude * dot(here.gradient, d));
    for (int j = 1; j <= kVisibilitySteps; ++j)
      tan_horizon = std::max(tan_horizon, amplitude * (rise[j - 1] - here.h) / (dt * j));
    open += 1.0 / (1.0 + tan_horizon * tan_horizon);
  }
  return open / kVisibilityAzimuths;
}

TEST(Height, VisibilityMarchEqualsStepByStepEvaluation) {
  // The visibility advances each term's phase by rotation; the definition
  // evaluates h at every step. Over 24 steps the two may differ by rounding
  // only, for sums and products of any number of terms. Against the march
  // one direction at a time it must not differ at all.
  const Vec3 dirs[] = {{1, 0, 0}, {0, 1, 0}, {0.6, 0.8, 0.0}};
  const HeightFunction families[] = {
      make_grating({1, 2, 0.5}, 7.0, 0.3), make_weave(dirs, 9.0, HeightCombine::kProduct),
      make_weave(dirs, 9.0, HeightCombine::kSum), make_noise(24, 4.0, 16.0, 5)};
  auto direct = [](const HeightFunction& f, double amplitude, const Vec3& p, const Vec3& n) {
    double shortest_k = 1e300;
    for (const SineTerm& t : f.terms) shortest_k = std::min(shortest_k, length(t.k));
    const double reach = 2.0 / shortest_k;
    const Frame frame = Frame::from_z(n);
    const HeightSample here = evaluate_height(f, p);
    double open = 0.0;
    for (int a = 0; a < kVisibilityAzimuths; ++a) {
      const double phi = 2.0 * kPi * (a + 0.5) / kVisibilityAzimuths;
      const Vec3 d = frame.s * std::cos(phi) + frame.t * std::sin(phi);
      double tan_horizon = std::max(0.0, amplitude * dot(here.gradient, d));
      for (int j = 1; j <= kVisibilitySteps; ++j) {
        const double t = reach * j / kVisibilitySteps;
        tan_horizon =
            std::max(tan_horizon, amplitude * (evaluate_height(f, p + d * t).h - here.h) / t);
      }
      open += 1.0 / (1.0 + tan_horizon * tan_horizon);
    }
    return open / kVisibilityAzimuths;
  };
  Pcg32 rng(41);
  int occluded = 0;
  for (const HeightFunction& f : families)
    for (int i = 0; i < 200; ++i) {
      const Vec3 p{rng.next_double(), rng.next_double(), rng.next_double()};
      const Vec3 n = normalize(Vec3{rng.next_double() - 0.5, rng.next_double() - 0.5, 1.0});
      const double amplitude = 0.03 * rng.next_double();
      const double v = height_field_visibility(f, amplitude, p, n);
      EXPECT_NEAR(v, direct(f, amplitude, p, n), 1e-12);
      ASSERT_EQ(v, visibility_one_direction_at_a_time(f, amplitude, p, n)) << "case " << i;
      ASSERT_EQ(height_field_visibility(f, -amplitude, p, n),
                visibility_one_direction_at_a_time(f, -amplitude, p, n))
          << "case " << i;
      occluded += v < 0.999;
    }
  EXPECT_GT(occluded, 400);  // the comparison is not between two ones
}

TEST(Vec, AcosApproximationStaysWithinItsStatedBound) {
  double worst = 0.0;
  for (int k = 0; k <= 2'000'000; ++k) {
    const double x = -1.0 + k * 1e-6;
    worst = std::max(worst, std::abs(acos_approx(x) - std::acos(std::clamp(x, -1.0, 1.0))));
  }
  EXPECT_LT(worst, 2.5e-8);
  EXPECT_EQ(acos_approx(1.0), 0.0);
  EXPECT_NEAR(acos_approx(-1.0), kPi, 1e-8);
  EXPECT_EQ(acos_approx(1.0 + 1e-15), 0.0);  // rounding past 1 is clamped
}

TEST(Shape, PrincipalFrameIsRightHandedAndOrthonormal) {
  Pcg32 rng(12);
  for (const Shape& s : {cylinder(false), sphere()})
    for (int i = 0; i < 1000; ++i) {
      const double u = 2 * kPi * rng.next_double();
      const double v = s.type == ShapeType::kSphere ? 0.05 + 3.0 * rng.next_double()
                                                    : (rng.next_double() - 0.5) * s.height;
      const SurfaceGeometry g = surface_at(s, u, v);
      EXPECT_NEAR(length(cross(g.t1, g.t2) - g.n), 0.0, 1e-12);
      EXPECT_NEAR(dot(g.t1, g.t2), 0.0, 1e-12);
      EXPECT_NEAR(length(g.p - s.center),
                  s.type == ShapeType::kSphere ? s.radius
                                               : std::hypot(s.radius, dot(g.p - s.center, s.axis)),
                  1e-12);
    }
}

TEST(Shape, RaysHitWhereTheClosedFormSays) {
  const Shape s = sphere();
  Pcg32 rng(13);
  for (int i = 0; i < 1000; ++i) {
    const Vec3 d = normalize(Vec3{rng.next_double() - 0.5, rng.next_double() - 0.5, 1.0});
    const Vec3 o =
        s.center - d * 5.0 + Vec3{rng.next_double() - 0.5, rng.next_double() - 0.5, 0} * 2.0;
    // Distance of the line from the centre decides hit or miss.
    const Vec3 oc = o - s.center;
    const double b = dot(oc, d), c = dot(oc, oc) - s.radius * s.radius;
    Hit hit;
    const bool got = intersect(s, {o, d}, 0.0, 1e30, &hit);
    EXPECT_EQ(got, b * b - c > 0);
    if (got) {
      EXPECT_NEAR(hit.t, -b - std::sqrt(b * b - c), 1e-9);
      EXPECT_NEAR(length(hit.geometry.p - s.center), s.radius, 1e-12);
      EXPECT_LT(dot(hit.geometry.n, d), 0.0);
    }
  }
}

TEST(Shape, CylinderCapsAndOpenEnds) {
  Shape s = cylinder(true);
  const Ray down{s.center + s.axis * 3.0, -s.axis};
  Hit hit;
  ASSERT_TRUE(intersect(s, down, 0.0, 1e30, &hit));
  EXPECT_NEAR(hit.t, 3.0 - 0.5 * s.height, 1e-12);
  EXPECT_FALSE(hit.geometry.displaceable);
  EXPECT_NEAR(dot(hit.geometry.n, s.axis), 1.0, 1e-12);
  s.caps = false;
  EXPECT_FALSE(intersect(s, down, 0.0, 1e30, &hit));  // straight through the open tube
}

TEST(Shape, ShadowRayFromTheSurfaceSkipsItsOwnOrigin) {
  const Shape s = sphere();
  const SurfaceGeometry g = surface_at(s, 1.0, 1.2);
  const Vec3 away = normalize(g.n + g.t1 * 0.3);
  EXPECT_FALSE(occluded(s, {g.p, away}, 1e-7 * s.radius, 1e30));
  const Vec3 into = normalize(-g.n + g.t1 * 0.3);
  EXPECT_TRUE(occluded(s, {g.p, into}, 1e-7 * s.radius, 1e30));
}

// The closed-form displaced normal against the normal of P'(u,v) computed by
// central differences of the displaced positions themselves.
TEST(Shape, DisplacedNormalMatchesFiniteDifferencesOfTheDisplacedSurface) {
  Pcg32 rng(14);
  for (const Shape& s : {cylinder(false), sphere()})
    for (const HeightFunction& f : families())
      for (double amplitude : {0.001, 0.02, 0.08})
        for (int i = 0; i < 200; ++i) {
          const double u = 2 * kPi * rng.next_double();
          const double v = s.type == ShapeType::kSphere ? 0.3 + 2.5 * rng.next_double()
                                                        : (rng.next_double() - 0.5) * s.height;
          auto displaced = [&](double uu, double vv) {
            const SurfaceGeometry g = surface_at(s, uu, vv);
            return displaced_point(g, amplitude, evaluate_height(f, g.p));
          };
          const double h = 1e-6;
          const Vec3 du = (displaced(u + h, v) - displaced(u - h, v)) / (2 * h);
          const Vec3 dv = (displaced(u, v + h) - displaced(u, v - h)) / (2 * h);
          Vec3 fd = normalize(cross(du, dv));
          const SurfaceGeometry g = surface_at(s, u, v);
          if (dot(fd, g.n) < 0) fd = -fd;
          const Vec3 ns = displaced_normal(g, amplitude, evaluate_height(f, g.p));
          EXPECT_NEAR(length(ns - fd), 0.0, 1e-6) << amplitude;
        }
}

// First order, Ns ~ normalize(N - A grad_s h) (reference sheet, section 5).
TEST(Shape, DisplacedNormalIsFirstOrderBumpForSmallAmplitude) {
  const Shape s = cylinder(false);
  const HeightFunction f = make_grating({1, 0, 0}, 8.0, 0.0);
  const SurfaceGeometry g = surface_at(s, 0.7, 0.2);
  const HeightSample hs = evaluate_height(f, g.p);
  for (double amplitude : {1e-2, 1e-3, 1e-4}) {
    const Vec3 grad_s = hs.gradient - g.n * dot(hs.gradient, g.n);
    const Vec3 first = normalize(g.n - grad_s * amplitude);
    const double error = length(displaced_normal(g, amplitude, hs) - first);
    EXPECT_LT(error, 5.0 * amplitude * amplitude * length(hs.gradient) * (1 + length(hs.gradient)));
  }
}

// The grid's rows are built in parallel: one thread or two, with normals or
// without, every vertex keeps its bits and its place in the layout, and the
// normals it does write are unit vectors.
TEST(GridMesh, SameVerticesWhateverTheThreadsAndWithoutNormals) {
  const HeightFunction height = families()[1];
  for (const ShapeType type : {ShapeType::kSphere, ShapeType::kCylinder, ShapeType::kPlane}) {
    Shape shape;
    shape.type = type;
    shape.caps = true;
    shape = with_frame(shape);
    const GridResolution res{67, 41};
    TriangleMesh serial;
    tbb::task_arena one(1);
    one.execute([&] { serial = make_grid_mesh(shape, height, 0.05, res); });
    const TriangleMesh parallel = make_grid_mesh(shape, height, 0.05, res);
    const TriangleMesh bare = make_grid_mesh(shape, height, 0.05, res, nullptr, GridNormals::kOmit);
    SCOPED_TRACE(static_cast<int>(type));
    ASSERT_GT(serial.vertex_count(), std::size_t(67 * 40));
    EXPECT_EQ(serial.positions, parallel.positions);
    EXPECT_EQ(serial.normals, parallel.normals);
    EXPECT_EQ(serial.triangles, parallel.triangles);
    EXPECT_EQ(serial.positions, bare.positions);
    EXPECT_EQ(serial.triangles, bare.triangles);
    EXPECT_TRUE(bare.normals.empty());
    // Each vertex where the documented layout (core/grid_mesh.h) puts it:
    // the displaced point of its own (u, v), every 7th column and 5th row.
    const bool sphere = type == ShapeType::kSphere, plane = type == ShapeType::kPlane;
    const unsigned columns = plane ? res.nu + 1 : res.nu;
    for (unsigned j = sphere ? 1 : 0; j < (sphere ? res.nv : res.nv + 1); j += 5)
      for (unsigned i = 0; i < columns; i += 7) {
        const std::size_t index =
            sphere ? 1 + std::size_t(j - 1) * res.nu + i : std::size_t(j) * columns + i;
        const SurfaceGeometry g = surface_at(shape, grid_u(shape, res, i), grid_v(shape, res, j));
        const Vec3 q = displaced_point(g, 0.05, height_at(height, nullptr, shape, g));
        const float* v = &parallel.positions[3 * index];
        ASSERT_TRUE(v[0] == float(q.x) && v[1] == float(q.y) && v[2] == float(q.z))
            << "vertex (" << i << ", " << j << ")";
      }
    ASSERT_EQ(serial.normals.size(), serial.positions.size());
    for (std::size_t i = 0; i < serial.normals.size(); i += 3) {
      const double length =
          std::hypot(serial.normals[i], serial.normals[i + 1], serial.normals[i + 2]);
      ASSERT_NEAR(length, 1.0, 1e-6) << "vertex " << i / 3;
    }
  }
}

}  // namespace
}  // namespace penumbra
