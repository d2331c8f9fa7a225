// The renderer interface and registry (cpp/renderers/) and what holds across
// renderers: errors of external ones, the same silhouettes and low-poly
// profiles, what each refuses, the calibration.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>

#include "analysis/metrics.h"
#include "fake_blender.h"
#include "renderers/code_digest.h"
#include "renderers/external/blender/blender.h"
#include "renderers/external/povray/povray.h"
#include "renderers/renderers_test.h"
#include "study/calibration.h"
#include "util/process.h"

namespace penumbra::renderer_test {
namespace {

// The registry: each enumerator has an entry with an id of its own that
// round-trips; an external renderer has an executable, an export, a version
// marker and a digest of its own code, the evaluator none of them.
TEST(RendererRegistry, EveryRendererHasAnEntryWithItsOwnIdAndCode) {
  ASSERT_GE(all_renderers().size(), 3u);
  EXPECT_EQ(all_renderers().front(), RendererKind::kEvaluator);
  std::set<std::string> ids, digests;
  for (RendererKind r : all_renderers()) {
    const RendererEntry& entry = renderer(r);
    const RendererInfo& info = entry.info;
    EXPECT_TRUE(ids.insert(info.id).second) << info.id;
    EXPECT_EQ(renderer_from_id(info.id), r) << info.id;
    EXPECT_TRUE(entry.render && entry.version && entry.pixel_code_digest &&
                entry.estimate_resources)
        << info.id;
    EXPECT_EQ(info.external(), entry.export_files != nullptr) << info.id;
    if (!info.external()) continue;
    EXPECT_NE(*info.debian_package, '\0') << info.id;
    EXPECT_NE(*info.version_marker, '\0') << info.id;
    EXPECT_NE(*entry.export_file, '\0') << info.id;
    EXPECT_TRUE(digests.insert(external_code_digest(info.id)).second) << info.id;
  }
  EXPECT_THROW(external_code_digest("evaluator"), std::logic_error);
  // An enumerator past the registry's rows is a programming error, not a
  // renderer with an empty entry.
  EXPECT_THROW(renderer(static_cast<RendererKind>(all_renderers().size())), std::logic_error);
}

TEST_F(Renderers, MissingRendererNamesTheDebianPackage) {
  RenderSettings settings;
  settings.log_path = path("out.log");
  settings.executable = "penumbra-no-such-renderer";
  try {
    render_with(RendererKind::kPovray, hostile_scene(), settings);
    FAIL() << "expected RendererError";
  } catch (const RendererError& e) {
    EXPECT_NE(std::string(e.what()).find("apt-get install povray"), std::string::npos) << e.what();
  }
  settings.executable = "penumbra-no-such-renderer";
  try {
    render_with(RendererKind::kBlender, hostile_scene(), settings);
    FAIL() << "expected RendererError";
  } catch (const RendererError& e) {
    EXPECT_NE(std::string(e.what()).find("apt-get install blender"), std::string::npos) << e.what();
  }
}

TEST_F(Renderers, FailingRendererReportsTheLogTailAndLeavesNoImage) {
  RenderSettings settings;
  settings.log_path = path("render.log");
  settings.executable =
      fake("povray", "echo first line; echo 'Parse Error: something broke' >&2; exit 3");
  try {
    render_with(RendererKind::kPovray, hostile_scene(), settings);
    FAIL() << "expected RendererError";
  } catch (const RendererError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("exited with status 3"), std::string::npos) << what;
    EXPECT_NE(what.find("Parse Error: something broke"), std::string::npos) << what;
    EXPECT_NE(what.find(settings.log_path), std::string::npos) << what;
  }
  // The log and the kept work folder (for rerunning by hand), no image.
  for (const std::string& f : files()) EXPECT_EQ(f.find(".exr"), std::string::npos) << f;
  EXPECT_NE(tail_lines(settings.log_path, 5).find("first line"), std::string::npos);
}

TEST_F(Renderers, HangingRendererIsKilledAtTheTimeout) {
  RenderSettings settings;
  settings.log_path = path("render.log");
  settings.timeout_s = 0.5;
  settings.executable = path("blender");
  std::ofstream(settings.executable) << fake_blender_text("echo started; sleep 60");
  ::chmod(settings.executable.c_str(), 0755);
  try {
    render_with(RendererKind::kBlender, hostile_scene(), settings);
    FAIL() << "expected RendererError";
  } catch (const RendererError& e) {
    EXPECT_NE(std::string(e.what()).find("timed out"), std::string::npos) << e.what();
  }
}

TEST_F(Renderers, RendererExitingZeroWithoutAnImageIsAFailure) {
  RenderSettings settings;
  settings.log_path = path("render.log");
  settings.executable = fake("povray", "echo pretending to render; exit 0");
  EXPECT_THROW(render_with(RendererKind::kPovray, hostile_scene(), settings), RendererError);
}

// The exporters convert coordinates (POV-Ray: canonical frame + matrix;
// Blender: y <-> z swap, camera matrix): an off-centre, tilted cylinder seen
// through a perspective camera, in a non-square image, must have the same
// silhouette in all three renderers.
TEST_F(Renderers, SilhouettesCoincideAcrossRenderers) {
  json doc = calibration_scene("cylinder");
  doc["camera"] = {{"projection", "perspective"},
                   {"position", {0.3, 0.2, -6}},
                   {"direction", {0, 0, 2.0}},
                   {"right", {1.2, 0, 0}},
                   {"up", {0, 0.8, 0}},
                   {"width", 96},
                   {"height", 64},
                   {"spp", 4},
                   {"jitter", false}};
  doc["shape"] = {{"type", "cylinder"},      {"center", {0.4, -0.1, 0.3}},
                  {"axis", {0.3, 0.9, 0.2}}, {"radius", 0.7},
                  {"height", 1.6},           {"caps", true}};
  doc["representation"] = "smooth";
  const Scene scene = scene_from_json(doc, "<tilted>");
  const Image reference = render(scene);
  for (RendererKind r : {RendererKind::kPovray, RendererKind::kBlender}) {
    RenderSettings settings;
    settings.log_path = path(std::string(to_string(r)) + ".log");
    settings.timeout_s = 300;
    const RendererRun run = render_with(r, scene, settings);
    const ImageMetrics m = compare_images(run.image, reference);
    // About 300 silhouette pixels of some 2600 covered; coverage near 0.5
    // decides a few of them either way.
    EXPECT_GE(m.mask_iou, 0.99) << to_string(r);
    EXPECT_GT(m.pixels, 1500u) << to_string(r);
    // Lit interior agrees (Cycles: a few % is sampling noise at 4 spp).
    EXPECT_LT(std::abs(m.mean_error), 0.01 * m.reference_mean) << to_string(r);
  }
}

TEST_F(Renderers, FlatShadedLowPolyMatchesTheEvaluator) {
  // Flat faces: Cycles shades with Ng and applies no geometry offset (it
  // needs smooth faces), the evaluator's offset is zero on a flat triangle.
  const std::string flat = "/shape/tessellation/shading=flat";
  const Scene pov_scene = lowpoly_sphere({"/camera/spp=4", "/camera/jitter=false", flat});
  EXPECT_EQ(export_povray(pov_scene).sdl.find("normal_vectors"), std::string::npos);
  // Facet edges are radiance steps that pixel samples straddle: measured
  // against the evaluator, 6.6e-4 at 16 spp, 4.3e-4 at 64, 6.8e-5 at 256.
  const Scene cycles_scene = lowpoly_sphere(
      {"/camera/spp=256", flat, R"(/offset={"method": "cycles-geometry-offset", "cutoff": 0.1})"});
  EXPECT_EQ(json::parse(export_blender(cycles_scene).job_json).at("mesh").at("faces"), "flat");
  for (const auto& [r, scene] : {std::pair{RendererKind::kPovray, pov_scene},
                                 std::pair{RendererKind::kBlender, cycles_scene}}) {
    RenderSettings settings;
    settings.log_path = path(std::string(to_string(r)) + ".log");
    settings.timeout_s = 120;
    const RendererRun run = render_with(r, scene, settings);
    const double scale = radiance_scale(scene);
    const ProfileMetrics m = compare_profiles(terminator_profile(run.image, scale),
                                              terminator_profile(render(scene), scale));
    std::printf("[ lowpoly  ] flat %s vs evaluator: profile RMSE terminator %.6f overall %.6f\n",
                to_string(r), m.rmse_terminator, m.rmse_overall);
    // As for smooth shading above: 1e-3 is ~15x what was measured (POV-Ray
    // 9e-6, Cycles 6.8e-5) and well below a one-stair shift (7.5e-3).
    EXPECT_LT(m.rmse_terminator, 1e-3) << to_string(r);
  }
}

TEST(LowPolyExport, RenderersRefuseWhatTheyCannotExpress) {
  auto refused = [](auto export_fn, const Scene& scene, std::vector<std::string> words) {
    try {
      export_fn(scene);
      ADD_FAILURE() << "expected ExportError";
    } catch (const ExportError& e) {
      for (const std::string& w : words)
        EXPECT_NE(std::string(e.what()).find(w), std::string::npos) << e.what();
    }
  };
  const auto pov = [](const Scene& s) { return export_povray(s); };
  const auto cycles = [](const Scene& s) { return export_blender(s); };
  refused(pov, lowpoly_sphere({R"(/offset={"method": "hanika2021"})"}),
          {"hanika2021", "only `none`"});
  refused(cycles, lowpoly_sphere({R"(/offset={"method": "gist2020"})"}),
          {"gist2020", "`none` and `cycles-geometry-offset`"});
  const std::string prop = R"(/props=[{"type": "sphere", "center": [1.2, 0, 0], "radius": 0.1}])";
  refused(pov, lowpoly_sphere({prop}), {"props are evaluator-only"});
  refused(cycles, lowpoly_sphere({prop}), {"props are evaluator-only"});
  refused(pov, lowpoly_sphere({"/shape/tessellation=null", prop}), {"props are evaluator-only"});
  // Consistent normal interpolation is view-dependent shading neither has.
  const std::string consistent = "/shape/tessellation/shading=consistent";
  refused(pov, lowpoly_sphere({consistent}), {"no view-dependent shading normal"});
  refused(cycles, lowpoly_sphere({consistent}), {"no consistent normal interpolation"});
  // Bump on a mesh: neither renderer's bump is the evaluator's (see export).
  const Scene bumped = lowpoly_sphere(
      {"/representation=bump",
       R"(/height={"type": "grating", "amplitude": 0.01, "frequency": 8, "direction": [1, 0, 0]})"});
  refused(pov, bumped, {"bump on a tessellated shape"});
  refused(cycles, bumped, {"bump on a tessellated shape"});

  // What each renderer offers, for studies.
  EXPECT_EQ(offsets_offered(RendererKind::kPovray), std::vector<OffsetMethod>{OffsetMethod::kNone});
  EXPECT_EQ(offsets_offered(RendererKind::kBlender),
            (std::vector<OffsetMethod>{OffsetMethod::kNone, OffsetMethod::kCyclesGeometryOffset}));
  EXPECT_EQ(offsets_offered(RendererKind::kEvaluator).size(), all_offset_methods().size());
  // Accepted offsets export: POV-Ray gets the mesh's own triangles.
  const Scene smooth = lowpoly_sphere({});
  const std::string sdl = export_povray(smooth).sdl;
  EXPECT_NE(sdl.find("mesh2 {"), std::string::npos);
  EXPECT_NE(sdl.find("normal_vectors {\n    114,"), std::string::npos);
  EXPECT_NE(sdl.find("face_indices {\n    224,"), std::string::npos);
  EXPECT_EQ(sdl.find("sphere {"), std::string::npos);
}

// The calibration set and its bounds (renderer issue): these are the same
// cases `penumbra calibrate` renders.
TEST_F(Renderers, CalibrationMeetsEveryBound) {
  CalibrationOptions options;
  options.output_dir = dir_.string();
  options.scenes_dir = kSource + "/scenes/calibration";
  options.parallelism = resolve_parallelism(2);
  options.timeout_s = 600;
  const CalibrationResult result = run_calibration(options);
  for (const CalibrationRender& r : result.renders)
    EXPECT_TRUE(r.error.empty()) << r.label << ": " << r.error;
  int checks = 0;
  for (const CalibrationRow& row : result.rows) {
    EXPECT_TRUE(row.missing.empty()) << row.missing;
    for (const CalibrationCheck& c : row.checks) {
      ++checks;
      EXPECT_TRUE(c.pass) << row.shape << " " << row.representation << " " << row.test << " vs "
                          << row.reference << ": " << c.name << " = " << c.value << ", bound "
                          << c.bound;
    }
  }
  // 2 shapes x (smooth 2x2 + bump 1 + displacement 3) checks.
  EXPECT_EQ(checks, 2 * (4 + 1 + 3));
  // Cycles' footprint-differenced bump: its residual against the analytic
  // bump falls as the footprint shrinks (the explanation in the report).
  for (const char* shape : {"cylinder", "sphere"}) {
    double previous = INFINITY;
    for (const char* rep : {"bump", "bump x2", "bump x4"})
      for (const CalibrationRow& row : result.rows)
        if (row.shape == shape && row.representation == rep && row.test == "blender:none") {
          EXPECT_LT(row.image.rmse, previous) << shape << " " << rep;
          previous = row.image.rmse;
        }
  }
  write_calibration_reports(result, dir_.string());
  const json report = read_json_file(path("calibration.json"));
  EXPECT_EQ(report.at("rows").size(), result.rows.size());
  EXPECT_TRUE(report.at("all_pass").get<bool>());
}

}  // namespace
}  // namespace penumbra::renderer_test
