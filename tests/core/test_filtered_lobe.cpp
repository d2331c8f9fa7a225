// Anisotropic GGX and Beckmann lobes with a full alpha^2 tensor: against
// the isotropic GGX of bsdf.h, and the two integral identities every
// microfacet distribution and its Smith Lambda satisfy (Heitz 2014, eqs. 4
// and 7), by quadrature over the hemisphere.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "core/bsdf.h"
#include "core/filtered_lobe.h"

namespace penumbra {
namespace {

constexpr FilteredDistribution kBoth[] = {FilteredDistribution::kGgx,
                                          FilteredDistribution::kBeckmann};
// Anisotropic and rotated: eigenvalues 0.36 and 0.04 at 30 degrees.
const Covariance2 kTensor{0.36 * 0.75 + 0.04 * 0.25, (0.36 - 0.04) * 0.4330127018922193,
                          0.36 * 0.25 + 0.04 * 0.75};

// Integrates g(m) over the hemisphere: theta = atan(u), u in [0, 400] on a
// grid dense near 0, phi uniform.
template <typename G>
double hemisphere_integral(G g) {
  const int nu = 6000, nphi = 360;
  double sum = 0.0;
  for (int i = 0; i < nu; ++i) {
    const double x0 = double(i) / nu, x1 = double(i + 1) / nu;
    const double u0 = 400.0 * x0 * x0 * x0, u1 = 400.0 * x1 * x1 * x1;
    const double u = 0.5 * (u0 + u1), du = u1 - u0;
    const double cos_t = 1.0 / std::sqrt(1.0 + u * u), sin_t = u * cos_t;
    // d omega = sin theta d theta d phi, d theta = du / (1 + u^2)
    const double jacobian = sin_t * du / (1.0 + u * u);
    for (int j = 0; j < nphi; ++j) {
      const double phi = 2.0 * kPi * (j + 0.5) / nphi;
      sum += g(Vec3(sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t)) * jacobian *
             (2.0 * kPi / nphi);
    }
  }
  return sum;
}

TEST(FilteredLobe, IsotropicGgxIsTheMaterialsGgx) {
  for (double alpha : {0.05, 0.3, 0.8})
    for (double theta = 0.0; theta < 1.5; theta += 0.1) {
      const Vec3 m{std::sin(theta) * 0.6, std::sin(theta) * 0.8, std::cos(theta)};
      const Covariance2 a{alpha * alpha, 0.0, alpha * alpha};
      EXPECT_NEAR(lobe_d(FilteredDistribution::kGgx, a, m), ggx_d(m.z, alpha),
                  1e-12 * ggx_d(m.z, alpha));
      const Vec3 wo{0.0, std::sin(0.4), std::cos(0.4)};
      const double g2 = 1.0 / (1.0 + lobe_lambda(FilteredDistribution::kGgx, a, m) +
                               lobe_lambda(FilteredDistribution::kGgx, a, wo));
      EXPECT_NEAR(g2, ggx_g2(m.z, wo.z, alpha), 1e-12);
    }
}

// Heitz 2014 eq. 4: the projected microfacet area is the macro area.
TEST(FilteredLobe, DistributionsAreNormalised) {
  for (FilteredDistribution d : kBoth)
    EXPECT_NEAR(hemisphere_integral([&](const Vec3& m) { return lobe_d(d, kTensor, m) * m.z; }),
                1.0, 2e-3);
}

// Heitz 2014 eq. 7: the projected area towards w, (1 + Lambda(w)) cos theta,
// equals the integral of <w, m>+ D(m): Lambda with the projected roughness
// of the tensor is exact for these elliptical distributions.
TEST(FilteredLobe, LambdaGivesTheProjectedArea) {
  for (FilteredDistribution d : kBoth)
    for (double theta : {0.5, 1.0, 1.3})
      for (double phi : {0.0, 1.0, 2.5}) {
        const Vec3 w{std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                     std::cos(theta)};
        const double projected = hemisphere_integral(
            [&](const Vec3& m) { return std::max(dot(w, m), 0.0) * lobe_d(d, kTensor, m); });
        EXPECT_NEAR(projected, (1.0 + lobe_lambda(d, kTensor, w)) * w.z, 3e-3 * projected)
            << "theta " << theta << " phi " << phi;
      }
}

TEST(FilteredLobe, SchillingsBlinnPhongIsRefused) {
  EXPECT_THROW(lobe_brdf(FilteredDistribution::kSchillingBlinnPhong, kTensor, {0, 0, 1}, {0, 0, 1}),
               std::invalid_argument);
}

}  // namespace
}  // namespace penumbra
