// The GGX specular lobe and the diffuse lobe of core/bsdf: properties any
// correct microfacet BSDF has, checked by quadrature over the sphere.
#include <gtest/gtest.h>

#include <cmath>

#include "core/bsdf.h"
#include "core/vec.h"

namespace penumbra {
namespace {

Vec3 direction(double theta, double phi) {
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

// Midpoint rule over the hemisphere in (cos theta, phi): exact measure dw.
template <typename F>
double hemisphere_integral(F f, int n_mu = 2000, int n_phi = 64) {
  double sum = 0.0;
  for (int i = 0; i < n_mu; ++i) {
    const double mu = (i + 0.5) / n_mu;
    for (int j = 0; j < n_phi; ++j) {
      const double phi = 2.0 * kPi * (j + 0.5) / n_phi;
      sum += f(direction(std::acos(mu), phi));
    }
  }
  return sum * (1.0 / n_mu) * (2.0 * kPi / n_phi);
}

// D is a distribution of microfacet normals: its projected area is 1.
TEST(Ggx, DistributionProjectsToUnitArea) {
  for (double alpha : {0.1, 0.3, 0.7, 1.0}) {
    // Substituting mu = cos theta_m puts D's peak at mu = 1; a fine grid
    // there resolves alpha = 0.1 (its width in mu is about alpha^2 / 2).
    const double area =
        hemisphere_integral([&](const Vec3& m) { return ggx_d(m.z, alpha) * m.z; }, 200000, 1);
    EXPECT_NEAR(area, 1.0, 2e-3) << alpha;
  }
}

TEST(Ggx, MaskingIsOneAtNormalIncidenceSymmetricAndBounded) {
  for (double alpha : {0.1, 0.5, 1.0}) {
    EXPECT_NEAR(ggx_g2(1.0, 1.0, alpha), 1.0, 1e-12);
    for (double a : {0.05, 0.3, 0.7, 1.0})
      for (double b : {0.1, 0.5, 0.9}) {
        const double g = ggx_g2(a, b, alpha);
        EXPECT_GE(g, 0.0);
        EXPECT_LE(g, 1.0);
        EXPECT_DOUBLE_EQ(g, ggx_g2(b, a, alpha));
      }
    // Rougher surfaces mask more at grazing angles.
    EXPECT_LT(ggx_g2(0.1, 1.0, 1.0), ggx_g2(0.1, 1.0, 0.1));
  }
}

// Reciprocity, and a specular lobe that never creates energy (F = 1, so its
// directional albedo is 1 minus the multiple scattering it leaves out).
double specular_albedo(double alpha, double theta_o) {
  const Material m{0.8, 1.0, alpha, {}};
  const Vec3 n{0, 0, 1}, wo = direction(theta_o, 0.0);
  return hemisphere_integral(
      [&](const Vec3& wi) { return evaluate_lobes(m, n, wi, wo).specular * wi.z; }, 1000, 256);
}

TEST(Ggx, LobeIsReciprocalAndConservesEnergy) {
  const Vec3 n{0, 0, 1};
  for (double alpha : {0.2, 0.5, 1.0}) {
    const Material m{0.8, 1.0, alpha, {}};
    const Vec3 a = direction(0.4, 0.3), b = direction(1.1, 2.0);
    EXPECT_NEAR(evaluate_lobes(m, n, a, b).specular, evaluate_lobes(m, n, b, a).specular,
                1e-12 * evaluate_lobes(m, n, a, b).specular);
    for (double theta_o : {0.0, 0.6, 1.2}) EXPECT_LE(specular_albedo(alpha, theta_o), 1.0 + 5e-3);
  }
  // Rougher lobes lose more to the multiple scattering they leave out.
  EXPECT_GT(specular_albedo(0.2, 0.0), specular_albedo(0.5, 0.0));
  EXPECT_GT(specular_albedo(0.5, 0.0), specular_albedo(1.0, 0.0));
}

// At alpha = 1, D = 1/pi and, viewed along the normal, G2 = 2 mu/(1 + mu)
// (Lambda(mu) = (1/mu - 1)/2), so the albedo is (1/2) integral of
// 2 mu/(1 + mu) over mu in [0, 1] times 2 = 1 - ln 2: a closed form to check
// the whole lobe against (midpoint quadrature: error well under 1e-3).
TEST(Ggx, RoughestLobeAtNormalIncidenceHasAlbedoOneMinusLnTwo) {
  EXPECT_NEAR(specular_albedo(1.0, 0.0), 1.0 - std::log(2.0), 1e-3);
}

TEST(Lobes, DiffuseIsAlbedoOverPiScaledByTheSpecularWeightAndZeroBelow) {
  const Vec3 n{0, 0, 1}, wo = direction(0.3, 0.0);
  const Material m{0.8, 0.25, 0.3, {}};
  EXPECT_NEAR(evaluate_lobes(m, n, direction(0.7, 1.0), wo).diffuse, 0.8 * 0.75 / kPi, 1e-15);
  const LobeValues below = evaluate_lobes(m, n, direction(2.0, 1.0), wo);
  EXPECT_EQ(below.diffuse, 0.0);
  EXPECT_EQ(below.specular, 0.0);
}

}  // namespace
}  // namespace penumbra
