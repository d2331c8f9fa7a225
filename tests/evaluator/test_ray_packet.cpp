// The camera-ray packets (core/ray_packet.h) against the scalar functions
// they stand in for, lane by lane and bit for bit, and the evaluator's
// packet path against its scalar path, image for image.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <hwy/targets.h>

#include "analysis/metrics.h"
#include "core/random.h"
#include "core/ray_packet.h"
#include "evaluator/embree_rounding.h"
#include "evaluator/evaluator.h"
#include "scene/scene_json.h"

namespace penumbra {
namespace {

const std::string kScenes = std::string(PENUMBRA_SOURCE_DIR) + "/scenes";

Scene scene_with(const std::string& file, const std::vector<std::string>& sets) {
  std::vector<Override> overrides;
  for (const std::string& s : sets) overrides.push_back(parse_override(s));
  return load_scene(kScenes + "/" + file, overrides);
}

// Same bits, -0 and +0 told apart.
void expect_bits(double packet, double scalar, const std::string& what) {
  EXPECT_EQ(std::bit_cast<std::uint64_t>(packet), std::bit_cast<std::uint64_t>(scalar))
      << what << ": packet " << packet << ", scalar " << scalar;
}
void expect_bits(const Vec3& packet, const Vec3& scalar, const std::string& what) {
  expect_bits(packet.x, scalar.x, what + ".x");
  expect_bits(packet.y, scalar.y, what + ".y");
  expect_bits(packet.z, scalar.z, what + ".z");
}

// Rays that hit from outside, from inside, graze the silhouette, run along
// the axis, start on the surface or miss: uniform origins in a box around
// the shape and uniform directions, plus rays aimed at surface points.
std::vector<Ray> test_rays(const Shape& shape, std::size_t count, std::uint64_t seed) {
  Pcg32 rng(seed);
  const auto uniform = [&](double a, double b) { return a + (b - a) * rng.next_double(); };
  std::vector<Ray> rays;
  while (rays.size() < count) {
    const double extent = 2.5 * shape.radius;
    const Vec3 origin = shape.center + Vec3{uniform(-extent, extent), uniform(-extent, extent),
                                            uniform(-extent, extent)};
    Vec3 direction{uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)};
    switch (rays.size() % 4) {
      case 0:
        break;
      case 1:  // at a point of the surface
        direction = surface_at(shape, uniform(0, 6.28), uniform(-0.9, 0.9)).p - origin;
        break;
      case 2:  // along the axis
        direction = shape.axis * (rng.next_double() < 0.5 ? -1.0 : 1.0);
        break;
      case 3:  // from the centre, so from inside
        rays.push_back({shape.center, normalize(direction)});
        continue;
    }
    if (length(direction) > 1e-6) rays.push_back({origin, normalize(direction)});
  }
  return rays;
}

// The light's direction and distance at p, as the evaluator samples it.
std::pair<Vec3, double> towards_light(const PacketLighting& lighting, const Vec3& p) {
  if (lighting.distant) return {lighting.light, std::numeric_limits<double>::infinity()};
  const Vec3 to_light = lighting.light - p;
  const double distance = std::sqrt(length_squared(to_light));
  return {to_light / distance, distance};
}

// What the packet computes past the bump normal, from the scalar functions:
// the shadow ray and the angles of the normals turned towards the viewer.
void expect_lighting(const HitPacket& hits, std::size_t k, const Shape& shape, const Ray& ray,
                     const SurfaceGeometry& g, Vec3 ns, const PacketLighting& lighting,
                     const std::string& what) {
  const auto [wi, distance] = towards_light(lighting, g.p);
  const bool blocked = occluded(shape, {g.p, wi}, lighting.shadow_t_min, distance);
  EXPECT_EQ(hits.blocked[k] != 0.0, blocked) << what << " blocked";
  const Vec3 wo = -ray.direction;
  Vec3 n = g.n;
  if (dot(n, wo) < 0.0) n = -n, ns = -ns;
  expect_bits(hits.theta[k], degrees(acos_approx(dot(n, wi))), what + " theta");
  expect_bits(hits.deviation[k], degrees(acos_approx(dot(ns, n))), what + " deviation");
  expect_bits(hits.view[k], degrees(acos_approx(dot(n, wo))), what + " view");
}

void expect_packet_matches_scalar(const Shape& shape, const HeightFunction& height,
                                  double amplitude, bool bump, const PacketLighting& lighting,
                                  const std::string& label) {
  const std::vector<Ray> all = test_rays(shape, 1000, 17);
  auto rays = std::make_unique<RayPacket>();
  auto hits = std::make_unique<HitPacket>();
  std::size_t found = 0, blocked = 0;
  // Packets of every fill, a lane count that is no multiple of the vector
  // width among them.
  for (std::size_t first = 0, size = 37; first < all.size(); first += size, size = kPacketSize) {
    rays->count = std::min(size, all.size() - first);
    for (std::size_t k = 0; k < rays->count; ++k) rays->set(k, all[first + k]);
    trace_packet(shape, height, amplitude, bump, lighting, *rays, hits.get());
    for (std::size_t k = 0; k < rays->count; ++k) {
      const std::string what = label + ", ray " + std::to_string(first + k);
      Hit scalar;
      const bool hit_scalar =
          intersect(shape, all[first + k], 0.0, std::numeric_limits<double>::infinity(), &scalar);
      ASSERT_EQ(hits->found[k] != 0.0, hit_scalar) << what;
      if (!hit_scalar) continue;
      ++found;
      Hit packet;
      packet.t = hits->hit(k, &packet.geometry);
      const SurfaceGeometry& g = scalar.geometry;
      expect_bits(packet.t, scalar.t, what + " t");
      expect_bits(packet.geometry.p, g.p, what + " p");
      expect_bits(packet.geometry.n, g.n, what + " n");
      expect_bits(packet.geometry.t1, g.t1, what + " t1");
      expect_bits(packet.geometry.t2, g.t2, what + " t2");
      expect_bits(packet.geometry.v, g.v, what + " v");
      expect_bits(packet.geometry.kappa1, g.kappa1, what + " kappa1");
      expect_bits(packet.geometry.kappa2, g.kappa2, what + " kappa2");
      const Vec3 ns = bump ? displaced_normal(g, amplitude, evaluate_height(height, g.p)) : g.n;
      expect_bits(hits->ns(k), ns, what + " ns");
      expect_lighting(*hits, k, shape, all[first + k], g, ns, lighting, what);
      blocked += hits->blocked[k] != 0.0;
      if (::testing::Test::HasFailure()) return;  // one ray's report is enough
    }
  }
  // Enough of both outcomes for the comparison to mean something.
  EXPECT_GT(found, 300u) << label;
  EXPECT_LT(found, 950u) << label;
  EXPECT_GT(blocked, found / 10) << label;
  EXPECT_LT(blocked, found - found / 10) << label;
}

HeightFunction sum_of_terms() {
  HeightFunction f;
  f.terms = {{{3.1, -1.7, 0.4}, 0.3, 0.8}, {{-0.2, 5.9, 2.2}, -1.1, 0.35}, {{7, 7, -7}, 2.0, -0.1}};
  return f;
}
HeightFunction product_of_terms() {
  HeightFunction f = sum_of_terms();
  f.combine = HeightCombine::kProduct;
  return f;
}

// On every instruction set this CPU runs that the packet was built for
// (AVX-512, AVX2, SSE4, SSSE3 and plain C++ on a recent x86), not only the widest.
TEST(RayPacket, HitsAndBumpNormalsHaveTheScalarBits) {
  Shape cylinder;
  cylinder.type = ShapeType::kCylinder;
  cylinder.center = {0.3, -0.2, 0.1};
  cylinder.axis = normalize(Vec3{0.2, 1.0, -0.3});
  cylinder.radius = 0.8;
  cylinder.height = 1.7;
  cylinder = with_frame(cylinder);
  Shape sphere = cylinder;
  sphere.type = ShapeType::kSphere;
  const std::vector<std::int64_t> targets = hwy::SupportedAndGeneratedTargets();
  EXPECT_GE(targets.size(), 2u) << "a vector target and the plain C++ one at least";
  for (const std::int64_t target : targets)
    for (const Shape& shape : {cylinder, sphere}) {
      hwy::SetSupportedTargetsForTest(target);
      ASSERT_STREQ(packet_target(), hwy::TargetName(target));
      const std::string name = std::string(hwy::TargetName(target)) + ", " +
                               (shape.type == ShapeType::kSphere ? "sphere" : "cylinder");
      ASSERT_TRUE(packet_supports(shape));
      const PacketLighting distant{true, normalize(Vec3{-1, 0.3, -0.2}), 1e-7 * shape.radius};
      const PacketLighting point{false, shape.center + Vec3{-3, 1, -2}, 1e-7 * shape.radius};
      expect_packet_matches_scalar(shape, sum_of_terms(), 0.02, true, distant, name + ", sum");
      expect_packet_matches_scalar(shape, product_of_terms(), 0.05, true, point,
                                   name + ", product");
      expect_packet_matches_scalar(shape, HeightFunction{}, 0.02, true, distant,
                                   name + ", no terms");
      expect_packet_matches_scalar(shape, sum_of_terms(), 0.0, true, point, name + ", A = 0");
      expect_packet_matches_scalar(shape, sum_of_terms(), 0.02, false, distant, name + ", no bump");
    }
  hwy::SetSupportedTargetsForTest(0);
  cylinder.caps = true;
  EXPECT_FALSE(packet_supports(cylinder)) << "caps are not displaceable; the packet has no flag";
}

// Two renders of a displaced mesh whose hits differ by Embree's float
// rounding alone (embree_rounding.h): radiance within 1e-5 of albedo*E/pi
// (measured on an AVX2 machine: 3.9e-7, the hit's barycentrics moving the
// exact normal; a hundredth of the truths' convergence tolerance), the
// analysis angles within 1e-2 degrees (measured: 2.2e-4, at a grazing
// view), the factor analysis.G within 1e-5, coverage the same. A
// shadow ray that the rounding turned around would move a pixel by a whole
// sample's share and fail this: none did on these scenes.
void expect_within_hit_rounding(const Image& packet, const Image& scalar, double radiance_scale,
                                const std::string& label) {
  const std::size_t nc = scalar.channels.size();
  double worst_radiance = 0.0, worst_angle = 0.0;
  for (std::size_t i = 0; i < scalar.pixels.size(); ++i) {
    const std::string& channel = scalar.channels[i % nc];
    const double difference = std::abs(double(packet.pixels[i]) - double(scalar.pixels[i]));
    if (channel == "A")
      EXPECT_EQ(packet.pixels[i], scalar.pixels[i]) << label << ", value " << i;
    else if (channel == "R" || channel == "G" || channel == "B")
      worst_radiance = std::max(worst_radiance, difference / radiance_scale);
    else if (channel == "analysis.theta" || channel == "analysis.deviation" ||
             channel == "analysis.view")
      worst_angle = std::max(worst_angle, difference);
    else
      EXPECT_NEAR(packet.pixels[i], scalar.pixels[i], 1e-5) << label << ", " << channel;
  }
  EXPECT_LT(worst_radiance, 1e-5) << label;
  EXPECT_LT(worst_angle, 1e-2) << label;
}

// The evaluator's packet path gives its scalar path's images bit for bit,
// on the scenes the packet covers (on a displaced mesh, where this
// machine's Embree kernels round alike); and the scenes it does not cover
// fall back to the scalar path.
TEST(Render, PacketsGiveTheScalarPathsBits) {
  struct Case {
    std::string file;
    std::vector<std::string> sets;
    bool packets;
  };
  const std::vector<Case> cases{
      {"cylinder-grating.json", {"/camera/jitter=true"}, true},
      {"cylinder-noise.json", {"/representation=\"smooth\""}, true},
      {"cylinder-weave.json",
       {"/camera/spp=300", "/camera/width=6", "/camera/height=6", "/terminator/lobes=\"all\"",
        "/material/specular={\"weight\":0.4,\"roughness\":0.3}"},
       true},  // more samples than a packet holds
      {"sphere-weave.json",
       {"/camera/projection=\"perspective\"", "/camera/jitter=true",
        "/light={\"type\":\"point\",\"position\":[-6,1,-2],\"intensity\":40}"},
       true},
      {"sphere-noise.json", {"/terminator/method=\"microshadow-chan2018\""}, true},
      // Displacement: the mesh's camera and shadow rays in Embree packets.
      // The first is the scene and ray on which rtcOccluded16 never returned
      // (evaluator/embree_mesh.h): 8 x 8 pixels, 1 spp.
      {"sphere-grating.json",
       {"/representation=\"displacement\"", "/displacement/edge_length=0.003", "/camera/width=8",
        "/camera/height=8", "/camera/spp=1"},
       true},
      {"sphere-weave.json",
       {"/representation=\"displacement\"", "/displacement/edge_length=0.02",
        "/camera/projection=\"perspective\"", "/camera/jitter=true",
        "/light={\"type\":\"point\",\"position\":[-6,1,-2],\"intensity\":40}",
        "/props=[{\"type\":\"sphere\",\"center\":[-0.6,0.5,-0.9],\"radius\":0.3}]"},
       true},  // point light (finite shadow rays), props, 9 samples: a packet and a lone ray
      {"cylinder-noise.json",
       {"/representation=\"displacement\"", "/displacement/edge_length=0.02", "/shape/caps=true",
        "/camera/position=[0,4,-4]", "/camera/direction=[0,-1,1]", "/camera/up=[0,1.8,1.8]",
        "/camera/spp=20"},
       true},  // the caps, seen from above
      {"cylinder-grating.json", {"/shape/caps=true"}, false},
      {"sphere-grating.json", {"/terminator/method=\"schuessler2017-walk\""}, false}};
  for (const Case& c : cases) {
    std::vector<std::string> sets{"/camera/width=40", "/camera/height=40", "/camera/spp=9"};
    sets.insert(sets.end(), c.sets.begin(), c.sets.end());
    const Scene scene = scene_with(c.file, sets);
    RenderOptions scalar_options;
    scalar_options.packets = false;
    RenderStats packet_stats, scalar_stats;
    const Image packet = render(scene, {}, &packet_stats);
    const Image scalar = render(scene, scalar_options, &scalar_stats);
    const std::string label = c.file + " " + ::testing::PrintToString(c.sets);
    EXPECT_EQ(packet_stats.packets, c.packets) << label;
    EXPECT_FALSE(scalar_stats.packets) << label;
    ASSERT_EQ(packet.pixels.size(), scalar.pixels.size());
    if (scene.representation != Representation::kDisplacement ||
        embree_packets_round_as_single_rays()) {
      EXPECT_EQ(std::memcmp(packet.pixels.data(), scalar.pixels.data(),
                            scalar.pixels.size() * sizeof(float)),
                0)
          << label;
    } else {
      expect_within_hit_rounding(packet, scalar, radiance_scale(scene), label);
    }
  }
}

}  // namespace
}  // namespace penumbra
