// Evaluator renders against analytic radiance, against each other
// (bump vs displacement as A -> 0, tessellation refinement), and for
// determinism across thread counts.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <thread>
#include <vector>

#include <tbb/global_control.h>

#include "core/random.h"
#include "core/shading.h"
#include "evaluator/displaced_mesh.h"
#include "evaluator/evaluator.h"
#include "scene/scene_json.h"

namespace penumbra {
namespace {

using nlohmann::json;

const std::string kScenes = std::string(PENUMBRA_SOURCE_DIR) + "/scenes";

Scene scene_with(const std::string& file, const std::vector<std::string>& sets) {
  std::vector<Override> overrides;
  for (const std::string& s : sets) overrides.push_back(parse_override(s));
  return load_scene(kScenes + "/" + file, overrides);
}

// A pixel-centre ray of the scene's camera, written out here from the
// convention in the reference sheet (section 6), not taken from the evaluator.
Ray centre_ray(const Camera& c, int i, int j) {
  const double x0 = (i + 0.5) / c.width - 0.5, y0 = 0.5 - (j + 0.5) / c.height;
  if (c.projection == Projection::kPerspective)
    return {c.position, normalize(c.direction + c.right * x0 + c.up * y0)};
  return {c.position + c.right * x0 + c.up * y0, normalize(c.direction)};
}

// Lambertian radiance albedo/pi * E * max(0, cos theta) in every pixel of a
// smooth render sampled at pixel centres, to float precision; coverage and the
// theta channel follow the geometry.
void expect_analytic(const Scene& scene, auto&& normal_at_centre_ray) {
  const Image image = render(scene);
  const int theta_channel = image.channel_index("analysis.theta");
  int lit = 0, covered = 0;
  for (int j = 0; j < image.height; ++j)
    for (int i = 0; i < image.width; ++i) {
      Vec3 n, p;
      const bool hit = normal_at_centre_ray(centre_ray(scene.camera, i, j), &n, &p);
      ASSERT_EQ(image.at(i, j, 3), hit ? 1.0f : 0.0f) << i << "," << j;
      if (!hit) {
        ASSERT_EQ(image.at(i, j, 0), 0.0f);
        continue;
      }
      ++covered;
      Vec3 wi = scene.light.direction;
      double irradiance = scene.light.irradiance;
      if (scene.light.type == LightType::kPoint) {
        wi = normalize(scene.light.position - p);
        irradiance = scene.light.intensity / length_squared(scene.light.position - p);
      }
      const double cos_theta = dot(n, wi);
      const double expected = scene.material.albedo / kPi * irradiance * std::max(0.0, cos_theta);
      lit += expected > 0;
      ASSERT_NEAR(image.at(i, j, 0), expected, 1e-6 * (1.0 + expected)) << i << "," << j;
      ASSERT_NEAR(image.at(i, j, theta_channel), degrees(std::acos(cos_theta)), 1e-4);
    }
  EXPECT_GT(covered, image.width * image.height / 4);
  EXPECT_GT(lit, covered / 4);
}

TEST(Render, SmoothCylinderMatchesAnalyticRadiance) {
  const Scene scene = scene_with("cylinder-grating.json",
                                 {"/representation=smooth", "/camera/spp=1", "/camera/jitter=false",
                                  "/camera/width=96", "/camera/height=80"});
  expect_analytic(scene, [&](const Ray& r, Vec3* n, Vec3* p) {
    // Axis y through the origin, radius 1, |y| <= 1, orthographic along +z.
    const double x = r.origin.x, y = r.origin.y;
    if (std::abs(x) >= 1.0 || std::abs(y) > 1.0) return false;
    *n = {x, 0.0, -std::sqrt(1.0 - x * x)};
    *p = *n + Vec3{0, y, 0};
    return true;
  });
}

bool sphere_hit(const Ray& r, Vec3* n, Vec3* p) {
  // Unit sphere at the origin.
  const double b = dot(r.origin, r.direction), c = dot(r.origin, r.origin) - 1.0;
  if (b * b - c <= 0.0) return false;
  *p = r.origin + r.direction * (-b - std::sqrt(b * b - c));
  *n = *p;
  return true;
}

TEST(Render, SmoothSphereMatchesAnalyticRadiance) {
  expect_analytic(scene_with("sphere-grating.json",
                             {"/representation=smooth", "/camera/spp=1", "/camera/jitter=false",
                              "/camera/width=64", "/camera/height=64"}),
                  sphere_hit);
}

TEST(Render, SmoothSpherePerspectiveWithPointLightMatchesAnalyticRadiance) {
  expect_analytic(
      scene_with("sphere-noise.json",
                 {"/representation=smooth", "/camera/spp=1", "/camera/jitter=false",
                  "/camera/width=64", "/camera/height=48", "/camera/projection=perspective",
                  "/camera/direction=[0,0,2]", "/camera/right=[1.2,0,0]", "/camera/up=[0,0.9,0]",
                  R"(/light={"type":"point","position":[-3,1,-2],"intensity":20})"}),
      sphere_hit);
}

// The fitted method's parameter: a small table (tests/evaluator/data).
const std::string kFittedTable = "/terminator/parameters={\"table\": \"" +
                                 std::string(PENUMBRA_SOURCE_DIR) +
                                 "/tests/evaluator/data/fitted-table.json\"}";

TEST(Render, BumpWithZeroAmplitudeEqualsSmoothBitForBit) {
  for (const MethodInfo& m : all_methods()) {
    if (m.user_defined) continue;  // a scene names a registered one (tests/python)
    const std::vector<std::string> common = {"/height/amplitude=0", "/camera/width=48",
                                             "/camera/height=48", "/camera/spp=4",
                                             "/terminator/method=\"" + std::string(m.id) + "\""};
    auto with = [&](const char* representation) {
      std::vector<std::string> sets = common;
      if (m.needs_table) sets.push_back(kFittedTable);
      sets.push_back(std::string("/representation=") + representation);
      return render(scene_with("sphere-weave.json", sets)).pixels;
    };
    EXPECT_EQ(with("bump"), with("smooth")) << m.id;
  }
}

// render_methods gives each method the bits of its own render, on every
// tracer: the analytic base (with jitter, a point light and GGX), a low-poly
// mesh with a prop, the displaced mesh, and the microshadowing methods'
// shared visibility. A method that draws random numbers is refused.
TEST(Render, MethodsRenderedTogetherHaveTheBitsOfTheirOwnRenders) {
  const std::vector<std::string> ids{"none",
                                     "chiang2019",
                                     "estevez2019",
                                     "deshmukh2020",
                                     "shading-offset",
                                     "cycles45",
                                     "mitsuba3",
                                     "mitsuba3-flip",
                                     "iray2017",
                                     "schuessler2017-shadowing",
                                     "microshadow-chan2018",
                                     "microshadow-brinck2016"};
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases{
      {"cylinder-weave.json",
       {"/representation=\"bump\"", "/camera/jitter=true",
        "/material/specular={\"weight\":0.4,\"roughness\":0.3}", "/terminator/lobes=\"all\""}},
      {"sphere-grating.json",
       {"/representation=\"bump\"", "/camera/projection=\"perspective\"",
        "/light={\"type\":\"point\",\"position\":[-6,1,-2],\"intensity\":40}"}},
      {"lowpoly/ball-on-sphere.json",
       {"/representation=\"bump\"",
        "/height={\"type\":\"grating\",\"amplitude\":0.01,\"frequency\":8,\"direction\":[1,0,0]}"}},
      {"sphere-noise.json",
       {"/representation=\"displacement\"", "/displacement/edge_length=0.03"}}};
  for (const auto& [file, sets] : cases) {
    std::vector<std::string> base = sets;
    for (const char* s : {"/camera/width=24", "/camera/height=24", "/camera/spp=4"})
      base.push_back(s);
    const Scene scene = scene_with(file, base);
    std::vector<TerminatorSettings> methods;
    std::vector<Image> alone;
    for (const std::string& id : ids) {
      std::vector<std::string> with_method = base;
      with_method.push_back("/terminator/method=\"" + id + "\"");
      const Scene one = scene_with(file, with_method);
      if (scene.tessellation && method_info(one.terminator.method.method).needs_visibility)
        continue;  // refused on meshes
      methods.push_back(one.terminator);
      alone.push_back(render(one));
    }
    RenderStats together_stats;
    const std::vector<Image> together = render_methods(scene, methods, {}, &together_stats);
    ASSERT_EQ(together.size(), methods.size());
    for (std::size_t k = 0; k < methods.size(); ++k) {
      ASSERT_EQ(together[k].pixels.size(), alone[k].pixels.size());
      EXPECT_EQ(std::memcmp(together[k].pixels.data(), alone[k].pixels.data(),
                            alone[k].pixels.size() * sizeof(float)),
                0)
          << file << ", " << method_info(methods[k].method.method).id;
    }
    // Not all alike: the methods do differ on these scenes.
    EXPECT_NE(std::memcmp(together[0].pixels.data(), together[1].pixels.data(),
                          together[0].pixels.size() * sizeof(float)),
              0)
        << file;
  }
  Scene walk = scene_with("sphere-grating.json", {"/camera/width=8", "/camera/height=8"});
  TerminatorSettings w = walk.terminator;
  w.method.method = TerminatorMethod::kSchuessler2017Walk;
  EXPECT_FALSE(shares_samples(w));
  EXPECT_THROW(render_methods(walk, {walk.terminator, w}), std::invalid_argument);
  EXPECT_EQ(render_methods(walk, {w}).size(), 1u);  // alone it is a plain render
}

// render_lightings gives each displacement truth the bits of its own
// render: distant, point, sphere and quad lights and a glossy material on
// one displaced mesh (and on a scene with a prop), through Embree
// packets and one ray at a time, with the camera rays traced once.
TEST(Render, TruthsOfSeveralLightsRenderedTogetherHaveTheBitsOfTheirOwnRenders) {
  const std::vector<std::vector<std::string>> lightings{
      {},
      {"/light/direction=[-1,0.7,-0.2]"},
      {"/material/specular={\"weight\":0.4,\"roughness\":0.3}", "/terminator/lobes=\"all\""},
      {"/light={\"type\":\"point\",\"position\":[-6,1,-2],\"intensity\":40}"},
      {"/light={\"type\":\"sphere\",\"position\":[-3,0,-1],\"radius\":0.5,\"power\":100}"},
      {"/light={\"type\":\"quad\",\"corner\":[-3,-1,-2],\"edge_u\":[0,2,0],"
       "\"edge_v\":[0,0,1],\"radiance\":5}"}};
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases{
      {"sphere-weave.json", {"/camera/jitter=true"}},
      {"cylinder-grating.json",
       {"/props=[{\"type\":\"sphere\",\"center\":[-1.3,0.2,-0.6],\"radius\":0.3}]"}}};
  for (const auto& [file, sets] : cases)
    for (const bool packets : {true, false}) {
      std::vector<Scene> scenes;
      std::vector<Image> alone;
      RenderOptions options;
      options.packets = packets;
      options.share_meshes = false;
      for (const std::vector<std::string>& lighting : lightings) {
        std::vector<std::string> with = sets;
        for (const char* s : {"/representation=\"displacement\"", "/displacement/edge_length=0.03",
                              "/camera/width=20", "/camera/height=20", "/camera/spp=9"})
          with.push_back(s);
        with.insert(with.end(), lighting.begin(), lighting.end());
        scenes.push_back(scene_with(file, with));
        alone.push_back(render(scenes.back(), options));
      }
      RenderStats stats;
      const std::vector<Image> together = render_lightings(scenes, options, &stats);
      ASSERT_EQ(together.size(), scenes.size());
      EXPECT_EQ(stats.camera_samples, 20u * 20u * 9u) << "each camera ray traced once";
      for (std::size_t k = 0; k < scenes.size(); ++k) {
        ASSERT_EQ(together[k].pixels.size(), alone[k].pixels.size());
        EXPECT_EQ(std::memcmp(together[k].pixels.data(), alone[k].pixels.data(),
                              alone[k].pixels.size() * sizeof(float)),
                  0)
            << file << ", lighting " << k << (packets ? ", packets" : ", one ray at a time");
        if (k > 0) {  // not all alike: the lightings do differ
          EXPECT_NE(std::memcmp(together[k].pixels.data(), together[0].pixels.data(),
                                alone[k].pixels.size() * sizeof(float)),
                    0)
              << file << ", lighting " << k;
        }
      }
    }
  Scene bump = scene_with("sphere-weave.json", {"/camera/width=8", "/camera/height=8"});
  EXPECT_THROW(render_lightings({bump}), std::invalid_argument);
  EXPECT_THROW(render_lightings({}), std::invalid_argument);
}

// A truth at 4^k times the samples that extends the sums of fewer
// (RenderOptions::resume) has the bits of the same truth rendered from
// scratch: alone and in a lightings pass, through Embree packets and one
// ray at a time, under a distant light and a sphere light (whose samples
// nest too), one level up (16 -> 64) and two (16 -> 256). It draws only
// the samples it adds.
TEST(Render, ATruthExtendedFromFewerSamplesHasTheBitsOfOneRenderedFromScratch) {
  const std::vector<std::vector<std::string>> lightings{
      {}, {"/light={\"type\":\"sphere\",\"position\":[-3,0,-1],\"radius\":0.5,\"power\":100}"}};
  const auto scene_at = [](int spp, const std::vector<std::string>& lighting) {
    std::vector<std::string> with{"/representation=\"displacement\"",
                                  "/displacement/edge_length=0.03",
                                  "/camera/width=12",
                                  "/camera/height=12",
                                  "/camera/jitter=true",
                                  "/camera/spp=" + std::to_string(spp)};
    with.insert(with.end(), lighting.begin(), lighting.end());
    return scene_with("sphere-weave.json", with);
  };
  const auto same_bits = [](const Image& a, const Image& b) {
    return a.pixels.size() == b.pixels.size() &&
           std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float)) == 0;
  };
  for (const bool packets : {true, false}) {
    RenderOptions options;
    options.packets = packets;
    const std::string path = packets ? "packets" : "one ray at a time";
    for (std::size_t l = 0; l < lightings.size(); ++l) {
      std::vector<SampleSums> s16, s64, s64_scratch;
      RenderOptions keep16 = options;
      keep16.sums = &s16;
      render(scene_at(16, lightings[l]), keep16);
      RenderOptions extend = options;
      extend.resume = &s16;
      extend.sums = &s64;
      RenderStats stats;
      const Image extended = render(scene_at(64, lightings[l]), extend, &stats);
      EXPECT_EQ(stats.camera_samples, 12u * 12u * 48u) << "only the samples it adds";
      EXPECT_EQ(stats.resumed_spp, 16);
      RenderOptions keep64 = options;
      keep64.sums = &s64_scratch;
      EXPECT_TRUE(same_bits(extended, render(scene_at(64, lightings[l]), keep64)))
          << path << ", lighting " << l;
      ASSERT_EQ(s64.size(), 1u);
      EXPECT_EQ(s64[0].values, s64_scratch[0].values) << "the sums a later check extends";
      const Image scratch256 = render(scene_at(256, lightings[l]), options);
      RenderOptions from16 = options, from64 = options;
      from16.resume = &s16;
      from64.resume = &s64;
      EXPECT_TRUE(same_bits(render(scene_at(256, lightings[l]), from16), scratch256)) << path;
      EXPECT_TRUE(same_bits(render(scene_at(256, lightings[l]), from64), scratch256)) << path;
      // Not the 16-sample image: the samples added do count.
      EXPECT_FALSE(same_bits(scratch256, render(scene_at(16, lightings[l]), options)));
    }
    // A lightings pass extends each truth's own sums.
    std::vector<Scene> at16, at64;
    for (const auto& lighting : lightings) {
      at16.push_back(scene_at(16, lighting));
      at64.push_back(scene_at(64, lighting));
    }
    std::vector<SampleSums> pass16;
    RenderOptions keep = options;
    keep.sums = &pass16;
    render_lightings(at16, keep);
    RenderOptions extend = options;
    extend.resume = &pass16;
    const std::vector<Image> extended = render_lightings(at64, extend);
    for (std::size_t l = 0; l < at64.size(); ++l)
      EXPECT_TRUE(same_bits(extended[l], render(at64[l], options))) << path << ", pass " << l;
  }
  // Sums the pattern does not nest (16 samples are a plain grid, not 4's
  // extended) or of another scene size are refused; so is a bump render.
  std::vector<SampleSums> s4;
  RenderOptions keep4;
  keep4.sums = &s4;
  render(scene_at(4, {}), keep4);
  RenderOptions wrong;
  wrong.resume = &s4;
  EXPECT_THROW(render(scene_at(64, {}), wrong), std::invalid_argument);
  s4[0].width = 6;
  EXPECT_THROW(render(scene_at(4, {}), wrong), std::invalid_argument);
  Scene bump = scene_with("sphere-weave.json", {"/camera/width=8", "/camera/height=8"});
  EXPECT_THROW(render(bump, keep4), std::invalid_argument);
}

// ospray renders: on a closed sphere every light below Ng is already behind
// the sphere, so its side test changes no radiance; on a plane lit from just
// below its horizon, raw bump lets the bump normals catch the light and
// ospray drops all of it.
TEST(Render, OsprayDropsTheLightBelowAPlaneAndChangesNothingOnASphere) {
  const auto radiance = [](const std::string& method, std::vector<std::string> sets) {
    for (const char* s : {"/camera/width=48", "/camera/height=48", "/camera/spp=4"})
      sets.emplace_back(s);
    sets.push_back("/terminator/method=\"" + method + "\"");
    const Image image = render(scene_with("sphere-weave.json", sets));
    std::vector<float> r;
    for (int j = 0; j < image.height; ++j)
      for (int i = 0; i < image.width; ++i) r.push_back(image.at(i, j, 0));
    return r;
  };
  EXPECT_EQ(radiance("ospray", {}), radiance("none", {}));
  const std::vector<std::string> plane = {
      R"(/shape={"type": "plane", "axis": [0, 0, -1], "width": 2, "height": 2})",
      "/light/direction=[-1,0,0.05]", "/height/amplitude=0.05"};
  double leaked = 0.0, dropped = 0.0;
  for (float r : radiance("none", plane)) leaked += r;
  for (float r : radiance("ospray", plane)) dropped += r;
  EXPECT_GT(leaked, 1.0);
  EXPECT_EQ(dropped, 0.0);
}

// The table's draws_random is what shade() does: a method that says it draws
// none leaves the pixel's stream where it was, at points where it shades.
TEST(Render, MethodsDrawRandomNumbersExactlyWhenTheTableSaysSo) {
  Material m;
  m.albedo = 0.8;
  const Vec3 ng{0, 0, 1}, wo = normalize(Vec3{0.2, 0.1, 1});
  for (const MethodInfo& info : all_methods()) {
    TerminatorSettings t;
    t.method.method = info.method;
    bool drew = false;
    for (double tilt : {0.1, 0.3, 0.6})
      for (double light : {0.2, 0.8, 1.4}) {
        const Vec3 ns = normalize(Vec3{tilt, 0, 1});
        const Vec3 wi = normalize(Vec3{std::sin(light), 0.05, std::cos(light)});
        Pcg32 rng(7), untouched(7);
        ShadingPoint p{ng, ng, ns, wi, wo};
        p.visibility = 0.7;
        shade(t, m, p, &rng);
        drew = drew || rng.next_double() != untouched.next_double();
      }
    EXPECT_EQ(drew, info.draws_random) << info.id;
  }
}

TEST(Render, SameBitsWhateverTheThreadCount) {
  for (const char* representation : {"bump", "displacement"}) {
    const Scene scene = scene_with(
        "cylinder-noise.json",
        {std::string("/representation=") + representation, "/camera/width=64", "/camera/height=64",
         "/camera/spp=4", "/terminator/method=estevez2019", "/displacement/edge_length=0.01"});
    // Each render builds its own mesh, under its own thread count.
    RenderOptions own_mesh;
    own_mesh.share_meshes = false;
    std::vector<float> one, two;
    {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
      one = render(scene, own_mesh).pixels;
    }
    {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
      two = render(scene, own_mesh).pixels;
    }
    EXPECT_EQ(one, two) << representation;
    EXPECT_EQ(render(scene, own_mesh).pixels, two) << representation;
  }
}

// A study's displacement renders share meshes by geometry (shape, height
// field, amplitude, edge length): what else differs does not split them,
// what the mesh is made of does, and a shared mesh renders the same bits as
// one built for the render, also when two threads ask for it at once.
TEST(Render, DisplacementRendersShareAMeshOnlyWithTheSameGeometry) {
  const std::vector<std::string> base{"/representation=displacement", "/camera/width=48",
                                      "/camera/height=48", "/camera/spp=2",
                                      "/displacement/edge_length=0.013"};
  auto with = [&](std::vector<std::string> more) {
    more.insert(more.begin(), base.begin(), base.end());
    return scene_with("sphere-weave.json", more);
  };
  const Scene a = with({});
  const std::string key = displaced_mesh_key(a);
  for (const std::vector<std::string>& same :
       {std::vector<std::string>{"/light/direction=[1,0.2,-1]"},
        {"/material/albedo=0.3"},
        {"/camera/spp=8"},
        {"/terminator/method=estevez2019"},
        {"/camera/width=20"}})
    EXPECT_EQ(displaced_mesh_key(with(same)), key) << same[0];
  for (const std::vector<std::string>& other :
       {std::vector<std::string>{"/displacement/edge_length=0.0131"},
        {"/height/amplitude=0.011"},
        {"/height/frequency=6.5"},
        {"/shape/radius=0.9"},
        {"/height/combine=sum"}})
    EXPECT_NE(displaced_mesh_key(with(other)), key) << other[0];

  RenderOptions own_mesh;
  own_mesh.share_meshes = false;
  const Scene lit_elsewhere = with({"/light/direction=[1,0.2,-1]"});
  const std::vector<float> fresh_a = render(a, own_mesh).pixels;
  const std::vector<float> fresh_b = render(lit_elsewhere, own_mesh).pixels;
  ASSERT_NE(fresh_a, fresh_b);  // the light moved: another image, one mesh
  RenderStats first, second, third;
  EXPECT_EQ(render(a, {}, &first).pixels, fresh_a);
  EXPECT_EQ(render(lit_elsewhere, {}, &second).pixels, fresh_b);
  EXPECT_TRUE(second.mesh_reused);
  // Two threads at once on a geometry not built yet: one builds, one waits.
  const Scene c = with({"/height/amplitude=0.012"});
  const std::vector<float> fresh_c = render(c, own_mesh).pixels;
  std::vector<float> from_thread;
  RenderStats thread_stats;
  std::thread t([&] { from_thread = render(c, {}, &thread_stats).pixels; });
  EXPECT_EQ(render(c, {}, &third).pixels, fresh_c);
  t.join();
  EXPECT_EQ(from_thread, fresh_c);
  EXPECT_NE(third.mesh_reused, thread_stats.mesh_reused) << "exactly one of them built it";
}

// Raw bump: light is lost exactly where the base geometry turns away from it,
// even though bumped normals still face the light there (the hard terminator),
// because shadow rays hit the base shape.
TEST(Render, RawBumpHasAHardTerminatorFromRealShadowRays) {
  const Image image =
      render(scene_with("cylinder-grating.json",
                        {"/camera/spp=1", "/camera/jitter=false", "/height/amplitude=0.03"}));
  const int theta = image.channel_index("analysis.theta");
  const int deviation = image.channel_index("analysis.deviation");
  int bumped_towards_light_beyond_terminator = 0;
  float brightest_before = 0.0f;
  for (int j = 0; j < image.height; ++j)
    for (int i = 0; i < image.width; ++i) {
      if (image.at(i, j, 3) < 1.0f) continue;
      const float t = image.at(i, j, theta);
      if (t > 90.01f) {
        EXPECT_EQ(image.at(i, j, 0), 0.0f) << i << "," << j;
        bumped_towards_light_beyond_terminator += image.at(i, j, deviation) > t - 90.0f;
      } else if (t > 87.0f) {
        brightest_before = std::max(brightest_before, image.at(i, j, 0));
      }
    }
  EXPECT_GT(bumped_towards_light_beyond_terminator, 0);
  // albedo/pi * E * cos(87 deg) = 0.8 * 0.052 = 0.042 for smooth shading; the
  // bump pushes pixels just before the terminator far above that.
  EXPECT_GT(brightest_before, 0.2f);
}

// Mean absolute per-pixel difference over pixels both renders cover fully.
double mean_abs_difference(const Image& a, const Image& b) {
  double sum = 0.0;
  int n = 0;
  for (int j = 0; j < a.height; ++j)
    for (int i = 0; i < a.width; ++i)
      if (a.at(i, j, 3) == 1.0f && b.at(i, j, 3) == 1.0f) {
        sum += std::abs(a.at(i, j, 0) - b.at(i, j, 0));
        ++n;
      }
  return sum / n;
}

TEST(Render, BumpConvergesToDisplacementLinearlyAsAmplitudeVanishes) {
  std::vector<double> differences;
  for (double amplitude : {0.008, 0.004, 0.002, 0.001}) {
    auto make = [&](const char* representation) {
      return render(
          scene_with("cylinder-grating.json",
                     {"/representation=" + std::string(representation),
                      "/height/amplitude=" + std::to_string(amplitude), "/camera/width=128",
                      "/camera/height=128", "/camera/spp=4", "/camera/jitter=false"}));
    };
    differences.push_back(mean_abs_difference(make("bump"), make("displacement")));
  }
  // At least first order: halving A at least halves the mean difference (10 %
  // slack for the discrete terminator pixels). Measured ratios are 4.7, 4.7
  // and 3.6: near the terminator the mismatch grows with A in both width and
  // depth (order 2); the order-1 parallax of the displaced silhouette takes
  // over as A shrinks.
  for (std::size_t k = 0; k + 1 < differences.size(); ++k) {
    const double ratio = differences[k] / differences[k + 1];
    RecordProperty("ratio_" + std::to_string(k), std::to_string(ratio));
    EXPECT_GT(ratio, 1.8) << "A ratio " << k << ": " << differences[k] << " / "
                          << differences[k + 1];
  }
  // And the renders do converge: at A = 0.001 (radius / 1000) the mean
  // difference is under 0.1 % of the peak radiance albedo E / pi = 0.8.
  EXPECT_LT(differences.back(), 0.8e-3);
}

// The terminator profile: mean radiance per 1-degree theta bin over fully
// covered pixels, divided by albedo E / pi (reference sheet, section 7).
std::map<int, double> profile(const Image& image, double normaliser) {
  std::map<int, std::pair<double, int>> bins;
  const int theta = image.channel_index("analysis.theta");
  for (int j = 0; j < image.height; ++j)
    for (int i = 0; i < image.width; ++i)
      if (image.at(i, j, 3) == 1.0f) {
        auto& bin = bins[static_cast<int>(image.at(i, j, theta))];
        bin.first += image.at(i, j, 0);
        ++bin.second;
      }
  std::map<int, double> out;
  for (const auto& [bin, sum] : bins)
    if (sum.second >= 20) out[bin] = sum.first / sum.second / normaliser;
  return out;
}

// Halving the tessellation edge changes the ground truth's terminator profile
// by under 0.1 % (RMS over bins, relative to the smooth peak of 1).
TEST(Render, DisplacementGroundTruthIsConvergedInTessellation) {
  for (const char* file : {"cylinder-grating.json", "sphere-weave.json"}) {
    auto make = [&](double edge) {
      const Scene s = scene_with(file, {"/representation=displacement", "/camera/spp=4",
                                        "/displacement/edge_length=" + std::to_string(edge)});
      return profile(render(s), s.material.albedo * s.light.irradiance / kPi);
    };
    const auto coarse = make(0.004), fine = make(0.002);
    double sum = 0.0;
    int n = 0;
    for (const auto& [bin, value] : fine)
      if (coarse.count(bin)) {
        sum += (value - coarse.at(bin)) * (value - coarse.at(bin));
        ++n;
      }
    ASSERT_GT(n, 100) << file;
    const double rms = std::sqrt(sum / n);
    RecordProperty(std::string("profile_rms_") + file, std::to_string(rms));
    EXPECT_LT(rms, 1e-3) << file;
  }
}

// A pixel's light and view angles are those at the base point its centre ray
// meets, whatever the samples per pixel and the representation: the bins of
// the profile and the viewer metric do not move when a ground truth is
// checked against 4x its samples, and truth and method bin their pixels
// alike. (Means over the samples moved by a few 0.01 degrees between 256
// and 1024 samples; where the glossy lobe makes a bin's pixels differ a lot,
// each pixel that crossed a bin edge moved that bin by 0.006 of albedo*E/pi.)
TEST(Render, AnalysisAnglesAreThePixelCentresWhateverTheSamplesAndRepresentation) {
  const std::vector<std::string> common = {
      "/camera/width=48", "/camera/height=48", "/height/amplitude=0.02",
      R"(/material/specular={"weight": 0.4, "roughness": 0.3})"};
  auto with = [&](std::vector<std::string> more) {
    more.insert(more.begin(), common.begin(), common.end());
    return scene_with("sphere-grating.json", more);
  };
  const Scene truth4 = with({"/representation=displacement", "/camera/spp=4"});
  const Image a = render(truth4);
  const Image b = render(with({"/representation=displacement", "/camera/spp=16"}));
  const Image c = render(with({"/representation=bump", "/camera/spp=4"}));
  const int theta = a.channel_index("analysis.theta"), view = a.channel_index("analysis.view");
  int checked = 0;
  for (int j = 0; j < a.height; ++j)
    for (int i = 0; i < a.width; ++i) {
      const Ray ray = centre_ray(truth4.camera, i, j);
      Hit hit;
      if (!intersect(truth4.shape, ray, 0.0, 1e30, &hit)) continue;
      if (!(a.at(i, j, 3) > 0.0f && b.at(i, j, 3) > 0.0f && c.at(i, j, 3) > 0.0f)) continue;
      ++checked;
      for (const Image* other : {&b, &c}) {
        ASSERT_EQ(a.at(i, j, theta), other->at(i, j, theta)) << i << "," << j;
        ASSERT_EQ(a.at(i, j, view), other->at(i, j, view)) << i << "," << j;
      }
      // The centre ray's base point, written out here.
      const Vec3 n = hit.geometry.n;
      EXPECT_NEAR(a.at(i, j, theta), degrees(std::acos(dot(n, truth4.light.direction))), 1e-4);
      EXPECT_NEAR(a.at(i, j, view), degrees(std::acos(dot(n, -ray.direction))), 1e-4);
    }
  EXPECT_GT(checked, a.width * a.height / 4);
}

}  // namespace
}  // namespace penumbra
