// POV-Ray 3.7 (cpp/renderers/external/povray/): its SDL is inert whatever
// the scene, its renders match the evaluator's, its box filter.
#include <gtest/gtest.h>

#include <cctype>
#include <cstdio>
#include <cstring>
#include <regex>
#include <sstream>
#include <string>

#include "analysis/metrics.h"
#include "renderers/external/povray/povray.h"
#include "renderers/renderers_test.h"
#include "small_sphere.h"

namespace penumbra::renderer_test {
namespace {

TEST_F(Renderers, PovraySdlIsInertWhateverTheSceneName) {
  const PovrayExport job = export_povray(hostile_scene());
  EXPECT_EQ(job.sdl.find("#include"), std::string::npos);
  EXPECT_EQ(job.sdl.find("#declare Evil"), std::string::npos);
  EXPECT_EQ(job.sdl.find("passwd\""), std::string::npos);
  // Every directive is one the exporter writes itself.
  std::istringstream lines(job.sdl);
  std::string line;
  int comment_lines = 0;
  while (std::getline(lines, line)) {
    if (line.rfind("//", 0) == 0) {
      ++comment_lines;
      continue;
    }
    if (line.rfind("#", 0) == 0) {
      bool known = false;
      for (const char* own : {"#version 3.7;", "#declare Penumbra_H", "#declare Penumbra_B = "})
        known = known || line.rfind(own, 0) == 0;
      EXPECT_TRUE(known) << line;
    }
  }
  EXPECT_GE(comment_lines, 1);
  // The name survives only reduced to the safe set, inside the first comment.
  EXPECT_NE(job.sdl.find(comment_safe(hostile_scene().name)), std::string::npos);
  for (char c : comment_safe(hostile_scene().name))
    EXPECT_TRUE(std::isalnum(c) || std::strchr(" _.+-", c)) << c;
}

// POV-Ray's function VM folds nothing and an isosurface calls its function
// tens of millions of times: the SDL computes |q| once per call and writes
// no factor that changes no bit (a zero coefficient, a weight 1, a phase 0).
// That it renders the same pixels as the unreduced functions was checked on
// every scene in scenes/ (idiff max error 0; README, POV-Ray's isosurface);
// the calibration checks it against the evaluator.
TEST(PovrayExport, FunctionsComputeTheRadiusOnceAndNoVoidTerms) {
  for (const char* representation : {"displacement", "bump"}) {
    json doc = read_json_file(kSource + "/scenes/sphere-grating.json");
    doc["representation"] = representation;
    std::istringstream lines(export_povray(scene_from_json(doc, "<functions>")).sdl);
    std::string sdl, line;  // without the comment lines
    while (std::getline(lines, line))
      if (line.rfind("//", 0) != 0) sdl += line + "\n";
    std::size_t roots = 0;
    for (std::size_t at = sdl.find("sqrt("); at != std::string::npos;
         at = sdl.find("sqrt(", at + 1))
      ++roots;
    EXPECT_EQ(roots, 1u) << representation << "\n" << sdl;
    EXPECT_FALSE(std::regex_search(sdl, std::regex(R"((^|[^0-9.e])(0|1)\*)"))) << sdl;
    EXPECT_NE(sdl.find("#declare Penumbra_H = function(x, y, z) {\n    sin("), std::string::npos)
        << sdl;
  }
}

TEST_F(Renderers, PovrayRendersTheHostileSceneAsAPlainCylinder) {
  RenderSettings settings;
  settings.log_path = path("hostile.log");
  settings.timeout_s = 120;
  const RendererRun run = render_with(RendererKind::kPovray, hostile_scene(), settings);
  const Image reference = render(hostile_scene());
  const ImageMetrics m = compare_images(run.image, reference);
  EXPECT_GT(m.pixels, 100u);
  EXPECT_GE(m.mask_iou, 0.99);
}

TEST(BoxDownsample, AveragesEachBlockInFixedOrder) {
  Image big;
  big.width = 4, big.height = 2;
  big.channels = {"R"};
  big.pixels = {1, 2, 3, 4, 5, 6, 7, 8};
  const Image small = box_downsample(big, 2, 2);
  ASSERT_EQ(small.width, 2);
  ASSERT_EQ(small.height, 1);
  EXPECT_FLOAT_EQ(small.at(0, 0, 0), (1 + 2 + 5 + 6) / 4.0f);
  EXPECT_FLOAT_EQ(small.at(1, 0, 0), (3 + 4 + 7 + 8) / 4.0f);
}

// Fully covered pixels that the reference lights (at least kDarkLevel of
// albedo E / pi) and the test renders below half of that: the stair steps
// (the definition of ShadowMetrics::darkened_pixels, restricted to a band of
// theta).
struct DarkenedPixels {
  std::size_t lit = 0, darkened = 0;
  double fraction() const { return lit ? double(darkened) / double(lit) : 0.0; }
};
DarkenedPixels darkened_pixels(const Image& test, const Image& reference, double scale,
                               double theta_begin, double theta_end) {
  DarkenedPixels d;
  const int theta = reference.channel_index("analysis.theta");
  for (int y = 0; y < reference.height; ++y)
    for (int x = 0; x < reference.width; ++x) {
      if (reference.at(x, y, 3) < 0.999f || test.at(x, y, 3) < 0.999f) continue;
      const double t = reference.at(x, y, theta);
      if (t < theta_begin || t >= theta_end || reference.at(x, y, 0) < kDarkLevel * scale) continue;
      ++d.lit;
      if (test.at(x, y, 0) < 0.5f * reference.at(x, y, 0)) ++d.darkened;
    }
  return d;
}

// POV-Ray's mesh2 with normal_vectors shows the shadow line artifact and has
// no fix (reference sheet, section 6): it must match the evaluator's `none`
// on the same triangles, stair steps included.
TEST_F(Renderers, PovrayLowPolyMeshMatchesTheEvaluatorsStairSteps) {
  // Stratum centres (jitter off) are exactly POV-Ray's samples, so both see
  // the same rays: what remains is POV-Ray's half-float EXR and its own
  // shadow tolerances.
  const Scene scene = lowpoly_sphere({"/camera/spp=4", "/camera/jitter=false"});
  ASSERT_TRUE(scene.tessellation);
  RenderSettings settings;
  settings.log_path = path("povray.log");
  settings.timeout_s = 120;
  const RendererRun run = render_with(RendererKind::kPovray, scene, settings);
  const Image evaluator = render(scene);
  const double scale = radiance_scale(scene);
  const Profile pov = terminator_profile(run.image, scale);
  const ProfileMetrics m = compare_profiles(pov, terminator_profile(evaluator, scale));
  // Measured 3.9e-5 (96x96, 4 spp): POV-Ray's half-float EXR rounds each
  // pixel by ~3e-4 relative (RMS), averaged over the ~30 pixels of a bin.
  // Moving the terminator by one stair (the Cycles offset of 0.1 below) costs
  // 7.5e-3, so 1e-3 is both far above the noise and far below a real change.
  EXPECT_LT(m.rmse_terminator, 1e-3);
  EXPECT_GE(m.common_bins, 100u);
  EXPECT_NEAR(m.position_error, 0.0, 0.25);
  std::printf("[ lowpoly  ] povray vs evaluator none: profile RMSE terminator %.6f overall %.6f\n",
              m.rmse_terminator, m.rmse_overall);

  // The artifact is there: against the analytic sphere, the mesh leaves dark
  // what the smooth sphere lights just before its terminator, where the light
  // is below a flat triangle (dot(Ng, wi) < 0) but above Ni. A facet of the
  // 16-segment sphere tilts at most ~16 degrees from the surface normal at
  // its points, so the steps lie past ~75 degrees: the band counted here.
  Scene analytic_scene = scene;
  analytic_scene.tessellation.reset();
  const Image analytic = render(analytic_scene);
  const DarkenedPixels all = darkened_pixels(run.image, analytic, scale, 0.0, 180.0);
  const DarkenedPixels band = darkened_pixels(run.image, analytic, scale, 75.0, 90.0);
  // The same mesh with Cycles' offset: the steps are the mesh's shadow rays.
  Scene offset_scene = scene;
  offset_scene.offset.method = OffsetMethod::kCyclesGeometryOffset;
  const DarkenedPixels fixed = darkened_pixels(render(offset_scene), analytic, scale, 75.0, 90.0);
  const ProfileMetrics artifact = compare_profiles(pov, terminator_profile(analytic, scale));
  std::printf(
      "[ lowpoly  ] povray mesh vs analytic: %zu/%zu lit pixels dark (%.3f), theta [75, 90): "
      "%zu/%zu (%.3f), evaluator with cycles-geometry-offset %zu/%zu (%.3f); profile RMSE "
      "terminator %.6f\n",
      all.darkened, all.lit, all.fraction(), band.darkened, band.lit, band.fraction(),
      fixed.darkened, fixed.lit, fixed.fraction(), artifact.rmse_terminator);
  // Measured 62 of 613 (0.101), 2.5% of every lit pixel; with the offset 0.
  EXPECT_GT(band.fraction(), 0.05);
  EXPECT_LT(fixed.fraction(), band.fraction() / 3);
  EXPECT_GT(artifact.rmse_terminator, 20 * m.rmse_terminator);
}

// A mesh shape in POV-Ray. Its smooth triangles against the evaluator's
// `none` (both start shadow rays on the flat triangle). Its truth against
// the evaluator rendering the very triangles and normals POV-Ray is given
// as a smooth mesh (exported_truth_as_mesh), which checks the export;
// against the evaluator's own truth (exact normals at each hit, shadow rays
// from the curved surface) POV-Ray's differs by its sub-triangles' own
// terminator, which shrinks with the edge length: printed, measured in
// docs/renderers.md. Bump is refused, saying why.
TEST_F(Renderers, PovrayRendersAMeshShapeAndItsTruthLikeTheEvaluator) {
  RenderSettings settings;
  settings.log_path = path("povray.log");
  settings.timeout_s = 300;
  const Scene smooth = mesh_sphere(path("sphere.ply"), "smooth");
  const double scale = radiance_scale(smooth);
  // Measured 5e-6 for both (96 x 96, 4 spp): POV-Ray's half-float EXR
  // (3.9e-5 on the low-poly sphere above); a wrong normal or vertex moves
  // the terminator by a stair, 7.5e-3 there.
  const Image smooth_evaluator = render(smooth);
  EXPECT_LT(mesh_profile_rmse(render_with(RendererKind::kPovray, smooth, settings).image,
                              smooth_evaluator, scale, "povray vs evaluator, smooth"),
            2e-4);
  const json truth_doc = mesh_sphere_doc(path("sphere.ply"), "displacement");
  const Scene truth = scene_from_json(truth_doc, "mesh sphere");
  const Image povray_truth = render_with(RendererKind::kPovray, truth, settings).image;
  const Image evaluator_truth = render(truth);
  const Image triangles = with_analysis_of(
      render(exported_truth_as_mesh(truth_doc, path("truth.ply"))), evaluator_truth);
  EXPECT_LT(mesh_profile_rmse(povray_truth, triangles, scale,
                              "povray truth vs the evaluator on its triangles"),
            2e-4);
  mesh_profile_rmse(povray_truth, evaluator_truth, scale, "povray truth vs the evaluator's truth");
  // The test tells a truth from the smooth mesh.
  EXPECT_GT(mesh_profile_rmse(smooth_evaluator, evaluator_truth, scale, "smooth vs truth"), 1e-2);
  try {
    export_povray(mesh_sphere(path("sphere.ply"), "bump"));
    ADD_FAILURE() << "bump on a mesh shape was exported";
  } catch (const ExportError& e) {
    EXPECT_NE(std::string(e.what()).find("mesh shape"), std::string::npos) << e.what();
  }
}

// A group of lights, even of distant ones, is refused with the reason.
TEST(PovrayExport, RefusesAGroupOfLights) {
  const Scene scene = sphere_grating_with({R"(/light={"type": "group", "lights": [
            {"type": "distant", "direction": [-1, 0, 0], "irradiance": 1},
            {"type": "distant", "direction": [0, 1, 0], "irradiance": 1}]})"});
  try {
    export_povray(scene);
    ADD_FAILURE() << "a group of lights was exported";
  } catch (const ExportError& e) {
    EXPECT_NE(std::string(e.what()).find("one distant light only"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace penumbra::renderer_test
