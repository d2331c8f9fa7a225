// Area lights (sphere and quad) against closed forms the test computes on
// its own: Lambert's polygon formula checked by brute-force quadrature, a
// sphere's irradiance pi L sin^2 theta_max cos alpha, the point light a
// small sphere tends to; and the estimator's mean and variance.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include <fmt/format.h>

#include "analysis/metrics.h"
#include "core/environment.h"
#include "core/light_sampling.h"
#include "core/random.h"
#include "evaluator/evaluator.h"
#include "image/exr_file.h"
#include "image/image_io.h"
#include "scene/scene_json.h"
#include "small_sphere.h"
#include "temp_dir_test.h"
#include "util/strict_json.h"

namespace penumbra {
namespace {

// The quad light of these tests: to the left of and in front of the plane
// z = 0 (normal -z, towards the camera), facing it ((0.5, 0, -0.5) x
// (0, 1, 0) = (0.5, 0, 0.5)).
const char* const kQuad =
    R"(/light={"type": "quad", "corner": [-1.5, -0.5, -1.0], "edge_u": [0.5, 0, -0.5],
               "edge_v": [0, 1, 0], "radiance": 2})";
const char* const kSphere =
    R"(/light={"type": "sphere", "position": [-1.2, 0.5, -1.5], "radius": 0.4, "radiance": 3})";

// A /light=... setting with "sampling" added (evaluator.md: area and
// environment lights).
std::string sampled(const std::string& light, const char* sampling) {
  return light.substr(0, light.rfind('}')) + R"(, "sampling": ")" + sampling + "\"}";
}

// A smooth Lambertian 2 x 2 plane at z = 0 facing the camera, 40 x 40
// pixels at stratum centres (no jitter), so that the estimator's
// expectation is the mean of E over known points.
Scene plane_scene(const std::string& light, int spp) {
  return sphere_grating_with(
      {R"(/shape={"type": "plane", "axis": [0, 0, -1], "width": 2, "height": 2})",
       "/representation=smooth", "/camera/width=40", "/camera/height=40", "/camera/jitter=false",
       "/camera/spp=" + std::to_string(spp), light});
}

// Brute force: the irradiance at p (normal n) from a parallelogram of
// radiance L, summed over m x m midpoint cells: L cos_p cos_l dA / d^2.
double quad_irradiance_by_quadrature(const Light& q, const Vec3& p, const Vec3& n, int m) {
  const Vec3 normal_area = cross(q.edge_u, q.edge_v);
  const double area = length(normal_area);
  double sum = 0.0;
  for (int a = 0; a < m; ++a)
    for (int b = 0; b < m; ++b) {
      const Vec3 x = q.corner + q.edge_u * ((a + 0.5) / m) + q.edge_v * ((b + 0.5) / m);
      const Vec3 d = x - p;
      const double d2 = length_squared(d);
      const double cos_p = dot(n, d) / std::sqrt(d2);
      const double cos_l = -dot(normal_area, d) / (area * std::sqrt(d2));
      if (cos_p > 0.0 && cos_l > 0.0) sum += cos_p * cos_l / d2;
    }
  return q.radiance * sum * area / (double(m) * m);
}

TEST(AreaLight, PolygonIrradianceEqualsQuadrature) {
  const Light q = plane_scene(kQuad, 1).light;
  const Vec3 n{0, 0, -1};
  for (const Vec3 p : {Vec3{0, 0, 0}, Vec3{-0.9, 0.9, 0}, Vec3{0.9, -0.9, 0}}) {
    const Vec3 v[4] = {q.corner, q.corner + q.edge_u, q.corner + q.edge_u + q.edge_v,
                       q.corner + q.edge_v};
    const double closed = polygon_irradiance(v, 4, p, n, q.radiance);
    // Midpoint rule: error O(h^2) with h = 1/800 of the quad, over 1e-5.
    EXPECT_NEAR(closed, quad_irradiance_by_quadrature(q, p, n, 800), 1e-5 * closed);
    EXPECT_GT(closed, 0.0);
  }
}

// Irradiance at a point of the plane z = 0 (normal -z) from the test's lights.
double plane_irradiance(const Light& light, const Vec3& p) {
  const Vec3 n{0, 0, -1};
  if (light.type == LightType::kGroup) {
    double sum = 0.0;
    for (const Light& m : light.members) sum += plane_irradiance(m, p);
    return sum;
  }
  if (light.type == LightType::kSphere) {
    // A sphere wholly above the plane's horizon: pi L sin^2 theta_max cos alpha.
    const Vec3 d = light.position - p;
    return kPi * light.radiance * light.radius * light.radius / length_squared(d) *
           dot(n, normalize(d));
  }
  const Vec3 v[4] = {light.corner, light.corner + light.edge_u,
                     light.corner + light.edge_u + light.edge_v, light.corner + light.edge_v};
  return polygon_irradiance(v, 4, p, n, light.radiance);
}

// Per pixel wholly on the plane: (rendered - expected) / expected, where
// expected = albedo/pi times the mean of E over the pixel's stratum centres.
std::vector<double> relative_errors(const Scene& scene) {
  const Image image = render(scene);
  const Camera& c = scene.camera;
  int nx, ny;
  strata(c.spp, &nx, &ny);
  std::vector<double> errors;
  for (int j = 0; j < c.height; ++j)
    for (int i = 0; i < c.width; ++i) {
      double e = 0.0;
      bool inside = true;
      for (int sy = 0; sy < ny; ++sy)
        for (int sx = 0; sx < nx; ++sx) {
          const double x0 = (i + (sx + 0.5) / nx) / c.width - 0.5;
          const double y0 = 0.5 - (j + (sy + 0.5) / ny) / c.height;
          const Vec3 p{c.right.x * x0, c.up.y * y0, 0.0};
          inside = inside && std::abs(p.x) < 1.0 && std::abs(p.y) < 1.0;
          e += plane_irradiance(scene.light, p);
        }
      if (!inside) continue;
      const double expected = scene.material.albedo / kPi * e / (nx * ny);
      errors.push_back((image.at(i, j, 0) - expected) / expected);
    }
  return errors;
}

double mean(const std::vector<double>& x) {
  double s = 0.0;
  for (double v : x) s += v;
  return s / double(x.size());
}
double variance(const std::vector<double>& x) {
  const double m = mean(x);
  double s = 0.0;
  for (double v : x) s += (v - m) * (v - m);
  return s / double(x.size() - 1);
}

// Unbiased: the mean relative error over ~1000 pixels is zero within 4
// standard errors (and 0.2 %). Four times the samples cut the variance to
// at most 1/4 of it, as independent samples would (the strata do better),
// and to more than nothing (the estimator is not the closed form itself).
void expect_unbiased_and_converging(const std::string& light, double bound = 2e-3) {
  const std::vector<double> e16 = relative_errors(plane_scene(light, 16));
  const std::vector<double> e64 = relative_errors(plane_scene(light, 64));
  ASSERT_GT(e16.size(), 900u);
  for (const auto* e : {&e16, &e64}) {
    const double standard_error = std::sqrt(variance(*e) / double(e->size()));
    EXPECT_LT(std::abs(mean(*e)), 4.0 * standard_error + 1e-6) << light;
    EXPECT_LT(std::abs(mean(*e)), bound) << light;
  }
  const double ratio = variance(e64) / variance(e16);
  EXPECT_LT(ratio, 0.3) << light;  // 1/4, and the variance estimate's ~5 % at 1000 pixels
  EXPECT_GT(variance(e64), 1e-12) << light;
}

TEST(AreaLight, QuadOnAPlaneMatchesLambertsPolygonFormula) {
  expect_unbiased_and_converging(kQuad);
}

TEST(AreaLight, SphereOnAPlaneMatchesItsClosedForm) {
  expect_unbiased_and_converging(kSphere);
}

// Several lights in one scene: a group draws one light per camera sample
// by its weights and divides by the chance it drew it, so its expectation
// is the sum of its lights' closed forms; the same tolerances as one light.
// The weights are mostly the lights' irradiance at the shape's centre, with
// a tenth of the samples spread evenly (set_member_weights).
TEST(AreaLight, GroupOnAPlaneMatchesTheSumOfItsLightsClosedForms) {
  const std::string quad = std::string(kQuad).substr(7), sphere = std::string(kSphere).substr(7);
  const std::string group = R"(/light={"type": "group", "lights": [)" + quad + ", " + sphere + "]}";
  expect_unbiased_and_converging(group);
  const Light g = plane_scene(group, 1).light;
  ASSERT_EQ(g.members.size(), 2u);
  const Vec3 centre{0, 0, 0};
  const double wq = light_strength(g.members[0], centre), ws = light_strength(g.members[1], centre);
  EXPECT_NEAR(g.member_cdf[1], 0.9 * wq / (wq + ws) + 0.05, 1e-15);
  EXPECT_EQ(g.member_cdf[2], 1.0);
}

// Multiple importance sampling with cosine-weighted directions has the
// light sampler's expectation: the same closed forms, within 4 standard
// errors. Half its samples are cosine-weighted, and most of those miss the
// small sphere: its variance there is ~30 times the light sampler's
// (MisLowersTheVarianceOnlyWhereTheLightSamplerIsPoor), its standard error
// ~5 times, so the absolute bound is 5 times the light sampler's.
TEST(AreaLight, MisMatchesTheSameClosedForms) {
  expect_unbiased_and_converging(sampled(kQuad, "mis"));
  expect_unbiased_and_converging(sampled(kSphere, "mis"), 1e-2);
}

// The densities MIS weighs a direction by are the samplers' own: at a
// sampled direction, the same pdf and distance (to rounding); a direction
// that misses (away from the light, or just outside a sphere's cone) has
// none. Cosine-weighted directions integrate cos to its closed form.
TEST(AreaLight, DensitiesAtADirectionAreTheSamplersOwn) {
  const Light quad = plane_scene(kQuad, 1).light, sphere = plane_scene(kSphere, 1).light;
  for (const Vec3 p : {Vec3{0, 0, 0}, Vec3{-0.9, 0.9, 0}, Vec3{0.9, -0.9, 0.3}})
    for (int k = 0; k < 64; ++k) {
      const double u1 = (k % 8 + 0.37) / 8, u2 = (k / 8 + 0.61) / 8;
      const LightDirectionSample q =
          sample_quad_light(quad.corner, quad.edge_u, quad.edge_v, p, u1, u2);
      const LightDirectionSample qd =
          quad_light_pdf(quad.corner, quad.edge_u, quad.edge_v, p, q.wi);
      ASSERT_GT(q.pdf, 0.0);
      EXPECT_NEAR(qd.pdf, q.pdf, 1e-9 * q.pdf);
      EXPECT_NEAR(qd.distance, q.distance, 1e-9 * q.distance);
      EXPECT_EQ(quad_light_pdf(quad.corner, quad.edge_u, quad.edge_v, p, -q.wi).pdf, 0.0);
      const LightDirectionSample s = sample_sphere_light(sphere.position, sphere.radius, p, u1, u2);
      const LightDirectionSample sd = sphere_light_pdf(sphere.position, sphere.radius, p, s.wi);
      ASSERT_GT(s.pdf, 0.0);
      EXPECT_NEAR(sd.pdf, s.pdf, 1e-9 * s.pdf);
      EXPECT_NEAR(sd.distance, s.distance, 1e-9 * s.distance);
      EXPECT_EQ(sphere_light_pdf(sphere.position, sphere.radius, p, -s.wi).pdf, 0.0);
    }
  // Tangent to the sphere, then turned 1e-6 rad further out: a miss.
  const Vec3 p{0, 0, 0}, axis = normalize(sphere.position - p);
  const double sin_max = sphere.radius / length(sphere.position - p);
  const Frame f = Frame::from_z(axis);
  const double outside = std::asin(sin_max) + 1e-6, inside = std::asin(sin_max) - 1e-6;
  EXPECT_EQ(sphere_light_pdf(sphere.position, sphere.radius, p,
                             f.to_world({std::sin(outside), 0, std::cos(outside)}))
                .pdf,
            0.0);
  EXPECT_GT(sphere_light_pdf(sphere.position, sphere.radius, p,
                             f.to_world({std::sin(inside), 0, std::cos(inside)}))
                .pdf,
            0.0);
  // Over 256 x 256 strata: the mean of pi cos(n, w) is 2/3 pi (the integral
  // of cos^2 over the hemisphere), to the strata's O(1/N^2) ~ 1e-5.
  const Vec3 n = normalize(Vec3{0.3, -0.5, 0.8});
  double sum = 0.0;
  const int m = 256;
  for (int a = 0; a < m; ++a)
    for (int b = 0; b < m; ++b) {
      const Vec3 w = sample_cosine_direction(n, (a + 0.5) / m, (b + 0.5) / m);
      ASSERT_GE(dot(n, w), 0.0);
      EXPECT_NEAR(cosine_direction_pdf(n, w), dot(n, w) / kPi, 1e-15);
      sum += kPi * dot(n, w);
    }
  EXPECT_NEAR(sum / (m * m), 2.0 * kPi / 3.0, 1e-4);
}

// The spherical rectangle (Urena et al. 2013): its solid angle is the
// quadrature of cos theta_l / d^2 over the quad; every sampled direction
// hits the quad, with density 1 / solid angle there and the same at the
// lookup; the four corners of [0,1)^2 reach the quad's corners; a
// parallelogram and a rectangle too small to subtend kMinSphericalRectangle
// are sampled by area.
TEST(AreaLight, SphericalRectanglesAreSampledUniformlyInSolidAngle) {
  const Light quad = plane_scene(kQuad, 1).light;
  for (const Vec3 p : {Vec3{0, 0, 0}, Vec3{-0.9, 0.9, 0}, Vec3{0.9, -0.9, 0.3}}) {
    const Vec3 normal_area = cross(quad.edge_u, quad.edge_v);
    const double area = length(normal_area);
    double quadrature = 0.0;
    const int m = 800;
    for (int a = 0; a < m; ++a)
      for (int b = 0; b < m; ++b) {
        const Vec3 d =
            quad.corner + quad.edge_u * ((a + 0.5) / m) + quad.edge_v * ((b + 0.5) / m) - p;
        const double d2 = length_squared(d);
        quadrature += -dot(normal_area, d) / (area * std::sqrt(d2) * d2);
      }
    quadrature *= area / (double(m) * m);
    const double solid_angle = rectangle_solid_angle(quad.corner, quad.edge_u, quad.edge_v, p);
    EXPECT_NEAR(solid_angle, quadrature, 1e-5 * quadrature);
    for (int k = 0; k < 256; ++k) {
      const double u1 = (k % 16 + 0.29) / 16, u2 = (k / 16 + 0.83) / 16;
      const LightDirectionSample s =
          sample_rectangle_light(quad.corner, quad.edge_u, quad.edge_v, p, u1, u2);
      ASSERT_NEAR(s.pdf, 1.0 / solid_angle, 1e-12 / solid_angle);
      const LightDirectionSample at =
          rectangle_light_pdf(quad.corner, quad.edge_u, quad.edge_v, p, s.wi);
      EXPECT_NEAR(at.pdf, s.pdf, 1e-9 * s.pdf) << u1 << " " << u2;
      EXPECT_NEAR(at.distance, s.distance, 1e-9 * s.distance) << u1 << " " << u2;
    }
    const Vec3 corners[4] = {quad.corner, quad.corner + quad.edge_v, quad.corner + quad.edge_u,
                             quad.corner + quad.edge_u + quad.edge_v};
    for (int c = 0; c < 4; ++c) {
      const double u1 = c < 2 ? 0.0 : 1.0 - 1e-12, u2 = c % 2 == 0 ? 0.0 : 1.0 - 1e-12;
      const LightDirectionSample s =
          sample_rectangle_light(quad.corner, quad.edge_u, quad.edge_v, p, u1, u2);
      EXPECT_NEAR(length(p + s.wi * s.distance - corners[c]), 0.0, 1e-5) << c;
    }
  }
  const Vec3 p{0, 0, 0};
  const Vec3 slanted = quad.edge_v + quad.edge_u * 0.3;  // a parallelogram
  const LightDirectionSample by_area =
      sample_quad_light(quad.corner, quad.edge_u, slanted, p, 0.3, 0.6);
  const LightDirectionSample s =
      sample_rectangle_light(quad.corner, quad.edge_u, slanted, p, 0.3, 0.6);
  EXPECT_EQ(s.pdf, by_area.pdf);
  EXPECT_EQ(s.wi, by_area.wi);
  const Vec3 tiny_u = quad.edge_u * 1e-3, tiny_v = quad.edge_v * 1e-3;
  ASSERT_LT(rectangle_solid_angle(quad.corner, tiny_u, tiny_v, p), kMinSphericalRectangle);
  EXPECT_EQ(sample_rectangle_light(quad.corner, tiny_u, tiny_v, p, 0.3, 0.6).pdf,
            sample_quad_light(quad.corner, tiny_u, tiny_v, p, 0.3, 0.6).pdf);
  // Behind the emitting side: nothing.
  EXPECT_EQ(
      sample_rectangle_light(quad.corner, quad.edge_u, quad.edge_v, Vec3{-3, 0, -3}, 0.5, 0.5).pdf,
      0.0);
}

// Where MIS lowers the variance and where it raises it, at the same
// samples (and shadow rays) per pixel: a large parallelogram 0.3 above the
// plane, sampled by area (it is no rectangle), which gives the near points'
// 1/d^2 few samples, is where cosine-weighted directions help; a small,
// distant sphere (the plane tests' light), whose cone sampling is already
// nearly the integrand, is where they waste half the samples. The measured
// ratios are about 1/20 and 28; the test asks for 1/2 and 3/2, well outside
// the ~10 % a variance estimate over ~1000 pixels carries.
TEST(AreaLight, MisLowersTheVarianceOnlyWhereTheLightSamplerIsPoor) {
  const std::string close_quad =
      R"(/light={"type": "quad", "corner": [-1.5, -1.5, -0.3], "edge_u": [3, 0, 0],
                 "edge_v": [1, 3, 0], "radiance": 1})";
  const auto ratio = [](const std::string& light) {
    return variance(relative_errors(plane_scene(sampled(light, "mis"), 16))) /
           variance(relative_errors(plane_scene(sampled(light, "light"), 16)));
  };
  const double quad_ratio = ratio(close_quad), sphere_ratio = ratio(kSphere);
  std::printf(
      "[ mis      ] variance ratio MIS / light: close parallelogram %.3f, small sphere %.3f\n",
      quad_ratio, sphere_ratio);
  EXPECT_LT(quad_ratio, 0.5);
  EXPECT_GT(sphere_ratio, 1.5);
}

// A sphere of radius r and radiance I / (pi r^2) tends to a point light of
// intensity I: at r = 1e-3 and distance ~3.5, the irradiance differs by
// O(r^2/d^2) ~ 1e-7 where the whole sphere is above the horizon, and only
// a band ~r/d = 3e-4 rad wide round the terminator sees part of it.
TEST(AreaLight, SmallSphereTendsToThePointLight) {
  const double r = 1e-3, intensity = 10.0;
  const std::vector<std::string> common = {"/representation=smooth", "/camera/width=48",
                                           "/camera/height=48", "/camera/spp=4"};
  auto with = [&](const std::string& light) {
    std::vector<std::string> sets = common;
    sets.push_back("/light=" + light);
    return render(sphere_grating_with(sets));
  };
  const Image point = with(R"({"type": "point", "position": [-3, 1, -2], "intensity": )" +
                           std::to_string(intensity) + "}");
  const Image sphere =
      with(R"({"type": "sphere", "position": [-3, 1, -2], "radius": 0.001, "radiance": )" +
           std::to_string(intensity / (kPi * r * r)) + "}");
  double sum = 0.0, difference = 0.0;
  int lit = 0;
  for (int j = 0; j < 48; ++j)
    for (int i = 0; i < 48; ++i) {
      sum += point.at(i, j, 0);
      difference += std::abs(sphere.at(i, j, 0) - point.at(i, j, 0));
      lit += point.at(i, j, 0) > 0.0f;
    }
  ASSERT_GT(lit, 200);
  EXPECT_LT(difference, 1e-4 * sum);
}

// The ground truth traces its shadow rays to the sampled point of the
// light: with the height at 0 the displaced mesh is the sphere tessellated
// to edge 0.02, whose render differs from the smooth one by the facets'
// normals (relative ~edge^2/8 = 5e-5) and by rays near the silhouette.
TEST(AreaLight, DisplacedTruthWithoutHeightRendersTheSmoothSphere) {
  for (
      const char* light :
      {R"(/light={"type": "sphere", "position": [-3, 1, -2], "radius": 0.5, "power": 400})",
       R"(/light={"type": "quad", "corner": [-3, -1, -3], "edge_u": [0, 2, 0], "edge_v": [1, 0, 2], "radiance": 3})"}) {
    auto with = [&](const char* representation) {
      return render(sphere_grating_with({"/height/amplitude=0", "/displacement/edge_length=0.02",
                                         "/camera/width=40", "/camera/height=40", "/camera/spp=16",
                                         light, std::string("/representation=") + representation}));
    };
    const Image smooth = with("smooth"), truth = with("displacement");
    double sum = 0.0, difference = 0.0;
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 40; ++i) {
        sum += smooth.at(i, j, 0);
        difference += truth.at(i, j, 0) - smooth.at(i, j, 0);
      }
    ASSERT_GT(sum, 0.0) << light;
    EXPECT_LT(std::abs(difference), 0.01 * sum) << light;
  }
}

TEST(AreaLight, SameBitsWhateverTheThreadCount) {
  const Scene scene = sphere_grating_with({"/camera/width=32", "/camera/height=32", "/camera/spp=8",
                                           kQuad, "/terminator/method=\"estevez2019\""});
  std::vector<float> one, two;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = render(scene).pixels;
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = render(scene).pixels;
  }
  EXPECT_EQ(one, two);
}

// light_irradiance, which normalises the profile metrics, is the test's
// own closed form at the shape's centre (facing the light).
TEST(AreaLight, IrradianceForMetricsIsTheClosedForm) {
  const Light sphere = plane_scene(kSphere, 1).light;
  const Vec3 at{0.3, -0.2, 0};
  const double d2 = length_squared(sphere.position - at);
  EXPECT_NEAR(light_irradiance(sphere, at), kPi * sphere.radiance * 0.16 / d2, 1e-12);
  const Light quad = plane_scene(kQuad, 1).light;
  const Vec3 towards = normalize(light_axis(quad, at));
  EXPECT_NEAR(light_irradiance(quad, at), quad_irradiance_by_quadrature(quad, at, towards, 800),
              1e-5 * light_irradiance(quad, at));
  // Behind a one-sided quad: nothing.
  EXPECT_EQ(light_irradiance(quad, Vec3{-3, 0, -3}), 0.0);
}

TEST(AreaLight, PermutationIsABijection) {
  for (std::uint32_t n : {1u, 2u, 7u, 16u, 64u, 100u, 1000u})
    for (std::uint32_t seed : {0u, 1u, 0xdeadbeefu}) {
      std::vector<int> seen(n, 0);
      for (std::uint32_t i = 0; i < n; ++i) ++seen[permute_index(i, n, seed)];
      for (std::uint32_t k = 0; k < n; ++k) ASSERT_EQ(seen[k], 1) << n << " " << seed;
    }
}

// ---------------------------------------------------------------- environment

// A 32 x 16 map: a gradient from the zenith down, a bright 2 x 2 patch and
// a dim one, in R, G, B of different weights (the luminance is what lights).
Image test_map(bool uniform) {
  Image map;
  map.width = 32, map.height = 16;
  map.channels = {"R", "G", "B"};
  map.pixels.resize(std::size_t(map.width) * map.height * 3);
  for (int y = 0; y < map.height; ++y)
    for (int x = 0; x < map.width; ++x) {
      double l = 0.3 + 0.05 * (map.height - y);
      if (x >= 5 && x < 7 && y >= 4 && y < 6) l = 8.0;
      if (x >= 20 && x < 22 && y >= 9 && y < 11) l = 0.0;
      if (uniform) l = 1.0;
      // R, G, B whose Rec. 709 luminance is l.
      map.at(x, y, 0) = float(1.2 * l), map.at(x, y, 1) = float(l);
      map.at(x, y, 2) = float((l - 0.2126 * 1.2 * l - 0.7152 * l) / 0.0722);
    }
  return map;
}

// The test's own reading of the convention (scene-format.md, Cycles'
// direction_to_equirectangular): map coordinates (s, t) -> scene direction.
Vec3 map_direction(double s, double t, double rotation) {
  const double phi = (0.5 - s) * 2.0 * kPi, theta = (1.0 - t) * kPi;
  const Vec3 b{std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
  const double c = std::cos(-rotation), sn = std::sin(-rotation);
  const Vec3 turned{c * b.x - sn * b.y, sn * b.x + c * b.y, b.z};
  return {turned.x, turned.z, turned.y};
}

// Irradiance on normal n from the map, shadows aside: each texel split into
// 4 x 4 cells of equal solid angle (uniform in s and in cos theta).
double map_irradiance(const Image& map, const Vec3& n, double rotation, double scale) {
  double sum = 0.0;
  const int k = 4;
  for (int y = 0; y < map.height; ++y) {
    const double z0 = std::cos(kPi * y / map.height), z1 = std::cos(kPi * (y + 1) / map.height);
    const double cell = 2.0 * kPi / map.width * (z0 - z1) / (k * k);
    for (int x = 0; x < map.width; ++x) {
      const double l =
          0.2126 * map.at(x, y, 0) + 0.7152 * map.at(x, y, 1) + 0.0722 * map.at(x, y, 2);
      for (int a = 0; a < k; ++a)
        for (int b = 0; b < k; ++b) {
          const double s = (x + (a + 0.5) / k) / map.width;
          const double z = z0 + (z1 - z0) * (b + 0.5) / k;
          const double t = 1.0 - std::acos(z) / kPi;
          sum += l * std::max(0.0, dot(n, map_direction(s, t, rotation))) * cell;
        }
    }
  }
  return scale * sum;
}

class Environment : public TempDirTest {
 protected:
  std::string environment(const std::string& file, double rotation_deg, double scale) const {
    return fmt::format(R"(/light={{"type": "environment", "map": "{}", "rotation_deg": {},
                                   "scale": {}}})",
                       path(file), rotation_deg, scale);
  }
  // Per fully covered pixel of the smooth unit sphere (64 samples at the
  // strata's centres): (rendered - expected) / expected.
  std::vector<double> sphere_errors(const Image& map, const std::string& light, double rotation,
                                    double scale) const {
    const Scene scene =
        sphere_grating_with({"/representation=smooth", "/camera/width=40", "/camera/height=40",
                             "/camera/spp=64", "/camera/jitter=false", light});
    const Image image = render(scene);
    const Camera& c = scene.camera;
    std::vector<double> errors;
    for (int j = 0; j < c.height; ++j)
      for (int i = 0; i < c.width; ++i) {
        double e = 0.0;
        bool inside = true;
        for (int sy = 0; sy < 8; ++sy)
          for (int sx = 0; sx < 8; ++sx) {
            const double x = c.right.x * ((i + (sx + 0.5) / 8) / c.width - 0.5);
            const double y = c.up.y * (0.5 - (j + (sy + 0.5) / 8) / c.height);
            inside = inside && x * x + y * y < 0.95;
            if (!inside) break;
            const Vec3 n{x, y, -std::sqrt(1.0 - x * x - y * y)};
            e += map_irradiance(map, n, rotation, scale);
          }
        if (!inside) continue;
        const double expected = scene.material.albedo / kPi * e / 64.0;
        errors.push_back((image.at(i, j, 0) - expected) / expected);
      }
    return errors;
  }
};

// A smooth Lambertian sphere under the map is the map's cosine convolution
// (the sphere is convex: nothing but its own horizon shadows a point), to
// Monte Carlo error: the mean relative error over ~700 pixels within 4
// standard errors and 1 % (light sampling alone: a standard error of ~0.4 %
// at 64 samples, from pixels facing away from the bright patch). The rotation and the scale are
// those of the scene; a map turned by another angle is told apart.
TEST_F(Environment, SmoothSphereIsTheMapsCosineConvolution) {
  const Image map = test_map(false);
  write_exr(map, path("map.exr"));
  const double rotation = radians(30.0);
  for (const char* sampling : {"light", "mis"}) {
    const std::vector<double> e =
        sphere_errors(map, sampled(environment("map.exr", 30.0, 2.0), sampling), rotation, 2.0);
    ASSERT_GT(e.size(), 600u);
    const double standard_error = std::sqrt(variance(e) / double(e.size()));
    EXPECT_LT(std::abs(mean(e)), 4.0 * standard_error) << sampling;
    EXPECT_LT(std::abs(mean(e)), 1e-2) << sampling;
    std::printf("[ env      ] %s: mean relative error %.5f, standard error %.5f, %zu pixels\n",
                sampling, mean(e), standard_error, e.size());
  }
  // The same render against the map read 90 degrees further round: far off.
  const std::vector<double> wrong =
      sphere_errors(map, environment("map.exr", 30.0, 2.0), radians(120.0), 2.0);
  double worst = 0.0;
  for (double x : wrong) worst = std::max(worst, std::abs(x));
  EXPECT_GT(worst, 0.3);
}

// White furnace: under a uniform environment of radiance 1, a smooth
// Lambertian sphere reflects exactly its albedo (E = pi); with bumps, no
// method may reflect more (the base sphere's shadow ray only removes light;
// the factors are at most 1). Means over ~700 pixels, within 4 standard
// errors.
TEST_F(Environment, WhiteFurnaceGivesTheAlbedoAndNoMethodMore) {
  write_exr(test_map(true), path("white.exr"));
  const std::string light = environment("white.exr", 0.0, 1.0);
  auto pixels = [&](const std::vector<std::string>& sets) {
    std::vector<std::string> all = {"/camera/width=40", "/camera/height=40", "/camera/spp=16",
                                    light};
    all.insert(all.end(), sets.begin(), sets.end());
    const Image image = render(sphere_grating_with(all));
    std::vector<double> values;
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 40; ++i) {
        const double x = 2.5 * ((i + 0.5) / 40 - 0.5), y = 2.5 * (0.5 - (j + 0.5) / 40);
        if (x * x + y * y < 0.9) values.push_back(image.at(i, j, 0));
      }
    return values;
  };
  const std::vector<double> smooth = pixels({"/representation=smooth"});
  const double albedo = 0.8;
  EXPECT_NEAR(mean(smooth), albedo, 4.0 * std::sqrt(variance(smooth) / double(smooth.size())));
  // Under MIS, the same albedo; and a uniform map is where cosine-weighted
  // directions help: the map's sampler spends half its samples below the
  // horizon. Measured: about a quarter of the variance; asked: below 2/3.
  const std::vector<double> mis = pixels({"/representation=smooth", sampled(light, "mis")});
  EXPECT_NEAR(mean(mis), albedo, 4.0 * std::sqrt(variance(mis) / double(mis.size())));
  EXPECT_LT(variance(mis), 2.0 / 3.0 * variance(smooth));
  std::printf("[ furnace  ] variance ratio MIS / light %.3f\n", variance(mis) / variance(smooth));
  for (const char* method : {"none", "chiang2019", "estevez2019", "mitsuba3", "cycles45"}) {
    const std::vector<double> bump =
        pixels({"/height/amplitude=0.03", "/terminator/method=\"" + std::string(method) + "\""});
    EXPECT_LT(mean(bump), albedo + 4.0 * std::sqrt(variance(bump) / double(bump.size()))) << method;
  }
}

// The lookups (for later BSDF sampling and for the metrics' normalisation)
// invert the sampling: a sampled direction reads back its texel's radiance
// and density, and coordinates round-trip; the densities integrate to 1.
TEST(EnvironmentMap, LookupsInvertTheSampling) {
  const Image image = test_map(false);
  std::vector<float> radiance(std::size_t(image.width) * image.height);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      radiance[std::size_t(y) * image.width + x] = float(
          0.2126 * image.at(x, y, 0) + 0.7152 * image.at(x, y, 1) + 0.0722 * image.at(x, y, 2));
  const EnvironmentMap map(radiance, image.width, image.height, radians(-70.0));
  int mismatched = 0;
  double pdf_sum = 0.0;
  for (int k = 0; k < 20000; ++k) {
    double l = 0.0;
    const LightDirectionSample s = map.sample(splitmix_double(7, 2 * std::uint64_t(k)),
                                              splitmix_double(7, 2 * std::uint64_t(k) + 1), &l);
    ASSERT_GT(s.pdf, 0.0);
    ASSERT_NEAR(length(s.wi), 1.0, 1e-12);
    // A direction on a texel's edge may read the neighbour (rounding).
    if (std::abs(map.radiance(s.wi) - l) > 1e-6 || std::abs(map.pdf(s.wi) - s.pdf) > 1e-9 * s.pdf)
      ++mismatched;
    const MapCoordinates c = environment_coordinates(s.wi, map.rotation());
    EXPECT_NEAR(length(environment_direction(c, map.rotation()) - s.wi), 0.0, 1e-9);
  }
  EXPECT_LE(mismatched, 2);
  // sum over texels of pdf * dOmega = 1, through the lookup at their centres.
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      pdf_sum += map.pdf(environment_direction(
                     {(x + 0.5) / image.width, 1.0 - (y + 0.5) / image.height}, map.rotation())) *
                 map.texel_solid_angle(y);
  EXPECT_NEAR(pdf_sum, 1.0, 1e-9);
}

TEST_F(Environment, BadMapsAreRefusedWithFileAndPointer) {
  Image nan_map = test_map(false);
  nan_map.at(3, 2, 1) = std::numeric_limits<float>::quiet_NaN();
  write_exr_file(nan_map, path("nan.exr"), {});  // no finiteness check
  Image tiny;
  tiny.width = tiny.height = 1;
  tiny.channels = {"Y"};
  tiny.pixels = {1.0f};
  write_exr(tiny, path("tiny.exr"));
  write_png_rgb8(path("ldr.png"), 4, 2, std::vector<unsigned char>(4 * 2 * 3, 128));
  const std::vector<std::pair<std::string, std::string>> cases = {
      {environment("missing.exr", 0, 1), "missing.exr"},
      {environment("nan.exr", 0, 1), "radiance must be finite"},
      {environment("tiny.exr", 0, 1), "at least 2x2 texels"},
      {environment("ldr.png", 0, 1), "floating-point radiance"},
      {environment("nan.exr", 400, 1), "in [-360, 360]"},
      {R"(/light={"type": "environment", "map": "blender:no/such/file.exr"})",
       "Blender's data folder"},
  };
  for (const auto& [light, expected] : cases) {
    try {
      sphere_grating_with({light});
      ADD_FAILURE() << light << " was accepted";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("/light/"), std::string::npos) << what;
      EXPECT_NE(what.find(expected), std::string::npos) << what;
    }
  }
}

}  // namespace
}  // namespace penumbra
