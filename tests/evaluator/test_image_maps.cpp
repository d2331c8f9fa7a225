// Image height and normal maps in scenes: a map baked from an analytic
// height function renders like that function, within bounds derived from
// the texel pitch; bad maps are refused with the scene file and pointer.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "analysis/metrics.h"
#include "cli_test.h"
#include "core/random.h"
#include "evaluator/evaluator.h"
#include "image/bump_maps.h"
#include "image/exr_file.h"
#include "image/image_io.h"
#include "renderers/external/blender/blender.h"
#include "renderers/external/povray/povray.h"
#include "renderers/renderers.h"
#include "scene/scene_json.h"
#include "study/cache.h"
#include "study/plan.h"
#include "temp_dir_test.h"

namespace penumbra {
namespace {

using nlohmann::json;

const std::string kScene = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/cylinder-grating.json";

// The test's grating: along the cylinder's axis (radius 1, height 2), 2
// cycles per unit, so that it is a pure sine of v with 4 whole periods over
// the map and a constant along u.
constexpr double kAmplitude = 0.03, kFrequency = 2.0, kHeightSpan = 2.0;

std::vector<Override> grating_sets(const std::vector<std::string>& more) {
  std::vector<Override> sets;
  for (const char* s :
       {"/height/direction=[0,1,0]", "/height/frequency=2", "/height/amplitude=0.03",
        "/height/phase=0.4", "/camera/width=96", "/camera/height=96", "/camera/spp=4"})
    sets.push_back(parse_override(s));
  for (const std::string& s : more) sets.push_back(parse_override(s));
  return sets;
}

Scene analytic_scene(const std::vector<std::string>& more = {}) {
  return load_scene(kScene, grating_sets(more));
}

// The same scene with /height replaced by an image map.
Scene map_scene(const json& height, const std::vector<std::string>& more = {}) {
  std::vector<Override> sets = grating_sets(more);
  sets.push_back({"/height", height});
  return load_scene(kScene, sets);
}

// Bakes the analytic scene's grating over the cylinder, `columns` texels
// around; returns the file.
std::string bake(const std::string& path, MapKind kind, int columns) {
  const Scene s = analytic_scene();
  const int rows = static_cast<int>(std::lround(columns * kHeightSpan / (2.0 * kPi)));
  write_exr(bake_surface_map(s.shape, s.height.function, s.height.amplitude, columns, rows, kind),
            path);
  return path;
}

// Largest slope error of the cubic B-spline of a sine of angular frequency
// omega sampled at pitch tau (Fourier: the spline of e^{i omega x} is
// sum_m Bhat(xi + 2 pi m) e^{i (omega + 2 pi m / tau) x}, xi = omega tau,
// Bhat(z) = (sin(z/2) / (z/2))^4; the triangle inequality bounds the error
// of the derivative term by term), per unit of height amplitude.
double spline_slope_error_bound(double omega, double tau) {
  const double xi = omega * tau;
  const double s4 = std::pow(std::sin(0.5 * xi), 4);
  double bound = omega * (1.0 - 16.0 * s4 / std::pow(xi, 4));
  for (int m = 1; m <= 1000; ++m)
    for (int sign : {-1, 1})
      bound += 16.0 * s4 / std::pow(std::abs(xi + sign * 2.0 * kPi * m), 3) / tau;
  return bound;
}

double rows_pitch(int columns) {
  return kHeightSpan / double(std::lround(columns * kHeightSpan / (2.0 * kPi)));
}

// Largest per-pixel difference of the radiance channel.
double max_difference(const Image& a, const Image& b, double* mean = nullptr) {
  double worst = 0.0, sum = 0.0;
  for (int j = 0; j < a.height; ++j)
    for (int i = 0; i < a.width; ++i) {
      const double d = std::abs(double(a.at(i, j, 0)) - b.at(i, j, 0));
      worst = std::max(worst, d);
      sum += d;
    }
  if (mean) *mean = sum / (a.width * a.height);
  return worst;
}

class ImageMaps : public TempDirTest {};

TEST_F(ImageMaps, BakedGratingSlopesStayWithinTheSplineBoundAndConvergeAtSecondOrder) {
  const Scene analytic = analytic_scene();
  const double omega = 2.0 * kPi * kFrequency;
  double previous = 0.0;
  for (int columns : {256, 512, 1024}) {
    const Scene mapped = map_scene({{"type", "height-map"},
                                    {"file", bake(path("h.exr"), MapKind::kHeight, columns)},
                                    {"amplitude", 1.0}});
    double worst = 0.0;
    for (int i = 0; i <= 2000; ++i) {
      const SurfaceGeometry g = surface_at_parameters(analytic.shape, 0.37, i / 2000.0);
      const HeightSample a = evaluate_height(analytic.height.function, g.p);
      const HeightSample m = height_at({}, mapped.height.height_map(), mapped.shape, g);
      worst = std::max(worst, length(m.gradient - a.gradient * kAmplitude));
    }
    const double bound = kAmplitude * spline_slope_error_bound(omega, rows_pitch(columns));
    EXPECT_LE(worst, bound * (1 + 1e-4) + 1e-6) << columns;
    EXPECT_GT(worst, 0.5 * bound) << columns;  // the bound is the error, not a ceiling far above
    if (previous > 0.0) {
      EXPECT_GT(previous / worst, 3.3) << columns;  // tau^2
      EXPECT_LT(previous / worst, 4.7) << columns;
    }
    previous = worst;
  }
}

TEST_F(ImageMaps, BakedHeightMapRendersLikeTheAnalyticBump) {
  // Same samples, same base geometry and shadows: only Ns differs, by at most
  // atan's Lipschitz constant times A |delta grad h| (the axial grating's
  // normal is N - A g t2 up to scale), and Lambert's radiance by rho E / pi
  // times that angle.
  const int columns = 512;
  const Scene analytic = analytic_scene();
  const Scene mapped = map_scene({{"type", "height-map"},
                                  {"file", bake(path("h.exr"), MapKind::kHeight, columns)},
                                  {"amplitude", 1.0}});
  const Image a = render(analytic), m = render(mapped);
  const double angle =
      kAmplitude * spline_slope_error_bound(2.0 * kPi * kFrequency, rows_pitch(columns));
  const double bound = analytic.material.albedo / kPi * analytic.light.irradiance * angle + 1e-6;
  const double worst = max_difference(a, m);
  EXPECT_LE(worst, bound);
  EXPECT_GT(worst, 0.05 * bound);  // the maps differ, and the test sees it
  // Coverage and the analysis channels follow the same geometry.
  const int deviation = a.channel_index("analysis.deviation");
  for (int j = 0; j < a.height; ++j)
    for (int i = 0; i < a.width; ++i) {
      ASSERT_EQ(a.at(i, j, 3), m.at(i, j, 3));
      ASSERT_NEAR(a.at(i, j, deviation), m.at(i, j, deviation), degrees(angle) + 1e-4);
    }
}

// Largest second derivative of the tangent-space normal's components of
// the axial grating along the axis, (0, -a, 1) / sqrt(1 + a^2) with
// a = A 2 pi f cos(2 pi f y + phase), by central differences on a fine grid.
double max_normal_curvature() {
  const auto n = [](double y, int k) {
    const double a =
        kAmplitude * 2.0 * kPi * kFrequency * std::cos(2.0 * kPi * kFrequency * y + 0.4);
    return (k == 0 ? -a : 1.0) / std::sqrt(1.0 + a * a);
  };
  double sum_sq = 0.0;
  for (int k = 0; k < 2; ++k) {
    double worst = 0.0;
    const double h = 1e-4;
    for (int i = 0; i <= 20000; ++i) {
      const double y = -1.0 + i / 10000.0;
      worst = std::max(worst, std::abs(n(y + h, k) - 2.0 * n(y, k) + n(y - h, k)) / (h * h));
    }
    sum_sq += worst * worst;
  }
  return std::sqrt(sum_sq);
}

TEST_F(ImageMaps, NormalMapOfTheGratingRendersLikeTheAnalyticBump) {
  // The spline reproduces linear functions, so decoding 2 S(0.5 n + 0.5) - 1
  // gives S(n), and |S(n) - n| <= tau^2 / 6 max|n''| per component (the
  // cubic B-spline's kernel has variance 1/3); the renormalised normal is
  // then within |delta| / (1 - |delta|) radians.
  const int columns = 512;
  const Scene analytic = analytic_scene();
  const Scene mapped =
      map_scene({{"type", "normal-map"}, {"file", bake(path("n.exr"), MapKind::kNormal, columns)}});
  ASSERT_NE(mapped.height.normal_map(), nullptr);
  const double tau = rows_pitch(columns);
  const double delta = tau * tau / 6.0 * max_normal_curvature() + 4e-7;  // + float texels
  const double angle = delta / (1.0 - delta);
  const Image a = render(analytic), m = render(mapped);
  const double bound = analytic.material.albedo / kPi * analytic.light.irradiance * angle + 1e-6;
  const double worst = max_difference(a, m);
  EXPECT_LE(worst, bound);
  EXPECT_GT(worst, 0.02 * bound);
}

TEST_F(ImageMaps, PlaneRendersLambertExactlyAndItsNormalMapLikeItsBump) {
  // Facing the camera, normal -z: frame.t is -y, so the axial grating is a
  // sine of v with 4 whole periods over the 2-unit side, as on the cylinder.
  const std::vector<std::string> plane{
      R"(/shape={"type": "plane", "axis": [0, 0, -1], "width": 2, "height": 2})"};
  const Scene smooth = analytic_scene({plane[0], "/representation=smooth"});
  const Image flat = render(smooth);
  const double expected = smooth.material.albedo / kPi * smooth.light.irradiance *
                          dot(Vec3{0, 0, -1}, smooth.light.direction);
  int covered = 0;
  for (int j = 0; j < flat.height; ++j)
    for (int i = 0; i < flat.width; ++i) {
      if (flat.at(i, j, 3) == 0.0f) continue;
      ++covered;
      if (flat.at(i, j, 3) == 1.0f) {
        ASSERT_NEAR(flat.at(i, j, 0), expected, 1e-6);
      }
    }
  // The 2 x 2 square in a 2.5 x 2.5 view: 64 % of the pixels, give or take its edge.
  EXPECT_NEAR(covered / double(flat.width * flat.height), 0.64, 0.03);

  const int columns = 256;
  const Scene analytic = analytic_scene(plane);
  const Image baked =
      bake_surface_map(analytic.shape, analytic.height.function, analytic.height.amplitude, columns,
                       columns, MapKind::kNormal);
  write_exr(baked, path("n.exr"));
  const Scene mapped = map_scene({{"type", "normal-map"}, {"file", path("n.exr")}}, plane);
  const double tau = 2.0 / columns;
  const double delta = tau * tau / 6.0 * max_normal_curvature() + 4e-7;
  const double angle = delta / (1.0 - delta);
  const double bound = analytic.material.albedo / kPi * analytic.light.irradiance * angle + 1e-6;
  const double worst = max_difference(render(analytic), render(mapped));
  EXPECT_LE(worst, bound);
  EXPECT_GT(worst, 0.02 * bound);
}

TEST_F(ImageMaps, SphereNormalMapConvergesToTheAnalyticBumpAtSecondOrder) {
  const std::vector<Override> sets{parse_override("/camera/width=8")};
  const Scene analytic =
      load_scene(std::string(PENUMBRA_SOURCE_DIR) + "/scenes/sphere-grating.json", sets);
  double previous = 0.0;
  for (int columns : {512, 1024, 2048}) {
    const Image baked =
        bake_surface_map(analytic.shape, analytic.height.function, analytic.height.amplitude,
                         columns, columns / 2, MapKind::kNormal);
    write_exr(baked, path("n.exr"));
    const auto map = load_surface_map(path("n.exr"), MapKind::kNormal);
    double worst = 0.0;
    Pcg32 rng(9);
    for (int i = 0; i < 4000; ++i) {  // within latitude +-60 degrees
      const SurfaceGeometry g = surface_at_parameters(analytic.shape, rng.next_double(),
                                                      (1.0 + 4.0 * rng.next_double()) / 6.0);
      const Vec3 exact = displaced_normal(g, analytic.height.amplitude,
                                          evaluate_height(analytic.height.function, g.p));
      const Vec3 mapped = normal_map_normal(*map, analytic.shape, g);
      worst = std::max(worst, std::acos(std::min(1.0, dot(exact, mapped))));
    }
    if (previous > 0.0) {
      EXPECT_GT(previous / worst, 3.0) << columns;
      EXPECT_LT(previous / worst, 5.0) << columns;
    }
    previous = worst;
  }
}

TEST_F(ImageMaps, DisplacedHeightMapMatchesTheAnalyticGroundTruth) {
  // The truth's shading normal obeys the bump bound; its mesh moves by at most
  // A |delta h| (far below a pixel), which can only flip samples on a shadow
  // or silhouette edge.
  const int columns = 512;
  const std::vector<std::string> truth{"/representation=displacement",
                                       "/displacement/edge_length=0.01"};
  const Scene analytic = analytic_scene(truth);
  const Scene mapped = map_scene({{"type", "height-map"},
                                  {"file", bake(path("h.exr"), MapKind::kHeight, columns)},
                                  {"amplitude", 1.0}},
                                 truth);
  const Image a = render(analytic), m = render(mapped);
  const double angle =
      kAmplitude * spline_slope_error_bound(2.0 * kPi * kFrequency, rows_pitch(columns));
  const double bound = analytic.material.albedo / kPi * analytic.light.irradiance * angle + 1e-6;
  int covered = 0, outside = 0;
  for (int j = 0; j < a.height; ++j)
    for (int i = 0; i < a.width; ++i) {
      if (a.at(i, j, 3) == 0.0f && m.at(i, j, 3) == 0.0f) continue;
      ++covered;
      outside += std::abs(double(a.at(i, j, 0)) - m.at(i, j, 0)) > bound;
    }
  EXPECT_GT(covered, 2000);
  EXPECT_LE(outside, covered / 100) << outside << " of " << covered;
}

std::string refusal(const json& height, const std::vector<std::string>& more = {}) {
  try {
    map_scene(height, more);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST_F(ImageMaps, BadMapsAreRefusedNamingTheSceneTheirPointerAndTheImage) {
  const std::string missing =
      refusal({{"type", "height-map"}, {"file", path("none.exr")}, {"amplitude", 1}});
  EXPECT_NE(missing.find("cylinder-grating.json"), std::string::npos) << missing;
  EXPECT_NE(missing.find("/height/file"), std::string::npos) << missing;
  EXPECT_NE(missing.find("none.exr: no such file"), std::string::npos) << missing;

  Image one;
  one.width = 4, one.height = 2, one.channels = {"Y"};
  one.pixels.assign(8, 0.5f);
  write_exr(one, path("one.exr"));
  const std::string channels = refusal({{"type", "normal-map"}, {"file", path("one.exr")}});
  EXPECT_NE(channels.find("a normal map needs R, G and B"), std::string::npos) << channels;

  one.pixels[5] = std::nanf("");
  write_exr_file(one, path("nan.exr"), {});  // write_exr refuses NaN
  const std::string nan =
      refusal({{"type", "height-map"}, {"file", path("nan.exr")}, {"amplitude", 1}});
  EXPECT_NE(nan.find("texel (1, 1)"), std::string::npos) << nan;

  one.pixels[5] = 0.5f;
  write_exr(one, path("ok.exr"));
  const json ok{{"type", "height-map"}, {"file", path("ok.exr")}, {"amplitude", 0.01}};
  json tiles = ok;
  tiles["tiles"] = {1, 0};
  EXPECT_NE(refusal(tiles).find("/height/tiles: expected [tiles_u, tiles_v]"), std::string::npos);
  json extra = ok;
  extra["scale"] = 2;
  EXPECT_NE(refusal(extra).find("/height/scale: unknown key"), std::string::npos);
  json reach = ok;
  reach["amplitude"] = 4.0;  // 4 * 0.5 >= radius 1
  EXPECT_NE(refusal(reach).find("/height/amplitude"), std::string::npos);

  const json normal{{"type", "normal-map"}, {"file", bake(path("n.exr"), MapKind::kNormal, 64)}};
  EXPECT_NE(refusal(normal, {"/representation=displacement"}).find("/representation"),
            std::string::npos);
  EXPECT_NE(refusal(ok, {"/terminator/method=microshadow-chan2018"}).find("/terminator/method"),
            std::string::npos);
  EXPECT_EQ(refusal(ok), "");
}

// POV-Ray renders an image height map as the evaluator's cubic B-spline of
// the texels (SDL functions over nearest-texel lookups of the exported map)
// and its displacement as the evaluator's grid. Each map render must agree
// with the evaluator's render of the same map about as well as POV-Ray's
// analytic render agrees with the evaluator's analytic one, and with
// POV-Ray's own analytic render within the map's error (as for Blender).
TEST_F(ImageMaps, PovrayRendersHeightMapsAsTheEvaluatorDoes) {
  const std::string heights = bake(path("h.exr"), MapKind::kHeight, 512);
  const json height_map{{"type", "height-map"}, {"file", heights}, {"amplitude", 1}};
  const std::vector<std::pair<const char*, std::vector<std::string>>> cases{
      {"height map, raw bump", {}},
      {"height map, displaced grid",
       {"/representation=displacement", "/displacement/edge_length=0.01"}}};
  RenderSettings settings;
  settings.log_path = path("povray.log");
  settings.timeout_s = 300;
  for (const auto& [what, more] : cases) {
    std::vector<std::string> sets = more;
    sets.push_back("/camera/spp=16");
    const Scene analytic = analytic_scene(sets);
    const Scene mapped = map_scene(height_map, sets);
    const double scale = radiance_scale(analytic);
    const auto profile = [&](const Image& image) { return terminator_profile(image, scale); };
    const Profile povray_analytic =
        profile(render_with(RendererKind::kPovray, analytic, settings).image);
    const Profile povray_map = profile(render_with(RendererKind::kPovray, mapped, settings).image);
    const double analytic_gap =
        compare_profiles(povray_analytic, profile(render(analytic))).rmse_overall;
    const double map_gap = compare_profiles(povray_map, profile(render(mapped))).rmse_overall;
    const double povray_twins = compare_profiles(povray_map, povray_analytic).rmse_overall;
    std::printf(
        "[ maps     ] %s: POV-Ray vs evaluator, analytic %.5f, map %.5f; POV-Ray map vs "
        "analytic %.5f\n",
        what, analytic_gap, map_gap, povray_twins);
    EXPECT_LT(map_gap, 1.5 * analytic_gap + 2e-3) << what;
    EXPECT_LT(povray_twins, 0.5 * analytic_gap + 2e-3) << what;
  }
  // A normal map has no scalar height for POV-Ray's normal patterns.
  const std::string normals = bake(path("n.exr"), MapKind::kNormal, 64);
  const RendererInfo& info = renderer_info(RendererKind::kPovray);
  EXPECT_FALSE(info.normal_maps);
  try {
    export_povray(map_scene({{"type", "normal-map"}, {"file", normals}}));
    ADD_FAILURE() << "POV-Ray exported a normal map";
  } catch (const ExportError& e) {
    EXPECT_NE(std::string(e.what()).find(info.normal_maps_why_not), std::string::npos);
  }
}

// The plane in POV-Ray, pixel by pixel against the evaluator (the same
// stratum centres, so the difference is the renderers', not noise):
// smooth, bump of the analytic grating and of its baked map, and the
// displaced grid. Bound: 1e-3 of albedo E / pi on the mean |difference|
// (POV-Ray's half-float output alone is 2.4e-4 relative; measured 4e-5),
// and at most 1 % of the pixels beyond 0.02. Reading the map's rows upside
// down gives 5.7e-3 on the height-map bump (tried).
TEST_F(ImageMaps, PovrayRendersThePlaneAsTheEvaluatorDoes) {
  const std::string plane =
      R"(/shape={"type": "plane", "axis": [0, 0, -1], "width": 2, "height": 2})";
  const Scene analytic = analytic_scene({plane});
  const Image baked = bake_surface_map(analytic.shape, analytic.height.function,
                                       analytic.height.amplitude, 256, 256, MapKind::kHeight);
  write_exr(baked, path("h.exr"));
  const json height_map{{"type", "height-map"}, {"file", path("h.exr")}, {"amplitude", 1}};
  const std::vector<std::pair<const char*, Scene>> cases{
      {"smooth", analytic_scene({plane, "/representation=smooth", "/camera/spp=16"})},
      {"analytic bump", analytic_scene({plane, "/camera/spp=16"})},
      {"height map bump", map_scene(height_map, {plane, "/camera/spp=16"})},
      {"height map bump, tiled 2 x 3, clamped edges", map_scene({{"type", "height-map"},
                                                                 {"file", path("h.exr")},
                                                                 {"amplitude", 0.5},
                                                                 {"tiles", {2, 3}},
                                                                 {"edge", "clamp"}},
                                                                {plane, "/camera/spp=16"})},
      {"height map, displaced grid",
       map_scene(height_map, {plane, "/camera/spp=16", "/representation=displacement",
                              "/displacement/edge_length=0.01"})}};
  RenderSettings settings;
  settings.log_path = path("povray.log");
  settings.timeout_s = 300;
  for (const auto& [what, scene] : cases) {
    const Image pov = render_with(RendererKind::kPovray, scene, settings).image;
    const Image eval = render(scene);
    const double unit = scene.material.albedo / kPi * scene.light.irradiance;
    double sum = 0.0;
    int covered = 0, far = 0;
    for (int j = 0; j < eval.height; ++j)
      for (int i = 0; i < eval.width; ++i) {
        if (eval.at(i, j, 3) < 1.0f || pov.at(i, j, 3) < 1.0f) continue;
        const double d = std::abs(double(pov.at(i, j, 0)) - eval.at(i, j, 0)) / unit;
        sum += d;
        ++covered;
        far += d > 0.02;
      }
    ASSERT_GT(covered, eval.width * eval.height / 2) << what;
    std::printf(
        "[ plane    ] %s: POV-Ray vs evaluator, mean |difference| %.6f, %d of %d pixels "
        "beyond 0.02\n",
        what, sum / covered, far, covered);
    EXPECT_LT(sum / covered, 1e-3) << what;
    EXPECT_LT(far, covered / 100 + 1) << what;
  }
}

// Blender renders an image map as the same surface its analytic twin is:
// the Image Texture's "Cubic" interpolation is the evaluator's B-spline, the
// mesh carries the evaluator's (u, v). Each map render must agree with the
// evaluator's render of the same map about as well as Blender's analytic
// render agrees with the evaluator's analytic one (the calibration's
// question), and with Blender's own analytic render within the map's error.
TEST_F(ImageMaps, BlenderRendersMapsAsTheEvaluatorDoes) {
  struct Case {
    const char* what;
    std::vector<std::string> sets;
    json height;
  };
  const std::string heights = bake(path("h.exr"), MapKind::kHeight, 512);
  const std::string normals = bake(path("n.exr"), MapKind::kNormal, 512);
  const json height_map{{"type", "height-map"}, {"file", heights}, {"amplitude", 1}};
  const std::vector<Case> cases{
      {"height map, raw bump", {"/terminator/method=none"}, height_map},
      {"height map, Bump node", {"/terminator/method=cycles34"}, height_map},
      {"normal map, Normal Map node",
       {"/terminator/method=cycles34"},
       {{"type", "normal-map"}, {"file", normals}}},
      {"height map, displaced mesh",
       {"/representation=displacement", "/displacement/edge_length=0.01"},
       height_map}};
  RenderSettings settings;
  settings.log_path = path("blender.log");
  settings.timeout_s = 300;
  for (const Case& c : cases) {
    std::vector<std::string> sets = c.sets;
    sets.push_back("/camera/spp=16");
    const Scene analytic = analytic_scene(sets);
    const Scene mapped = map_scene(c.height, sets);
    const double scale = radiance_scale(analytic);
    const auto profile = [&](const Image& image) { return terminator_profile(image, scale); };
    const Profile blender_analytic =
        profile(render_with(RendererKind::kBlender, analytic, settings).image);
    const Profile blender_map =
        profile(render_with(RendererKind::kBlender, mapped, settings).image);
    const Profile evaluator_analytic = profile(render(analytic));
    const Profile evaluator_map = profile(render(mapped));
    const double analytic_gap = compare_profiles(blender_analytic, evaluator_analytic).rmse_overall;
    const double map_gap = compare_profiles(blender_map, evaluator_map).rmse_overall;
    const double blender_twins = compare_profiles(blender_map, blender_analytic).rmse_overall;
    std::printf(
        "[ maps     ] %s: Blender vs evaluator, analytic %.5f, map %.5f; Blender map vs "
        "analytic %.5f\n",
        c.what, analytic_gap, map_gap, blender_twins);
    EXPECT_LT(map_gap, 1.5 * analytic_gap + 2e-3) << c.what;
    EXPECT_LT(blender_twins, 0.5 * analytic_gap + 2e-3) << c.what;
  }
  // Raw bump cannot take a normal map in Cycles: refused with the reason.
  try {
    export_blender(map_scene({{"type", "normal-map"}, {"file", normals}}));
    ADD_FAILURE() << "a raw-bump normal map was exported to Blender";
  } catch (const ExportError& e) {
    EXPECT_NE(std::string(e.what()).find("Normal Map node"), std::string::npos) << e.what();
  }
}

TEST_F(ImageMaps, CacheKeysFollowTheMapsContentNotItsPath) {
  const std::string file = bake(path("h.exr"), MapKind::kHeight, 64);
  auto job_for = [&](const std::string& f) {
    Job job;
    const nlohmann::json height = {{"type", "height-map"}, {"file", f}, {"amplitude", 1}};
    job.set_scene({{"height", height}}, map_scene(height), "test");
    return job;
  };
  std::filesystem::copy_file(file, path("moved.exr"));
  std::vector<Job> jobs{job_for(file), job_for(path("moved.exr"))};
  Image other = read_image(file);
  other.pixels[3] += 1e-4f;
  write_exr(other, path("edited.exr"));
  jobs.push_back(job_for(path("edited.exr")));
  assign_keys(jobs, {{RendererKind::kEvaluator, RendererIdentity{"penumbra test", "digest"}}});
  EXPECT_EQ(jobs[0].key, jobs[1].key);
  EXPECT_NE(jobs[0].key, jobs[2].key);
}

// bake --integrate: the cylinder's exact normal map, integrated, bumps the
// cylinder as the map does (the height a normal map stands for); the bump
// renders differ by the slope-averaging error alone: (omega tau)^2 / 12 =
// 0.8 % of the slope at this map's 20 texels a period (16 periods along
// the axis, 326 rows), so about that fraction of the bump's own contrast
// (measured 1.1 %; bound 2 %). A scene without a normal map is refused at
// /height/type, exit 2, nothing written.
TEST_F(ImageMaps, IntegratedNormalMapBumpsLikeTheMap) {
  const std::string source = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/cylinder-grating.json";
  const std::vector<std::string> along_v = {"--set", "/height/direction=[0,1,0]"};
  std::vector<std::string> bake_normal = {"bake",   source,   "--on", "shape", "--kind",
                                          "normal", "--size", "1024", "-o",    path("n.exr")};
  bake_normal.insert(bake_normal.end(), along_v.begin(), along_v.end());
  ASSERT_EQ(run_penumbra(bake_normal).code, 0);
  const CliResult refused = run_penumbra({"bake", source, "--integrate", "-o", path("no.exr")});
  EXPECT_EQ(refused.code, 2) << refused.err;
  EXPECT_NE(refused.err.find("/height/type"), std::string::npos) << refused.err;
  EXPECT_FALSE(std::filesystem::exists(path("no.exr")));
  json scene = read_json_file(source);
  scene["height"] = {{"type", "normal-map"}, {"file", path("n.exr")}};
  scene["representation"] = "bump";
  scene["camera"]["width"] = scene["camera"]["height"] = 64;
  std::ofstream(path("normal.json")) << scene.dump();
  const CliResult integrated =
      run_penumbra({"bake", path("normal.json"), "--integrate", "-o", path("h.exr")});
  ASSERT_EQ(integrated.code, 0) << integrated.err;
  EXPECT_NE(integrated.out.find("RMS"), std::string::npos) << integrated.out;
  std::printf("%s", integrated.out.c_str());
  const Image by_normals = render(scene_from_json(scene, "normal map"));
  scene["height"] = {{"type", "height-map"}, {"file", path("h.exr")}, {"amplitude", 1}};
  const Image by_heights = render(scene_from_json(scene, "integrated height map"));
  const Image flat = [&] {
    json plain = scene;
    plain["height"] = {{"type", "none"}};
    return render(scene_from_json(plain, "no height"));
  }();
  double differ = 0.0, contrast = 0.0;
  const std::size_t channels = by_normals.channels.size();
  for (std::size_t p = 0; p < by_normals.pixels.size(); p += channels) {
    differ += std::abs(by_normals.pixels[p] - by_heights.pixels[p]);
    contrast += std::abs(by_normals.pixels[p] - flat.pixels[p]);
  }
  std::printf("integrated height vs normal map: mean |difference| %.3g of the bump's own %.3g\n",
              differ, contrast);
  EXPECT_LT(differ, 0.02 * contrast);
}

TEST_F(ImageMaps, BakeOnTheShapeGivesAMapTheSceneReadsRelativeToItself) {
  const std::string source = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/cylinder-grating.json";
  const CliResult baked = run_penumbra({"bake", source, "--on", "shape", "--size", "128", "-o",
                                        path("h.exr"), "--set", "/height/direction=[0,1,0]"});
  ASSERT_EQ(baked.code, 0) << baked.err;
  EXPECT_NE(baked.out.find("128x41 over the cylinder"), std::string::npos) << baked.out;
  EXPECT_NE(baked.out.find(R"("type": "height-map")"), std::string::npos) << baked.out;
  const Image map = read_image(path("h.exr"));
  EXPECT_EQ(map.channels, std::vector<std::string>{"Y"});
  // The scene names the map relative to its own folder, and renders it from
  // any working directory.
  json scene = read_json_file(source);
  scene["height"] = {{"type", "height-map"}, {"file", "h.exr"}, {"amplitude", 1}};
  scene["camera"]["width"] = scene["camera"]["height"] = 16;
  std::ofstream(path("scene.json")) << scene.dump();
  const CliResult rendered = run_penumbra({"render", path("scene.json"), "-o", path("out.exr")});
  EXPECT_EQ(rendered.code, 0) << rendered.err;
  // A filtered render of it is the same scene to `compare --same-scene`.
  const CliResult filtered =
      run_penumbra({"render", path("scene.json"), "-o", path("filtered.exr"), "--set",
                    R"(/height/filter={"method": "pixar2014", "level": 3})"});
  EXPECT_EQ(filtered.code, 0) << filtered.err;
  const CliResult compared =
      run_penumbra({"compare", "--same-scene", path("out.exr"), path("filtered.exr")});
  EXPECT_EQ(compared.code, 0) << compared.err;
  EXPECT_EQ(compared.err.find("different scenes"), std::string::npos) << compared.err;
  // A bare scene file name lies in the working directory; absolute paths stay.
  json bare{{"height", {{"file", "maps/h.exr"}}}};
  resolve_map_files(bare, "scene.json");
  EXPECT_EQ(bare["height"]["file"], (std::filesystem::current_path() / "maps/h.exr").string());
  json absolute{{"height", {{"file", "/x/h.exr"}}}};
  resolve_map_files(absolute, "/y/scene.json");
  EXPECT_EQ(absolute["height"]["file"], "/x/h.exr");
  // A normal map needs the shape.
  const CliResult plane = run_penumbra({"bake", source, "--kind", "normal", "-o", path("n.exr")});
  EXPECT_EQ(plane.code, 2);
  EXPECT_NE(plane.err.find("--on shape"), std::string::npos) << plane.err;
}

}  // namespace
}  // namespace penumbra

namespace penumbra {
namespace {

// A glossy plane (GGX alpha 0.1, no diffuse) bumped by the shipped noise
// family (4 to 12 cycles per unit) baked into a 512 x 512 height map over
// its 2 x 2 units (21 texels or more per cycle), lit off the mirror
// direction so that the highlight lives in the lobe's tail, which is where
// filtered bumps must put energy back. A 32 x 32 view of `span` units
// shows 256 span / 32 texels a pixel.
class FilteredRender : public TempDirTest {
 protected:
  static constexpr int kMapSize = 512;
  static constexpr int kWidth = 32;

  std::vector<Override> base(double span) {
    std::vector<Override> sets;
    for (const std::string& s :
         {std::string(R"(/shape={"type": "plane", "axis": [0, 0, -1], "width": 2, "height": 2})"),
          std::string(R"(/material={"albedo": 0.8, "specular": {"weight": 1, "roughness": 0.1}})"),
          std::string("/light/direction=[0.3, 0, -1]"),
          "/camera/right=[" + std::to_string(span) + ", 0, 0]",
          "/camera/up=[0, " + std::to_string(span) + ", 0]",
          "/camera/width=" + std::to_string(kWidth), "/camera/height=" + std::to_string(kWidth)})
      sets.push_back(parse_override(s));
    return sets;
  }
  std::string map_file() {
    const std::string file = path("noise.exr");
    if (std::filesystem::exists(file)) return file;
    std::vector<Override> sets = base(2.0);
    const Scene noise =
        load_scene(std::string(PENUMBRA_SOURCE_DIR) + "/scenes/cylinder-noise.json", {sets[0]});
    write_exr(bake_surface_map(noise.shape, noise.height.function, noise.height.amplitude, kMapSize,
                               kMapSize, MapKind::kHeight),
              file);
    return file;
  }
  Image render_view(double texels_per_pixel, const json& filter, int spp) {
    std::vector<Override> sets = base(texels_per_pixel * kWidth * 2.0 / kMapSize);
    json height{{"type", "height-map"}, {"file", map_file()}, {"amplitude", 1}};
    if (!filter.is_null()) height["filter"] = filter;
    sets.push_back({"/height", height});
    sets.push_back(parse_override("/camera/spp=" + std::to_string(spp)));
    sets.push_back(parse_override(spp == 1 ? "/camera/jitter=false" : "/camera/jitter=true"));
    return render(load_scene(kScene, sets));
  }
  // Relative L1 error of the radiance against the reference.
  static double error(const Image& test, const Image& reference) {
    double diff = 0.0, total = 0.0;
    for (int j = 0; j < test.height; ++j)
      for (int i = 0; i < test.width; ++i) {
        diff += std::abs(double(test.at(i, j, 0)) - reference.at(i, j, 0));
        total += reference.at(i, j, 0);
      }
    return diff / total;
  }
};

TEST_F(FilteredRender, ConvergesToTheSupersampledReferenceAsTheLevelFallsToZero) {
  const json pixar{{"method", "pixar2014"}};
  double previous = 0.0;
  for (double texels_per_pixel : {16.0, 4.0, 1.0, 0.25}) {
    const Image reference = render_view(texels_per_pixel, nullptr, 256);
    const double filtered = error(render_view(texels_per_pixel, pixar, 1), reference);
    const double mip = error(render_view(texels_per_pixel, {{"method", "mip-only"}}, 1), reference);
    const double unfiltered = error(render_view(texels_per_pixel, nullptr, 1), reference);
    std::printf("%g texels/pixel: pixar2014 %.4f mip-only %.4f point-sampled %.4f\n",
                texels_per_pixel, filtered, mip, unfiltered);
    if (previous > 0.0) {
      EXPECT_LT(filtered, previous) << texels_per_pixel;
    }
    // Where a pixel covers many texels, filtering is what keeps the highlight.
    if (texels_per_pixel == 16.0) {
      EXPECT_LT(filtered, 0.5 * mip);
    }
    previous = filtered;
  }
  // Magnified, the filtered render is the map's own (the reference's pixel
  // average of a smooth field differs from its centre by a few per mille).
  EXPECT_LT(previous, 0.02);
}

TEST_F(FilteredRender, AConstantSlopeRendersTheSameThroughEveryFilterAtEveryLevel) {
  // A ramp along u with clamped edges: every footprint has the same slope
  // and no spread, so no filter may add roughness or move the normal.
  Image ramp;
  ramp.width = ramp.height = 64;
  ramp.channels = {"Y"};
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) ramp.pixels.push_back(0.002f * float(x));
  write_exr(ramp, path("ramp.exr"));
  const auto view = [&](const json& filter) {
    // The middle unit of the plane: at least 16 texels from its edges, where
    // the spline of a clamped ramp is still the ramp.
    std::vector<Override> sets = base(1.0);
    json height{
        {"type", "height-map"}, {"file", path("ramp.exr")}, {"amplitude", 1}, {"edge", "clamp"}};
    if (!filter.is_null()) height["filter"] = filter;
    sets.push_back({"/height", height});
    return render(load_scene(kScene, sets));
  };
  const Image plain = view(nullptr);
  double lit = 0.0;
  for (int j = 0; j < plain.height; ++j)
    for (int i = 0; i < plain.width; ++i) lit += plain.at(i, j, 0);
  ASSERT_GT(lit, 0.0);
  for (const RoughnessFilterInfo& info : all_roughness_filters()) {
    if (info.distribution == FilteredDistribution::kSchillingBlinnPhong) continue;
    // A GGX filter must give the material's own GGX lobe; a Beckmann one
    // (LEAN) its Beckmann lobe of the same alpha at every level.
    const Image same = info.distribution == FilteredDistribution::kGgx
                           ? plain
                           : view({{"method", std::string(info.id)}, {"level", 0}});
    for (const json& level : {json(nullptr), json(0), json(2.5), json(6)}) {
      json filter{{"method", std::string(info.id)}};
      if (!level.is_null()) filter["level"] = level;
      const Image filtered = view(filter);
      for (int j = 0; j < plain.height; ++j)
        for (int i = 0; i < plain.width; ++i)
          ASSERT_NEAR(filtered.at(i, j, 0), same.at(i, j, 0), 1e-4 * same.at(i, j, 0) + 1e-7)
              << info.id << " level " << level << " pixel " << i << "," << j;
    }
  }
}

TEST_F(FilteredRender, OnlyBumpSamplesAreFilteredAndSchillingsLobeIsRefused) {
  const json filter{{"method", "pixar2014"}, {"level", 4}};
  for (const char* representation : {"smooth", "displacement"}) {
    const auto view = [&](const json& f) {
      std::vector<Override> sets = base(2.0);
      json height{{"type", "height-map"}, {"file", map_file()}, {"amplitude", 1}};
      if (!f.is_null()) height["filter"] = f;
      sets.push_back({"/height", height});
      sets.push_back(parse_override(std::string("/representation=") + representation));
      sets.push_back(parse_override("/displacement/edge_length=0.02"));
      return render(load_scene(kScene, sets));
    };
    const Image with = view(filter), without = view(nullptr);
    EXPECT_EQ(with.pixels, without.pixels) << representation;
  }
  std::vector<Override> sets = base(2.0);
  sets.push_back({"/height",
                  {{"type", "height-map"},
                   {"file", map_file()},
                   {"amplitude", 1},
                   {"filter", {{"method", "schilling1997"}}}}});
  try {
    load_scene(kScene, sets);
    ADD_FAILURE() << "schilling1997 was accepted for rendering";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/height/filter/method"), std::string::npos) << e.what();
  }
}

TEST_F(FilteredRender, ANormalMapFiltersLikeTheHeightMapOfTheSameSurface) {
  // The normal map holds the exact slopes where the height map's pyramid
  // takes central differences (a slope factor sin(w t) / (w t) >= 0.985 at
  // 21 texels a cycle): the two filtered renders agree far closer than
  // either agrees with the reference.
  std::vector<Override> sets = base(2.0);
  const Scene noise =
      load_scene(std::string(PENUMBRA_SOURCE_DIR) + "/scenes/cylinder-noise.json", {sets[0]});
  write_exr(bake_surface_map(noise.shape, noise.height.function, noise.height.amplitude, kMapSize,
                             kMapSize, MapKind::kNormal),
            path("noise-normal.exr"));
  for (double texels_per_pixel : {16.0, 4.0}) {
    const double span = texels_per_pixel * kWidth * 2.0 / kMapSize;
    const auto view = [&](const json& height) {
      std::vector<Override> s = base(span);
      s.push_back({"/height", height});
      s.push_back(parse_override("/camera/spp=1"));
      s.push_back(parse_override("/camera/jitter=false"));
      return render(load_scene(kScene, s));
    };
    const json filter{{"method", "pixar2014"}};
    const Image from_heights =
        view({{"type", "height-map"}, {"file", map_file()}, {"amplitude", 1}, {"filter", filter}});
    const Image from_normals =
        view({{"type", "normal-map"}, {"file", path("noise-normal.exr")}, {"filter", filter}});
    const Image reference = render_view(texels_per_pixel, nullptr, 256);
    const double between = error(from_normals, from_heights);
    std::printf("%g texels/pixel: normal vs height %.4f, height vs reference %.4f\n",
                texels_per_pixel, between, error(from_heights, reference));
    EXPECT_LT(between, 0.5 * error(from_heights, reference)) << texels_per_pixel;
  }
}

}  // namespace
}  // namespace penumbra
