// Properties of the shadowing factors, checked against the papers' own
// statements and independent re-implementations (not against the code's output).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/bsdf.h"
#include "core/random.h"
#include "core/terminator.h"

namespace penumbra {
namespace {

Vec3 random_unit(Pcg32& rng) {
  const double z = 1.0 - 2.0 * rng.next_double();
  const double phi = 2.0 * kPi * rng.next_double();
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  return {r * std::cos(phi), r * std::sin(phi), z};
}

// Unit vector in the x-z plane at `angle` from +z towards +x.
Vec3 in_plane(double angle) {
  return {std::sin(angle), 0.0, std::cos(angle)};
}

std::vector<MethodSettings> every_method(double s) {
  std::vector<MethodSettings> out;
  for (const MethodInfo& m : all_methods()) out.push_back({m.method, s});
  return out;
}

// Every method's factor for `v` is finite and in [0,1].
void expect_valid_factors(const ShadingVectors& v, double s) {
  for (const MethodSettings& m : every_method(s)) {
    const double g = terminator_factor(m, v);
    ASSERT_TRUE(std::isfinite(g) && g >= 0.0 && g <= 1.0)
        << method_info(m.method).id << " gave " << g;
  }
}

TEST(Terminator, EveryFactorIsFiniteAndInUnitIntervalForRandomInputs) {
  Pcg32 rng(1);
  for (int i = 0; i < 1'000'000; ++i) {
    const ShadingVectors v{random_unit(rng), random_unit(rng), random_unit(rng), random_unit(rng)};
    expect_valid_factors(v, rng.next_double());
    if (HasFatalFailure()) return;
  }
}

TEST(Terminator, EveryFactorIsFiniteAndInUnitIntervalForDegenerateInputs) {
  const Vec3 z{0, 0, 1};
  const double tiny = 1e-12;
  const std::vector<ShadingVectors> cases = {
      {z, z, {1, 0, 0}, z},                                 // light at the terminator, dot = 0
      {z, z, z, z},                                         // Ns == Ng == wi == wo
      {z, in_plane(0.3), {1, 0, 0}, z},                     // dot(Ng, wi) = 0 with deviation
      {z, {1, 0, 0}, in_plane(0.5), z},                     // Ns on the horizon
      {z, in_plane(2.0), in_plane(0.5), z},                 // Ns below the horizon
      {z, -z, z, z},                                        // Ns opposite Ng
      {z, in_plane(0.4), in_plane(-2.0), z},                // light below the horizon
      {z, in_plane(tiny), in_plane(tiny), in_plane(tiny)},  // nearly parallel
      {z, in_plane(0.5), in_plane(0.5 + tiny), z},          // Ns nearly along wi
      {z, in_plane(0.5), in_plane(kPi / 2 - tiny), z},      // just before the terminator
      {z, in_plane(0.5), in_plane(kPi / 2 + tiny), z},      // just after it
      {z, in_plane(0.5), in_plane(0.4), {0, 0, -1}},        // viewer below
  };
  for (const ShadingVectors& v : cases)
    for (double s : {0.0, 0.5, 1.0}) expect_valid_factors(v, s);
}

// Without deviation the factors leave the light alone: exactly 1 wherever
// the light reaches the surface. Two methods do not, by their definition;
// their documented exceptions are checked instead of skipped.
TEST(Terminator, FactorIsOneWithoutDeviation) {
  Pcg32 rng(2);
  for (int i = 0; i < 100'000; ++i) {
    const Vec3 n = random_unit(rng);
    Vec3 wi = random_unit(rng);
    if (dot(wi, n) < 0.0) wi = -wi;
    if (dot(wi, n) <= 0.0) continue;
    const ShadingVectors v{n, n, wi, n};
    for (const MethodInfo& info : all_methods()) {
      const double g = terminator_factor({info.method, 0.0}, v);
      if (info.method == TerminatorMethod::kDeshmukh2020) {
        // Smoothstep over <Ng,wi> in [0, 0.01999]: identity only above it.
        if (dot(n, wi) >= 0.01999 * (1.0 + 1e-12)) {
          EXPECT_EQ(g, 1.0);
        } else {
          EXPECT_LT(g, 1.0);
        }
        continue;
      }
      // |n|^2 differs from 1 by rounding, so estevez2019 may see alpha^2 of
      // ~1e-16, which its tan^2(theta_i) amplifies towards the terminator.
      const double tan2_i = (1.0 - dot(n, wi) * dot(n, wi)) / (dot(n, wi) * dot(n, wi));
      EXPECT_NEAR(g, 1.0, 1e-15 * (1.0 + tan2_i)) << info.id;  // shading-offset s = 0 included
      if (dot(n, n) == 1.0) {
        EXPECT_EQ(g, 1.0) << info.id;
      }
    }
  }
  // shading-offset with s > 0 darkens unbumped surfaces too (Cycles' design).
  EXPECT_LT(shading_offset(0.5, {0, 0, 1}, in_plane(1.0)), 1.0);
  EXPECT_EQ(shading_offset(0.5, {0, 0, 1}, {0, 0, 1}), 1.0);
}

TEST(Chiang2019, IsOneWhenTheLightIsOnTheGeometricSideOfNs) {
  const Vec3 ng{0, 0, 1};
  for (double deviation = 0.05; deviation < 1.5; deviation += 0.05)
    for (double light = 0.0; light <= deviation; light += 0.01)
      EXPECT_EQ(chiang2019(ng, in_plane(deviation), in_plane(light)), 1.0)
          << deviation << " " << light;
  // In general: G = 1 exactly when <Ng,wi> >= <Ns,wi><Ng,Ns>.
  Pcg32 rng(3);
  for (int i = 0; i < 100'000; ++i) {
    Vec3 ns = random_unit(rng), wi = random_unit(rng);
    if (ns.z < 0) ns = -ns;
    if (wi.z <= 0 || dot(ns, wi) <= 0) continue;
    if (wi.z >= dot(ns, wi) * ns.z) {
      EXPECT_EQ(chiang2019_raw_g(ng, ns, wi), 1.0);
    } else {
      EXPECT_LT(chiang2019_raw_g(ng, ns, wi), 1.0);
    }
  }
}

TEST(Chiang2019, IsZeroAtTheGeometricTerminator) {
  const Vec3 ng{0, 0, 1};
  for (double deviation : {0.0, 0.1, 0.5, 1.0, 1.4}) {
    EXPECT_EQ(chiang2019(ng, in_plane(deviation), {1, 0, 0}), 0.0);
    EXPECT_EQ(chiang2019(ng, in_plane(deviation), in_plane(kPi / 2 + 0.1)), 0.0);
    // and, with a deviation, approaches 0 continuously from the lit side:
    // G ~ <Ng,wi> / (sin(d) cos(d)) there.
    if (deviation > 0.0) {
      EXPECT_LT(chiang2019(ng, in_plane(deviation), in_plane(kPi / 2 - 1e-6)),
                2e-6 / (std::sin(deviation) * std::cos(deviation)));
    }
  }
}

// Eq. (2) exists to remove the C1 discontinuity of eq. (1) where G reaches 1.
// Along the light angle, the one-sided derivatives at that point agree for
// G' (both ~0) but not for the raw G, which shows the check can fail.
TEST(Chiang2019, IsC1ContinuousWhereGReachesOne) {
  const Vec3 ng{0, 0, 1};
  for (double deviation : {0.2, 0.5, 0.9}) {
    const Vec3 ns = in_plane(deviation);
    // Find the light angle where the raw G leaves 1 (bisection on eq. (1)).
    double lo = deviation, hi = kPi / 2;
    for (int k = 0; k < 200; ++k) {
      const double mid = 0.5 * (lo + hi);
      (chiang2019_raw_g(ng, ns, in_plane(mid)) >= 1.0 ? lo : hi) = mid;
    }
    const double at = 0.5 * (lo + hi), h = 1e-5;
    auto slope = [&](auto f, double a, double b) { return (f(b) - f(a)) / (b - a); };
    auto smooth = [&](double t) { return chiang2019(ng, ns, in_plane(t)); };
    auto raw = [&](double t) { return chiang2019_raw_g(ng, ns, in_plane(t)); };
    const double left = slope(smooth, at - 2 * h, at - h),
                 right = slope(smooth, at + h, at + 2 * h);
    EXPECT_NEAR(left, right, 1e-3) << deviation;
    const double raw_left = slope(raw, at - 2 * h, at - h),
                 raw_right = slope(raw, at + h, at + 2 * h);
    EXPECT_GT(std::abs(raw_left - raw_right), 0.05) << deviation;
  }
}

// Listing 12-1 of Ray Tracing Gems ch. 12, transcribed in float as printed.
float listing_bump_alpha2(const float n[3], const float nb[3]) {
  const float d = n[0] * nb[0] + n[1] * nb[1] + n[2] * nb[2];
  const float cos_d = std::min(std::fabs(d), 1.0f);
  const float tan2_d = (1 - cos_d * cos_d) / (cos_d * cos_d);
  return std::clamp(0.125f * tan2_d, 0.0f, 1.0f);
}
float listing_bump_shadowing_function(const float n[3], const float ld[3], float alpha2) {
  const float d = n[0] * ld[0] + n[1] * ld[1] + n[2] * ld[2];
  const float cos_i = std::max(std::fabs(d), 1e-6f);
  const float tan2_i = (1 - cos_i * cos_i) / (cos_i * cos_i);
  return 2.0f / (1 + std::sqrt(1 + alpha2 * tan2_i));
}

TEST(Estevez2019, MatchesListing12_1) {
  Pcg32 rng(4);
  int compared = 0;
  for (int i = 0; i < 10'000; ++i) {
    const Vec3 ng = random_unit(rng), ns = random_unit(rng), wi = random_unit(rng);
    // Away from |dot| ~ 0, where float and double legitimately part ways.
    if (std::abs(dot(ng, ns)) < 0.05 || std::abs(dot(ng, wi)) < 0.05) continue;
    const float n[3] = {float(ng.x), float(ng.y), float(ng.z)};
    const float nb[3] = {float(ns.x), float(ns.y), float(ns.z)};
    const float ld[3] = {float(wi.x), float(wi.y), float(wi.z)};
    const float expected = listing_bump_shadowing_function(n, ld, listing_bump_alpha2(n, nb));
    EXPECT_NEAR(estevez2019(ng, ns, wi), expected, 2e-5);
    ++compared;
  }
  EXPECT_GT(compared, 5000);
}

TEST(Estevez2019, ReciprocalVariantAppliesTheSameG1ToTheViewer) {
  const Vec3 ng{0, 0, 1}, ns = in_plane(0.6), wi = in_plane(1.2), wo = in_plane(-1.3);
  const double a2 = estevez2019_alpha2(ng, ns);
  EXPECT_DOUBLE_EQ(terminator_factor({TerminatorMethod::kEstevez2019Reciprocal}, {ng, ns, wi, wo}),
                   estevez2019_g1(ng, wi, a2) * estevez2019_g1(ng, wo, a2));
  // It darkens silhouettes (grazing wo) where the plain variant does not.
  EXPECT_LT(terminator_factor({TerminatorMethod::kEstevez2019Reciprocal},
                              {ng, ns, in_plane(0.2), in_plane(1.5)}),
            0.8 * terminator_factor({TerminatorMethod::kEstevez2019},
                                    {ng, ns, in_plane(0.2), in_plane(1.5)}));
}

// RTG Fig. 12-5: the GGX slope distribution truncated at radius 4 alpha keeps
// 94.1 % of its mass, and its truncated mean of tan^2 is 2.01 alpha^2.
// Computed by quadrature of the slope density that the project's ggx_d
// implies (P22(slope) = D(m) cos^4 theta_m, tan theta_m = |slope|), so a
// wrong D fails the paper's numbers.
TEST(Estevez2019, Figure12_5TruncatedGgxVarianceClaim) {
  for (double alpha : {0.1, 0.5, 1.0}) {
    auto p22 = [&](double r) {
      const double cos_theta_m = 1.0 / std::sqrt(1.0 + r * r);
      return ggx_d(cos_theta_m, alpha) * std::pow(cos_theta_m, 4);
    };
    // Simpson's rule over the radius; the angular integral is 2 pi r.
    const int n = 200'000;
    const double r_max = 4.0 * alpha, h = r_max / n;
    double mass = 0.0, moment = 0.0;
    for (int k = 0; k <= n; ++k) {
      const double r = k * h, w = (k == 0 || k == n) ? 1.0 : (k % 2 ? 4.0 : 2.0);
      mass += w * 2.0 * kPi * r * p22(r);
      moment += w * 2.0 * kPi * r * r * r * p22(r);
    }
    mass *= h / 3.0;
    moment *= h / 3.0;
    EXPECT_NEAR(mass, 0.941, 0.0005) << alpha;
    EXPECT_NEAR(moment / mass / (alpha * alpha), 2.01, 0.005) << alpha;
  }
  // Estevez's alpha mapping follows: tan(theta_d) = 2 sigma, sigma^2 = 2 alpha^2.
  const Vec3 ng{0, 0, 1};
  const double theta_d = 0.4;
  EXPECT_NEAR(estevez2019_alpha2(ng, in_plane(theta_d)), std::pow(std::tan(theta_d) / 2.0, 2) / 2.0,
              1e-12);
}

// Chiang et al., Fig. 5 (reference sheet, section 8), on a grid of light
// angle theta_i from Ng and deviation theta_d of Ns towards the light.
TEST(Figure5, RelationsBetweenChiangAndEstevez) {
  const Vec3 ng{0, 0, 1};
  auto both = [&](double theta_i_deg, double theta_d_deg) {
    const Vec3 ns = in_plane(radians(theta_d_deg)), wi = in_plane(radians(theta_i_deg));
    return std::pair{chiang2019(ng, ns, wi), estevez2019(ng, ns, wi)};
  };
  for (int ti = 0; ti <= 89; ++ti) {
    const auto [c, e] = both(ti, 0);
    EXPECT_EQ(c, 1.0);  // no deviation, no attenuation
    EXPECT_EQ(e, 1.0);
  }
  for (int td = 1; td <= 85; ++td)
    for (int ti = 1; ti < td; ++ti) {  // Ns tilted past the light
      const auto [c, e] = both(ti, td);
      EXPECT_EQ(c, 1.0) << ti << " " << td;
      EXPECT_LT(e, 1.0) << ti << " " << td;
    }
  for (int td = 5; td <= 30; ++td)  // small deviations: Estevez shadows less
    for (int ti = td + 10; ti <= 85; ++ti) {
      const auto [c, e] = both(ti, td);
      EXPECT_GE(e, c) << ti << " " << td;
    }
  for (int td = 60; td <= 85; ++td)  // large deviations: Estevez shadows more
    for (int ti = 20; ti <= 80; ++ti) {
      const auto [c, e] = both(ti, td);
      EXPECT_LT(e, c) << ti << " " << td;
    }
}

TEST(Methods, TableIsCompleteAndIdsRoundTrip) {
  EXPECT_EQ(all_methods().size(), 24u);
  for (const MethodInfo& info : all_methods()) {
    EXPECT_EQ(method_from_id(info.id), info.method);
    EXPECT_EQ(&method_info(info.method), &info);
  }
  EXPECT_FALSE(method_from_id("chiang"));
}

TEST(ShadingOffset, MatchesCyclesFrequencyMapping) {
  EXPECT_DOUBLE_EQ(shading_offset_frequency(0.0), 1.0);
  EXPECT_DOUBLE_EQ(shading_offset_frequency(1.0), 2.0);
  // cos(theta) becomes max(cos(f theta), 0): at theta = 60 deg and s = 1,
  // cos(120 deg) < 0, so the light is gone.
  EXPECT_EQ(shading_offset(1.0, {0, 0, 1}, in_plane(radians(60))), 0.0);
  const double theta = radians(30), f = shading_offset_frequency(0.5);
  EXPECT_NEAR(shading_offset(0.5, {0, 0, 1}, in_plane(theta)),
              std::cos(f * theta) / std::cos(theta), 1e-12);
}

// The list forms the fit's probes use are the single-value forms: the
// shading offset to the bit at every s (its cut at pi/2 included), the
// exponents at the published 2 to the bit of the published factors (x * x,
// which glibc's pow(x, 2) misses by an ulp at times). Elsewhere a value is
// a pow (1 ulp) squared up to four times, each squaring doubling the
// relative error and adding half an ulp: under 32 ulp, and 33 against pow's
// own, 3.7e-15 relative; Brinck's factor adds 2 V^q - 1 to the cosine, so
// its error is absolute, under 2 x that.
TEST(MicroShadowing, ListFormsAreTheSingleValueForms) {
  std::vector<double> s, e;
  for (int k = 0; k <= 40; ++k) s.push_back(k / 40.0);
  for (int k = 0; k <= 20; ++k) e.push_back(std::exp2(k / 4.0));
  std::vector<double> out(s.size());
  Pcg32 rng(7);
  for (int i = 0; i < 20000; ++i) {
    const Vec3 ns = random_unit(rng), wi = random_unit(rng);
    shading_offsets(s, ns, wi, out.data());
    for (std::size_t k = 0; k < s.size(); ++k)
      ASSERT_EQ(out[k], shading_offset(s[k], ns, wi)) << s[k] << " " << dot(ns, wi);
    const double cos_theta = dot(ns, wi), v = rng.next_double();
    for (const bool chan : {true, false}) {
      if (chan)
        microshadow_chan2018_exponents(cos_theta, v, e, out.data());
      else
        microshadow_brinck2016_exponents(cos_theta, v, e, out.data());
      for (std::size_t k = 0; k < e.size(); ++k) {
        const double single = chan ? microshadow_chan2018(cos_theta, v, e[k])
                                   : microshadow_brinck2016(cos_theta, v, e[k]);
        if (e[k] == 2.0) {
          ASSERT_EQ(out[k], chan ? microshadow_chan2018(cos_theta, v)
                                 : microshadow_brinck2016(cos_theta, v))
              << chan << " " << cos_theta << " " << v;
        }
        ASSERT_NEAR(out[k], single, chan ? 4e-15 * single : 8e-15) << chan << " " << e[k];
      }
    }
  }
}

}  // namespace
}  // namespace penumbra

namespace penumbra {
namespace {

// Filament's computeMicroShadowing (credited to Chan 2018) and Unity SRP
// Core's ComputeMicroShadowing (credited to Brinck & Maximov 2016),
// transcribed here: aperture = inversesqrt(1 - ao), saturate(NoL *
// aperture)^2; saturate(NoL + 2 ao^2 - 1).
TEST(MicroShadowing, MatchesTheShaderSources) {
  for (double ao : {0.0, 0.3, 0.75, 0.99})
    for (double nol : {0.0, 0.05, 0.25, 0.6, 1.0}) {
      const double aperture = 1.0 / std::sqrt(1.0 - ao);
      const double filament = std::pow(std::clamp(nol * aperture, 0.0, 1.0), 2.0);
      EXPECT_NEAR(microshadow_chan2018(nol, ao), filament, 1e-15) << ao << " " << nol;
      const double unity = std::clamp(nol + 2.0 * ao * ao - 1.0, 0.0, 1.0);
      EXPECT_NEAR(microshadow_brinck2016(nol, ao), unity, 1e-15) << ao << " " << nol;
    }
  // Unoccluded: no micro-shadowing wherever the light reaches the surface.
  EXPECT_EQ(microshadow_chan2018(0.01, 1.0), 1.0);
  EXPECT_EQ(microshadow_brinck2016(0.01, 1.0), 1.0);
}

// The forms `penumbra fit` refits (study/fit_probes.h): at the published
// exponent 2 they are the published factors to the bit; both keep the
// published ends (no occlusion at V = 1, all of it at V = 0, for Brinck;
// Chan's cut at cos = sqrt(1 - V) is sharper as p grows); and Chan's factor
// falls as p grows where it lies below 1.
TEST(MicroShadowing, FreeExponentsKeepThePublishedFactorsAtTwo) {
  for (double ao = 0.0; ao <= 1.0; ao += 1.0 / 64.0)
    for (double nol = -0.1; nol <= 1.0; nol += 1.0 / 128.0) {
      EXPECT_EQ(microshadow_chan2018(nol, ao, 2.0), microshadow_chan2018(nol, ao)) << ao << nol;
      EXPECT_EQ(microshadow_brinck2016(nol, ao, 2.0), microshadow_brinck2016(nol, ao)) << ao << nol;
      const double low = microshadow_chan2018(nol, ao, 1.0),
                   high = microshadow_chan2018(nol, ao, 8.0);
      EXPECT_LE(high, low) << ao << " " << nol;
      for (double q : {0.5, 4.0}) {
        EXPECT_NEAR(microshadow_brinck2016(nol, 1.0, q), std::clamp(nol + 1.0, 0.0, 1.0), 1e-15);
        EXPECT_NEAR(microshadow_brinck2016(nol, 0.0, q), std::clamp(nol - 1.0, 0.0, 1.0), 1e-15);
      }
    }
}

}  // namespace
}  // namespace penumbra
