// Schilling's pyramid and the roughness filters against direct computation
// over the finest texels, closed forms derived here, and the papers' claims.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/bump_pyramid.h"
#include "core/random.h"
#include "core/roughness_filter.h"

namespace penumbra {
namespace {

std::vector<Offset2> random_offsets(int n, std::uint64_t seed) {
  Pcg32 rng(seed);
  std::vector<Offset2> offsets(n);
  // Anisotropic and correlated, with a mean, so that every term of K is
  // exercised: f_u in [-0.5, 0.5] + 0.2, f_v = 0.3 f_u + noise.
  for (Offset2& f : offsets) {
    f.f_u = rng.next_double() - 0.3;
    f.f_v = 0.3 * f.f_u + 0.2 * (rng.next_double() - 0.5);
  }
  return offsets;
}

struct Moments {
  double mu_u = 0, mu_v = 0;
  Covariance2 k;
  Vec3 mean_normal;
};

// Mean, population covariance and mean unit normal of the finest texels that
// texel (x, y) of `level` covers, straight from level 0.
Moments direct_moments(const PyramidLevel& finest, int level, int x, int y) {
  const int x0 = x << level, y0 = y << level;
  const int x1 = std::min(x0 + (1 << level), finest.width);
  const int y1 = std::min(y0 + (1 << level), finest.height);
  Moments m;
  double n = 0;
  for (int j = y0; j < y1; ++j)
    for (int i = x0; i < x1; ++i) {
      const Offset2 f = finest.offset(i, j);
      m.mu_u += f.f_u;
      m.mu_v += f.f_v;
      m.mean_normal += normalize(Vec3(f.f_u, f.f_v, 1.0));
      n += 1;
    }
  m.mu_u /= n;
  m.mu_v /= n;
  m.mean_normal = m.mean_normal / n;
  for (int j = y0; j < y1; ++j)
    for (int i = x0; i < x1; ++i) {
      const Offset2 f = finest.offset(i, j);
      const double du = f.f_u - m.mu_u, dv = f.f_v - m.mu_v;
      m.k.a += du * du / n;
      m.k.b += du * dv / n;
      m.k.c += dv * dv / n;
    }
  return m;
}

double largest_eigenvalue(const Covariance2& k) {
  const double t = k.a + k.c, d = k.a * k.c - k.b * k.b;
  return 0.5 * t + std::sqrt(std::max(0.25 * t * t - d, 0.0));
}

// The paper's claim: "This formula is equivalent to the calculation of the
// covariance matrix for all f_u and f_v values in the highest resolution
// level for the whole area covered by the respective texel in level l."
// Float storage over up to 5 levels: relative error ~1e-7 per level.
TEST(BumpPyramid, CovarianceIsThatOfEveryCoveredFinestOffset) {
  for (const auto& [w, h] : {std::pair{16, 16}, std::pair{13, 10}, std::pair{1, 7}}) {
    const std::vector<PyramidLevel> levels =
        build_bump_pyramid(level_from_offsets(random_offsets(w * h, 3 + w), w, h));
    EXPECT_EQ(levels.back().width, 1);
    EXPECT_EQ(levels.back().height, 1);
    for (int l = 0; l < int(levels.size()); ++l) {
      EXPECT_EQ(levels[l].width, (w + (1 << l) - 1) >> l);
      for (int y = 0; y < levels[l].height; ++y)
        for (int x = 0; x < levels[l].width; ++x) {
          const Moments m = direct_moments(levels[0], l, x, y);
          const Covariance2 k = levels[l].covariance(x, y);
          const double tol = 1e-6 * (1.0 + m.k.a + m.k.c);
          EXPECT_NEAR(levels[l].f_u[levels[l].index(x, y)], m.mu_u, tol);
          EXPECT_NEAR(levels[l].f_v[levels[l].index(x, y)], m.mu_v, tol);
          EXPECT_NEAR(k.a, m.k.a, tol) << w << "x" << h << " level " << l;
          EXPECT_NEAR(k.b, m.k.b, tol);
          EXPECT_NEAR(k.c, m.k.c, tol);
          EXPECT_NEAR(isotropic_roughness(k), std::sqrt(largest_eigenvalue(m.k)), 1e-5);
          const Vec3 n = levels[l].mean_normal(x, y);
          EXPECT_NEAR(n.x, m.mean_normal.x, 1e-6);
          EXPECT_NEAR(n.z, m.mean_normal.z, 1e-6);
        }
    }
  }
}

TEST(BumpPyramid, FlatMapHasZeroRoughnessAtEveryLevel) {
  const std::vector<float> heights(24 * 20, 0.75f);
  for (MapEdge edge : {MapEdge::kWrap, MapEdge::kClamp})
    for (const PyramidLevel& level :
         build_bump_pyramid(offsets_from_heights(heights, 24, 20, 0.01, 3.0, edge)))
      for (std::size_t i = 0; i < level.f_u.size(); ++i) {
        EXPECT_EQ(level.f_u[i], 0.0f);
        EXPECT_EQ(level.f_v[i], 0.0f);
        EXPECT_EQ(level.k_a[i], 0.0f);
        EXPECT_EQ(level.k_b[i], 0.0f);
        EXPECT_EQ(level.k_c[i], 0.0f);
        EXPECT_EQ(level.n_z[i], 1.0f);
      }
}

// A plane h = 0.3 x - 0.2 y (scene units; x along columns, y down the rows)
// has slope f_u = 0.3 and, v pointing up, f_v = +0.2 everywhere: clamped
// edges keep the differences one-sided, so every texel sees the same slope.
TEST(BumpPyramid, ConstantSlopeMapHasZeroRoughnessAndItsSlope) {
  const int w = 32, h = 24;
  const double texel = 0.05, scale = 2.0;
  std::vector<float> heights(w * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      heights[y * w + x] = float((0.3 * x * texel - 0.2 * y * texel) / scale);
  const std::vector<PyramidLevel> levels =
      build_bump_pyramid(offsets_from_heights(heights, w, h, texel, scale, MapEdge::kClamp));
  for (const PyramidLevel& level : levels)
    for (int y = 0; y < level.height; ++y)
      for (int x = 0; x < level.width; ++x) {
        const Offset2 f = level.offset(x, y);
        EXPECT_NEAR(f.f_u, 0.3, 2e-5);
        EXPECT_NEAR(f.f_v, 0.2, 2e-5);
        EXPECT_LT(isotropic_roughness(level.covariance(x, y)), 2e-5);
      }
}

// Central differences of A sin(w x) sampled every t return A w cos(w x)
// times sin(w t) / (w t): the transfer function of the difference.
TEST(BumpPyramid, OffsetsAreCentralDifferencesWithTheirKnownTransfer) {
  const int w = 64;
  const double texel = 0.01, amplitude = 0.02, omega = 2.0 * kPi * 4.0 / (w * texel);
  std::vector<float> heights(w * 2);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < w; ++x) heights[y * w + x] = float(amplitude * std::sin(omega * x * texel));
  const PyramidLevel level = offsets_from_heights(heights, w, 2, texel, 1.0, MapEdge::kWrap);
  const double transfer = std::sin(omega * texel) / (omega * texel);
  for (int x = 0; x < w; ++x) {
    EXPECT_NEAR(level.offset(x, 0).f_u, amplitude * omega * std::cos(omega * x * texel) * transfer,
                1e-5);
    EXPECT_NEAR(level.offset(x, 1).f_v, 0.0, 1e-7);
  }
}

Covariance2 random_spd(Pcg32& rng, double smaller_over_larger) {
  const double angle = kPi * rng.next_double(), l1 = 0.01 + rng.next_double();
  const double l2 = l1 * smaller_over_larger;
  const double c = std::cos(angle), s = std::sin(angle);
  return {l1 * c * c + l2 * s * s, (l1 - l2) * c * s, l1 * s * s + l2 * c * c};
}

TEST(BumpPyramid, FactorTimesItsTransposeIsK) {
  Pcg32 rng(5);
  for (double ratio : {1.0, 0.5, 1e-3, 1e-9, 1e-15, 0.0})
    for (int i = 0; i < 200; ++i) {
      const Covariance2 k = random_spd(rng, ratio);
      const RoughnessFactor d = roughness_factor(k);
      ASSERT_TRUE(std::isfinite(d.d1) && std::isfinite(d.d2) && std::isfinite(d.d3));
      EXPECT_GE(d.d1, 0.0);
      EXPECT_GE(d.d3, 0.0);
      const Covariance2 back = covariance_from_factor(d);
      const double tol = 1e-12 * (k.a + k.c);
      EXPECT_NEAR(back.a, k.a, tol) << "ratio " << ratio;
      EXPECT_NEAR(back.b, k.b, tol);
      EXPECT_NEAR(back.c, k.c, tol);
    }
  // c == 0: the paper's formulas divide by zero; the factor is still exact.
  const Covariance2 k{0.4, 0.0, 0.0};
  const Covariance2 back = covariance_from_factor(roughness_factor(k));
  EXPECT_DOUBLE_EQ(back.a, 0.4);
  EXPECT_EQ(back.b, 0.0);
  EXPECT_EQ(back.c, 0.0);
}

TEST(BumpPyramid, Lambda1BoundsTheVarianceInEveryDirection) {
  Pcg32 rng(6);
  for (int i = 0; i < 200; ++i) {
    const Covariance2 k = random_spd(rng, rng.next_double());
    const double l1 = isotropic_roughness(k);
    double largest = 0.0;
    for (int j = 0; j < 360; ++j) {
      const double c = std::cos(radians(j * 0.5)), s = std::sin(radians(j * 0.5));
      const double variance = k.a * c * c + 2 * k.b * c * s + k.c * s * s;
      EXPECT_LE(variance, l1 * l1 * (1 + 1e-12));
      largest = std::max(largest, variance);
    }
    EXPECT_NEAR(largest, l1 * l1, 1e-4 * l1 * l1);  // 0.5 degree grid
  }
}

// A lookup at a texel's centre at its own level is that texel; halfway
// between two texels of a level, the equal-weight mixture of the two is
// exactly the pooled covariance of every finest offset both cover.
TEST(BumpPyramid, LookupMixesTexelsWithTheMomentsOfTheirUnion) {
  const int n = 16;
  const std::vector<PyramidLevel> levels =
      build_bump_pyramid(level_from_offsets(random_offsets(n * n, 21), n, n));
  for (int l = 0; l < 3; ++l) {  // level 2 is 4x4: texels 2 and 3 of a row exist
    const double size = double(1 << l);
    const FilteredTexel t = sample_pyramid(levels, 2.5 * size, 1.5 * size, size, MapEdge::kWrap);
    const Covariance2 k = levels[l].covariance(2, 1);
    EXPECT_NEAR(t.covariance.a, k.a, 1e-7);
    EXPECT_NEAR(t.covariance.c, k.c, 1e-7);
    EXPECT_NEAR(t.mean.f_u, levels[l].offset(2, 1).f_u, 1e-7);
    // Between texels (2, 1) and (3, 1): the centre x = 3 size.
    const FilteredTexel mid = sample_pyramid(levels, 3.0 * size, 1.5 * size, size, MapEdge::kWrap);
    Moments left = direct_moments(levels[0], l, 2, 1), right = direct_moments(levels[0], l, 3, 1);
    const double mu_u = 0.5 * (left.mu_u + right.mu_u), mu_v = 0.5 * (left.mu_v + right.mu_v);
    const double pooled_a = 0.5 * (left.k.a + (left.mu_u - mu_u) * (left.mu_u - mu_u)) +
                            0.5 * (right.k.a + (right.mu_u - mu_u) * (right.mu_u - mu_u));
    const double pooled_b = 0.5 * (left.k.b + (left.mu_u - mu_u) * (left.mu_v - mu_v)) +
                            0.5 * (right.k.b + (right.mu_u - mu_u) * (right.mu_v - mu_v));
    EXPECT_NEAR(mid.mean.f_u, mu_u, 1e-6);
    EXPECT_NEAR(mid.covariance.a, pooled_a, 1e-6) << "level " << l;
    EXPECT_NEAR(mid.covariance.b, pooled_b, 1e-6);
  }
  // Wrapped: a lookup at x = 0 blends the last column and the first.
  const FilteredTexel edge = sample_pyramid(levels, 0.0, 0.5, 1.0, MapEdge::kWrap);
  EXPECT_NEAR(edge.mean.f_u, 0.5 * (levels[0].offset(15, 0).f_u + levels[0].offset(0, 0).f_u),
              1e-7);
  // Between levels: footprint 2^1.5 mixes levels 1 and 2 half and half.
  const FilteredTexel between =
      sample_pyramid(levels, 4.0, 4.0, std::pow(2.0, 1.5), MapEdge::kWrap);
  const FilteredTexel at1 = sample_pyramid(levels, 4.0, 4.0, 2.0, MapEdge::kWrap);
  const FilteredTexel at2 = sample_pyramid(levels, 4.0, 4.0, 4.0, MapEdge::kWrap);
  EXPECT_NEAR(between.mean.f_u, 0.5 * (at1.mean.f_u + at2.mean.f_u), 1e-12);
}

// Appendix A: "We get alpha' < alpha, if the variance of n in the regarded
// direction is larger than 1, otherwise we get alpha' >= alpha", and the
// isotropic form is the unmodified Blinn-Phong at lambda1 = 1.
TEST(Schilling, ModifiedBlinnPhongIsTheUnmodifiedOneAtLambdaOne) {
  for (double cos2 = 0.0; cos2 <= 1.0; cos2 += 0.05) {
    EXPECT_NEAR(schilling_cos2_alpha_isotropic(cos2, 1.0), cos2, 1e-15);
    EXPECT_GE(schilling_cos2_alpha_isotropic(cos2, 1.7), cos2 - 1e-15);
    EXPECT_LE(schilling_cos2_alpha_isotropic(cos2, 0.4), cos2 + 1e-15);
  }
  Pcg32 rng(8);
  for (int i = 0; i < 500; ++i) {
    const double theta = 0.5 * kPi * rng.next_double(), phi = 2 * kPi * rng.next_double();
    const Vec3 h{std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
    const double cos2 = h.z * h.z;
    EXPECT_NEAR(schilling_cos2_alpha(h, {1, 0, 1}), cos2, 1e-14);
    for (double lambda : {0.05, 0.3, 2.0})
      EXPECT_NEAR(schilling_cos2_alpha(h, {lambda * lambda, 0, lambda * lambda}),
                  schilling_cos2_alpha_isotropic(cos2, lambda), 1e-12);
  }
}

// d^T K^-1 d depends on K and d only: rotating both about n leaves the
// value unchanged (the reading of |D d| that does not depend on the factor).
TEST(Schilling, AnisotropicFormIsInvariantUnderRotationsAboutTheNormal) {
  Pcg32 rng(9);
  for (int i = 0; i < 300; ++i) {
    const Covariance2 k = random_spd(rng, 0.05 + rng.next_double());
    const double theta = 0.4 * kPi * rng.next_double(), phi = 2 * kPi * rng.next_double();
    const Vec3 h{std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
    const double r = 2 * kPi * rng.next_double(), c = std::cos(r), s = std::sin(r);
    const Vec3 h_rotated{c * h.x - s * h.y, s * h.x + c * h.y, h.z};
    // K' = R K R^T
    const Covariance2 k_rotated{c * c * k.a - 2 * c * s * k.b + s * s * k.c,
                                c * s * (k.a - k.c) + (c * c - s * s) * k.b,
                                s * s * k.a + 2 * c * s * k.b + c * c * k.c};
    EXPECT_NEAR(schilling_cos2_alpha(h, k), schilling_cos2_alpha(h_rotated, k_rotated), 1e-12);
  }
  // A rank-one K keeps the highlight only along its range.
  EXPECT_GT(schilling_cos2_alpha(normalize(Vec3(0.2, 0, 1)), {0.3, 0, 0}), 0.5);
  EXPECT_EQ(schilling_cos2_alpha(normalize(Vec3(0.0, 0.2, 1)), {0.3, 0, 0}), 0.0);
}

// Frame 1 on a plane is exact: the displaced plane p + f n/|n| has normal
// (p_u + f_u n/|n|) x (p_v + f_v n/|n|) = n + f_u s_u + f_v s_v.
TEST(BumpPyramid, FramesGiveTheDisplacedSurfacesNormal) {
  const Vec3 p_u{0.7, 0.1, 0.0}, p_v{0.3, 1.2, 0.2};
  const Offset2 f{0.25, -0.4};
  const BumpFrame natural = natural_frame(p_u, p_v);
  const Vec3 n_unit = normalize(natural.n);
  const Vec3 exact = cross(p_u + n_unit * f.f_u, p_v + n_unit * f.f_v);
  const Vec3 bumped = bumped_normal(natural, f);
  EXPECT_NEAR(length(bumped - exact), 0.0, 1e-14);
  // Frame 2 on an isometric (u, v) = (x, y) plane: offsets are the slopes
  // of z = h(x, y), whose normal is (-h_x, -h_y, 1).
  const Vec3 n2 = normalize(bumped_normal(normalized_natural_frame({1, 0, 0}, {0, 1, 0}), f));
  EXPECT_NEAR(length(n2 - normalize(Vec3(-f.f_u, -f.f_v, 1.0))), 0.0, 1e-15);
  // Frame 3: orthonormal, e1 perpendicular to m, e2 in the plane of n and m.
  const Vec3 m{0, 0, 1};
  const BumpFrame f3 = main_direction_frame({0.6, 0.2, 0.5}, m);
  EXPECT_NEAR(dot(f3.s_u, m), 0.0, 1e-15);
  EXPECT_NEAR(dot(f3.s_v, cross(f3.n, m)), 0.0, 1e-15);
  EXPECT_NEAR(length(f3.s_u), 1.0, 1e-15);
  EXPECT_NEAR(dot(f3.s_u, f3.s_v), 0.0, 1e-15);
  EXPECT_NEAR(dot(cross(f3.s_u, f3.s_v), f3.n), 1.0, 1e-15);
}

// RTG ch. 12, Fig. 12-5: truncated at slopes of radius 4 alpha, GGX keeps
// 94.1 % of its mass and its mean tan^2 is 2.01 alpha^2. The closed forms
// (16/17 and (ln 17 + 1/17 - 1) / (16/17)) are derived in the test.
TEST(RoughnessFilter, GgxTruncatedVarianceNumbersOfTheChapter) {
  const TruncatedMoments m = ggx_truncated_slope_moments(4.0);
  EXPECT_NEAR(m.mass, 0.941, 5e-4);
  EXPECT_NEAR(m.mean_tan2_over_alpha2, 2.01, 5e-3);
  EXPECT_NEAR(m.mass, 16.0 / 17.0, 1e-10);
  EXPECT_NEAR(m.mean_tan2_over_alpha2, (std::log(17.0) + 1.0 / 17.0 - 1.0) / (16.0 / 17.0), 1e-9);
  // GGX has no variance: the truncated mean keeps growing with the radius.
  EXPECT_GT(ggx_truncated_slope_moments(40.0).mean_tan2_over_alpha2, 2 * m.mean_tan2_over_alpha2);
}

TEST(RoughnessFilter, TableIdsAreUniqueAndRoundTrip) {
  for (const RoughnessFilterInfo& f : all_roughness_filters()) {
    EXPECT_EQ(roughness_filter_from_id(f.id), f.filter);
    EXPECT_EQ(roughness_filter_info(f.filter).id, f.id);
    EXPECT_FALSE(f.source.empty());
    for (const FilterParameter& p : f.parameters) {
      EXPECT_LE(p.min_value, p.default_value);
      EXPECT_LE(p.default_value, p.max_value);
    }
  }
  EXPECT_FALSE(roughness_filter_from_id("estevez2019").has_value());  // a terminator method
}

// A footprint without sub-texel bumps keeps the material's lobe.
TEST(RoughnessFilter, AFootprintWithoutBumpsKeepsTheBaseLobe) {
  for (const RoughnessFilterInfo& info : all_roughness_filters()) {
    FilterSettings settings;
    settings.filter = info.filter;
    for (double alpha : {0.01, 0.2, 0.8}) {
      const FilteredLobe lobe = filter_roughness(settings, {}, alpha);
      const double expected = info.distribution == FilteredDistribution::kSchillingBlinnPhong
                                  ? 0.5 * alpha * alpha
                                  : alpha * alpha;
      EXPECT_NEAR(lobe.alpha2.a, expected, 1e-12 * expected) << info.id << " alpha " << alpha;
      EXPECT_EQ(lobe.alpha2.b, 0.0);
      EXPECT_NEAR(lobe.alpha2.c, expected, 1e-12 * expected) << info.id;
    }
  }
}

// The two mappings of Fig. 12-6 differ by the factor two of sigma^2 = 2
// alpha^2; and with small slopes, Toksvig's normal-length variance reads
// the same roughness as the covariance: |n| ~ 1 - tr K / 2, so alpha'^2 ~
// alpha^2 + tr K (the Beckmann mapping), measured on a real pyramid.
TEST(RoughnessFilter, MappingsAgreeWhereTheirDerivationsSayTheyShould) {
  const Covariance2 k{0.02, 0.005, 0.01};
  FilterSettings settings;
  settings.filter = RoughnessFilter::kBeckmannVariance;
  const double beckmann = filter_roughness(settings, {k}, 0.3).alpha2.a;
  settings.filter = RoughnessFilter::kGgxVarianceEstevez2019;
  const double ggx = filter_roughness(settings, {k}, 0.3).alpha2.a;
  EXPECT_NEAR(beckmann - 0.09, 0.03, 1e-15);
  EXPECT_NEAR(ggx - 0.09, 0.015, 1e-15);

  const int n = 64;
  Pcg32 rng(12);
  std::vector<Offset2> offsets(n * n);
  for (Offset2& f : offsets)
    f = {0.04 * (rng.next_double() - 0.5), 0.02 * (rng.next_double() - 0.5)};
  const std::vector<PyramidLevel> levels = build_bump_pyramid(level_from_offsets(offsets, n, n));
  const FootprintStatistics top{levels.back().covariance(0, 0),
                                length(levels.back().mean_normal(0, 0))};
  settings.filter = RoughnessFilter::kToksvig2005;
  const double toksvig = filter_roughness(settings, top, 0.1).alpha2.a;
  settings.filter = RoughnessFilter::kBeckmannVariance;
  const double from_k = filter_roughness(settings, top, 0.1).alpha2.a;
  EXPECT_NEAR(toksvig - 0.01, from_k - 0.01, 0.05 * (from_k - 0.01));
}

TEST(RoughnessFilter, TokuyoshiKernelIsClampedAndSaturated) {
  FilterSettings settings;
  settings.filter = RoughnessFilter::kTokuyoshi2021;
  EXPECT_NEAR(filter_roughness(settings, {{}, 1.0, 0.5}, 0.2).alpha2.a, 0.04 + 0.5 / (2 * kPi),
              1e-15);
  EXPECT_NEAR(filter_roughness(settings, {{}, 1.0, 50.0}, 0.2).alpha2.a, 0.04 + 0.18, 1e-15);
  EXPECT_EQ(filter_roughness(settings, {{}, 1.0, 50.0}, 0.95).alpha2.a, 1.0);
}

}  // namespace
}  // namespace penumbra
