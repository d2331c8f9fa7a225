// The light vector (scene.h, light_vector) that the terminator metric bins
// by under any lighting: each light type's against a brute-force integral
// the test computes on its own, and the analysis.theta channel it gives a
// render: the distant light's angle for a light that shrinks to a point,
// and a smooth sphere's cos(theta) profile under a large light.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "analysis/metrics.h"
#include "core/environment.h"
#include "evaluator/evaluator.h"
#include "scene/scene_json.h"
#include "small_sphere.h"

namespace penumbra {
namespace {

void expect_near_vector(const Vec3& got, const Vec3& expected, double tolerance) {
  EXPECT_LT(length(got - expected), tolerance * length(expected))
      << "got (" << got.x << ", " << got.y << ", " << got.z << "), expected (" << expected.x << ", "
      << expected.y << ", " << expected.z << ")";
}

// The integral of L w dw over the quad, as one over its area:
// L w cos_l dA / d^2, on m x m midpoint cells (error O(1/m^2)).
Vec3 quad_vector_by_quadrature(const Light& q, const Vec3& p, int m) {
  const Vec3 normal_area = cross(q.edge_u, q.edge_v);
  const double area = length(normal_area);
  Vec3 sum;
  for (int a = 0; a < m; ++a)
    for (int b = 0; b < m; ++b) {
      const Vec3 x = q.corner + q.edge_u * ((a + 0.5) / m) + q.edge_v * ((b + 0.5) / m);
      const Vec3 d = x - p;
      const double d2 = length_squared(d), dist = std::sqrt(d2);
      const double cos_l = -dot(normal_area, d) / (area * dist);
      if (cos_l > 0.0) sum += d * (cos_l / (d2 * dist));
    }
  return sum * (q.radiance * area / (double(m) * m));
}

TEST(LightVector, QuadEqualsQuadratureOverItsArea) {
  Light q;
  q.type = LightType::kQuad;
  q.corner = {-1.5, -0.5, -1.0};
  q.edge_u = {0.5, 0, -0.5};
  q.edge_v = {0, 1, 0};
  q.radiance = 2.0;
  for (const Vec3 p :
       {Vec3{0, 0, 0}, Vec3{-0.9, 0.9, 0}, Vec3{0.9, -0.9, 0.5}, Vec3{-1.4, 0, -0.8}})
    expect_near_vector(light_vector(q, p), quad_vector_by_quadrature(q, p, 600), 1e-5);
  // Behind its emitting side (edge_u x edge_v points to +x, +z): no light.
  EXPECT_EQ(length(light_vector(q, Vec3{-2, 0, -2})), 0.0);
}

// The integral over the sphere's surface seen from p: L w cos_l dA / d^2
// on an n x 2n midpoint grid in its polar and azimuthal angles.
Vec3 sphere_vector_by_quadrature(const Light& s, const Vec3& p, int n) {
  Vec3 sum;
  const double r = s.radius;
  for (int i = 0; i < n; ++i) {
    const double theta = kPi * (i + 0.5) / n;
    const double area = r * r * std::sin(theta) * (kPi / n) * (kPi / n);
    for (int j = 0; j < 2 * n; ++j) {
      const double phi = kPi * (j + 0.5) / n;
      const Vec3 normal{std::sin(theta) * std::cos(phi), std::cos(theta),
                        std::sin(theta) * std::sin(phi)};
      const Vec3 d = s.position + normal * r - p;
      const double d2 = length_squared(d), dist = std::sqrt(d2);
      const double cos_l = -dot(normal, d) / dist;
      if (cos_l > 0.0) sum += d * (cos_l * area / (d2 * dist));
    }
  }
  return sum * s.radiance;
}

TEST(LightVector, SphereEqualsQuadratureOverItsSurface) {
  Light s;
  s.type = LightType::kSphere;
  s.position = {-1.2, 0.5, -1.5};
  s.radius = 0.4;
  s.radiance = 3.0;
  for (const Vec3 p : {Vec3{0, 0, 0}, Vec3{-1.2, 0.5, -0.6}, Vec3{2, -1, 1}})
    expect_near_vector(light_vector(s, p), sphere_vector_by_quadrature(s, p, 800), 1e-4);
  EXPECT_EQ(length(light_vector(s, s.position + Vec3{0.1, 0, 0})), 0.0);  // inside it
}

// An environment's vector, the sum at its texels' centres, against the
// mean of L w / pdf over its own sampling (the integral of the piecewise-
// constant map, unbiased): they differ by the texels' curvature, O(texel^2)
// = 0.1 % at 64 x 32, and by the Monte Carlo error, under 0.1 % at
// 256 x 256 strata with sampling proportional to the radiance.
TEST(LightVector, EnvironmentEqualsTheMeanOfItsSampledDirections) {
  const int w = 64, h = 32;
  std::vector<float> texels(std::size_t(w) * h, 0.2f);
  for (int y = 6; y < 10; ++y)
    for (int x = 40; x < 46; ++x) texels[std::size_t(y) * w + x] = 50.0f;
  const EnvironmentMap map(texels, w, h, 0.7);
  Light e;
  e.type = LightType::kEnvironment;
  e.environment = std::make_shared<EnvironmentMap>(map);
  e.scale = 1.5;
  Vec3 sum;
  const int m = 256;
  for (int a = 0; a < m; ++a)
    for (int b = 0; b < m; ++b) {
      double radiance = 0.0;
      const LightDirectionSample s = map.sample((a + 0.5) / m, (b + 0.5) / m, &radiance);
      ASSERT_GT(s.pdf, 0.0);
      sum += s.wi * (radiance / s.pdf);
    }
  expect_near_vector(light_vector(e, Vec3{3, -2, 1}), sum * (e.scale / (double(m) * m)), 2e-3);
}

// The smooth unit sphere, 64 x 64 pixels at 16 samples, under a light.
Image smooth_sphere(const std::string& light) {
  return render(
      sphere_grating_with({"/representation=smooth", "/camera/width=64", "/camera/height=64",
                           "/camera/spp=16", "/camera/jitter=false", "/light=" + light}));
}

// A sphere light of radius 1 at distance 1000 along the distant light's
// direction is seen within 0.06 degrees of it from every point of the unit
// sphere (asin(1/1000) of parallax, 0.057 degrees of cone): analysis.theta
// must agree to that, on every fully covered pixel.
TEST(LightVector, AnalysisThetaOfASmallFarSphereIsTheDistantLightsAngle) {
  const Vec3 d = normalize(Vec3{-1, 0.3, -0.4});
  const Image sun =
      smooth_sphere(R"({"type": "distant", "direction": [)" + std::to_string(d.x) + "," +
                    std::to_string(d.y) + "," + std::to_string(d.z) + R"(], "irradiance": 1})");
  const Vec3 c = d * 1000.0;
  const Image sphere = smooth_sphere(
      R"({"type": "sphere", "radius": 1, "radiance": 1, "position": [)" + std::to_string(c.x) +
      "," + std::to_string(c.y) + "," + std::to_string(c.z) + "]}");
  const int a = 3, theta = 4;
  int covered = 0;
  double largest = 0.0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      if (sun.at(x, y, a) < 0.999f) continue;
      ++covered;
      largest = std::max(largest, double(std::abs(sphere.at(x, y, theta) - sun.at(x, y, theta))));
    }
  ASSERT_GT(covered, 1500);
  EXPECT_LT(largest, 0.12) << "degrees";
}

// The light vector depends on the base point alone, so with the camera's
// samples at their strata's centres analysis.theta is the same to the bit
// whatever light samples are drawn (another seed), while the radiance,
// which does depend on them, changes; a channel of the sampled directions'
// angles would change with it.
TEST(LightVector, AnalysisThetaIsFreeOfTheLightSamplesNoise) {
  const std::string quad =
      R"(/light={"type": "quad", "corner": [-3, -1, -2], "edge_u": [1, 0, -1.5],
                 "edge_v": [0, 2, 0], "radiance": 5})";
  auto with_seed = [&](int seed) {
    return render(sphere_grating_with({"/representation=smooth", "/camera/width=32",
                                       "/camera/height=32", "/camera/spp=4", "/camera/jitter=false",
                                       quad, "/camera/seed=" + std::to_string(seed)}));
  };
  const Image a = with_seed(1), b = with_seed(2);
  const int alpha = 3, theta = 4;
  int covered = 0, same_theta = 0, same_radiance = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      if (a.at(x, y, alpha) < 0.999f) continue;
      ++covered;
      same_theta += a.at(x, y, theta) == b.at(x, y, theta);
      same_radiance += a.at(x, y, 0) == b.at(x, y, 0);
    }
  ASSERT_GT(covered, 300);
  EXPECT_EQ(same_theta, covered);
  EXPECT_LT(same_radiance, covered / 2);  // the seed does change the light samples
}

// Under a sphere light of half-angle 30 degrees (radius 500 at 1000) the
// smooth sphere's radiance is albedo/pi times pi L sin^2(30) cos(theta_L)
// wherever the whole light is above the horizon (theta_L < 60 degrees), so
// its profile binned by the light vector's angle is cos(theta_L) there, to
// the Monte Carlo error of 16 cone samples averaged over each bin's pixels
// and the 0.2 % that the light's distance varies across the unit sphere;
// beyond 90 degrees the light still reaches it (the base shape's own
// penumbra: 0.03 of the facing radiance at 100 degrees), which a profile
// binned by the sun's angle could not hold, and none from 120 on.
TEST(LightVector, SmoothSphereProfileUnderALargeLightIsCosThetaWhereItSeesAllOfIt) {
  const Image image = smooth_sphere(
      R"({"type": "sphere", "position": [-800, 0, -600], "radius": 500, "radiance": 1})");
  const double scale = 0.8 * kPi * 0.25 / kPi;  // albedo * pi L sin^2 / pi
  const Profile p = terminator_profile(image, scale, {5.0});
  int checked = 0;
  for (std::size_t k = 0; k < p.value.size(); ++k) {
    if (p.count[k] < 20 || p.centre(k) > 55.0) continue;
    ++checked;
    EXPECT_NEAR(p.value[k], std::cos(p.centre(k) * kPi / 180.0), 0.01) << "bin " << p.centre(k);
  }
  EXPECT_GE(checked, 6);
  const std::size_t k100 = 20;  // [100, 105) degrees
  ASSERT_GT(p.count[k100], 20u);
  EXPECT_GT(p.value[k100], 0.02);
  // From 90 + 30 degrees on, the whole light is below the horizon.
  for (std::size_t k = 24; k < p.value.size(); ++k)
    EXPECT_EQ(p.value[k], 0.0) << "bin " << p.centre(k);
}

}  // namespace
}  // namespace penumbra
