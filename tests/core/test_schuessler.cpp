// Schuessler et al. 2017: properties the paper states or that follow from
// its microsurface (a height field of a diffuse facet and a mirror), checked
// by quadrature and Monte Carlo written here, not against stored outputs.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/bsdf.h"
#include "core/random.h"
#include "core/schuessler.h"
#include "core/test_directions.h"

namespace penumbra {
namespace {

using test::in_plane;
using test::kZ;
using test::random_unit;
using test::spherical;

Material white_lambert() {
  Material m;
  m.albedo = 1.0;
  return m;
}

// Directional albedo seen from v: the integral of the throughput over every
// light direction above the macro-surface, by a midpoint rule in
// (cos theta, phi), which is exact for constant integrands.
template <typename Throughput>
double albedo(const Throughput& throughput, const Vec3& v, int n = 400) {
  double sum = 0.0;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < 2 * n; ++b) {
      const double mu = (a + 0.5) / n, phi = kPi * (b + 0.5) / n;
      sum += throughput(spherical(std::acos(mu), phi), v);
    }
  return sum * (2.0 * kPi) / (2.0 * n * n);
}

TEST(Schuessler2017, TangentFacetClosesTheHeightField) {
  // <w,Ng> = ap(w) + at(w) wherever w sees the front of both facets: the
  // two facets project onto exactly one unit of macro-surface.
  const MicrosurfaceFacets f = make_facets(kZ, in_plane(0.5));
  ASSERT_FALSE(f.degenerate);
  EXPECT_NEAR(dot(f.wt, kZ), 0.0, 1e-15);
  EXPECT_LT(dot(f.wt, f.wp), 0.0);  // faces away from wp
  for (double t : {-0.9, -0.6, -0.3}) {
    const Vec3 w = in_plane(t);
    ASSERT_GT(dot(w, f.wp), 0.0);
    ASSERT_GT(dot(w, f.wt), 0.0);
    EXPECT_NEAR(projected_area_p(f, w) + projected_area_t(f, w), w.z, 1e-15);
    EXPECT_DOUBLE_EQ(schuessler_g1(f, w, f.wp), 1.0);
  }
  // Towards the perturbed side, the tangent facet is hidden: G1 < 1.
  EXPECT_LT(schuessler_g1(f, in_plane(1.2), f.wp), 1.0);
}

TEST(Schuessler2017, WithoutPerturbationIsThePlainBsdf) {
  Material m;
  m.specular_weight = 0.3;
  const Vec3 l = spherical(0.7, 0.4), v = spherical(0.3, 2.0);
  const LobeValues plain = evaluate_lobes(m, kZ, l, v);
  const double expected = (plain.diffuse + plain.specular) * l.z;
  EXPECT_DOUBLE_EQ(schuessler2017(m, kZ, kZ, l, v), expected);
  EXPECT_DOUBLE_EQ(schuessler2017_shadowing(m, kZ, kZ, l, v), expected);
  Pcg32 rng(3);
  EXPECT_DOUBLE_EQ(schuessler2017_walk(m, kZ, kZ, l, v, rng), expected);
}

// White furnace: a white Lambertian facet and a perfect mirror lose no
// energy, so the walk's albedo is 1; the explicit evaluation drops the
// longer paths and stays below. (The shadowing-only variant is not a
// truncation of the walk: its closed form is checked below.)
TEST(Schuessler2017, WhiteFurnace) {
  const Material m = white_lambert();
  for (double deviation : {0.2, 0.6, 1.0}) {
    const Vec3 wp = in_plane(deviation);
    for (double view : {0.0, 0.6, -0.6, 1.2}) {
      const Vec3 v = in_plane(view);
      const double explicit_albedo =
          albedo([&](const Vec3& l, const Vec3& w) { return schuessler2017(m, kZ, wp, l, w); }, v);
      const double shadowing_albedo = albedo(
          [&](const Vec3& l, const Vec3& w) { return schuessler2017_shadowing(m, kZ, wp, l, w); },
          v);
      Pcg32 rng(17);
      // Monte Carlo over the light direction and the walk together.
      constexpr int kSamples = 400'000;
      double sum = 0.0, sum2 = 0.0;
      for (int k = 0; k < kSamples; ++k) {
        const Vec3 l = spherical(std::acos(rng.next_double()), 2.0 * kPi * rng.next_double());
        const double x = 2.0 * kPi * schuessler2017_walk(m, kZ, wp, l, v, rng, 256);
        sum += x;
        sum2 += x * x;
      }
      const double walk_albedo = sum / kSamples;
      const double walk_error = std::sqrt((sum2 / kSamples - walk_albedo * walk_albedo) / kSamples);
      EXPECT_LE(explicit_albedo, 1.0 + 1e-3) << deviation << " " << view;
      EXPECT_LT(shadowing_albedo, 1.0) << deviation << " " << view;
      EXPECT_NEAR(walk_albedo, 1.0, 5.0 * walk_error) << deviation << " " << view;
      EXPECT_GT(walk_albedo, explicit_albedo - 5.0 * walk_error) << deviation << " " << view;
    }
  }
}

// The walk capped at one visit of p contains the explicit evaluation's three
// paths plus one: v->t->p->t->l, the light reaching p off the mirror after
// the viewer's ray came off it too. Transcribed here from the path weights.
TEST(Schuessler2017, OneVisitWalkIsTheExplicitEvaluationPlusOnePath) {
  const Material m = white_lambert();
  const Vec3 wp = in_plane(0.5), l = in_plane(-1.2), v = in_plane(-0.9);
  const MicrosurfaceFacets f = make_facets(kZ, wp);
  const Vec3 l_m = mirror_on_tangent(f, l), v_m = mirror_on_tangent(f, v);
  const double lambert = 1.0 / kPi;
  const double extra = (1.0 - lambda_p(f, v)) * (dot(v_m, wp) > 0 ? 1.0 : 0.0) * lambert *
                       std::max(0.0, dot(l_m, wp)) * (1.0 - schuessler_g1(f, l_m, wp)) *
                       schuessler_g1(f, l, f.wt);
  ASSERT_GT(extra, 1e-3);  // the case exercises that path
  Pcg32 rng(5);
  constexpr int kSamples = 2'000'000;
  double sum = 0.0;
  for (int k = 0; k < kSamples; ++k) sum += schuessler2017_walk(m, kZ, wp, l, v, rng, 1);
  const double expected = schuessler2017(m, kZ, wp, l, v) + extra;
  EXPECT_NEAR(sum / kSamples, expected, 3e-3 * expected);
}

// Closed forms for a diffuse base of albedo rho, derived from the path
// weights (c = <wp,Ng>, s = sin): seen head-on the explicit form is Lambert
// about Ng darkened by c; the shadowing-only variant reflects
// S = (1 + c - s)/2 of a white sky towards every viewer; the uncapped walk
// is Lambert about Ng with albedo rho c / (1 - rho (1 - c)).
TEST(Schuessler2017, DiffuseClosedForms) {
  Material m;
  m.albedo = 0.5;
  const double theta_p = radians(40.0);
  const Vec3 wp = in_plane(theta_p);
  const double c = std::cos(theta_p), s = std::sin(theta_p);
  for (double a : {-1.4, -0.9, -0.2, 0.3, 1.1, 1.5}) {
    const Vec3 l = in_plane(a);
    EXPECT_NEAR(schuessler2017(m, kZ, wp, l, kZ), m.albedo / kPi * l.z * c, 1e-15) << a;
  }
  // Chiang et al. 2019, Fig. 3c: light along Ns is shadowed all the same,
  // here by G1(wp, wp) = cos^2 of the deviation.
  const double bumped = m.albedo / kPi;
  EXPECT_NEAR(schuessler2017_shadowing(m, kZ, wp, wp, kZ), bumped * c * c, 1e-15);
  Material white = m;
  white.albedo = 1.0;
  for (double view : {0.0, -0.7, 0.7, -1.3}) {
    const double shadowing = albedo(
        [&](const Vec3& l, const Vec3& v) { return schuessler2017_shadowing(white, kZ, wp, l, v); },
        in_plane(view));
    EXPECT_NEAR(shadowing, 0.5 * (1.0 + c - s), 2e-4) << view;
  }
  const double walk_albedo = m.albedo * c / (1.0 - m.albedo * (1.0 - c));
  const Vec3 l = in_plane(-1.1), v = in_plane(-0.8);
  Pcg32 rng(8);
  constexpr int kSamples = 1'000'000;
  double sum = 0.0, sum2 = 0.0;
  for (int k = 0; k < kSamples; ++k) {
    const double x = schuessler2017_walk(m, kZ, wp, l, v, rng, 256);
    sum += x;
    sum2 += x * x;
  }
  const double mean = sum / kSamples;
  const double error = std::sqrt((sum2 / kSamples - mean * mean) / kSamples);
  EXPECT_NEAR(mean, walk_albedo / kPi * l.z, 5.0 * error);
}

TEST(Schuessler2017, WalkIsDeterministicAndItsVarianceFallsAsOneOverN) {
  const Material m = white_lambert();
  const Vec3 wp = in_plane(0.6), l = in_plane(-1.0), v = in_plane(0.4);
  Pcg32 a(99), b(99);
  for (int k = 0; k < 1000; ++k)
    ASSERT_EQ(schuessler2017_walk(m, kZ, wp, l, v, a), schuessler2017_walk(m, kZ, wp, l, v, b));
  // Variance of a mean of N walks over 2000 independent batches.
  auto variance_of_mean = [&](int n) {
    Pcg32 rng(1234 + n);
    constexpr int kBatches = 2000;
    double s = 0.0, s2 = 0.0;
    for (int i = 0; i < kBatches; ++i) {
      double mean = 0.0;
      for (int k = 0; k < n; ++k) mean += schuessler2017_walk(m, kZ, wp, l, v, rng);
      mean /= n;
      s += mean;
      s2 += mean * mean;
    }
    return (s2 - s * s / kBatches) / (kBatches - 1);
  };
  const double ratio = variance_of_mean(4) / variance_of_mean(16);
  // The ratio of two sample variances of 2000 batches each: 4 within about
  // 4 * 2 * sqrt(2/2000) = 25 % at five sigma... use 30 %.
  EXPECT_NEAR(ratio, 4.0, 1.2);
}

TEST(Schuessler2017, FiniteAndNonNegativeOnDegenerateInputs) {
  const Material m = white_lambert();
  const double tiny = 1e-12;
  const std::vector<Vec3> normals{kZ,  in_plane(tiny), in_plane(kPi / 2),       in_plane(2.0),
                                  -kZ, in_plane(0.5),  in_plane(kPi / 2 - tiny)};
  const std::vector<Vec3> directions{kZ,
                                     in_plane(kPi / 2),
                                     in_plane(-kPi / 2),
                                     in_plane(2.5),
                                     in_plane(0.5),
                                     in_plane(-0.5),
                                     in_plane(tiny)};
  Pcg32 rng(7);
  for (const Vec3& wp : normals)
    for (const Vec3& l : directions)
      for (const Vec3& v : directions) {
        for (double x : {schuessler2017(m, kZ, wp, l, v), schuessler2017_shadowing(m, kZ, wp, l, v),
                         schuessler2017_walk(m, kZ, wp, l, v, rng)})
          ASSERT_TRUE(std::isfinite(x) && x >= 0.0) << wp.x << " " << l.x << " " << v.x;
      }
}

}  // namespace
}  // namespace penumbra
