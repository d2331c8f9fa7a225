// Exporters, external renderers and calibration. POV-Ray and Blender must be
// installed (the quick start and CI install them): a missing renderer fails
// these tests, it is never skipped as a pass.
#include <gtest/gtest.h>

#include "temp_dir_test.h"

#include <sys/stat.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "analysis/metrics.h"
#include "export/export.h"
#include "render/image_io.h"
#include "renderers/process.h"
#include "renderers/renderers.h"
#include "report/calibration.h"
#include "scene/scene_json.h"

namespace penumbra {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kSource = PENUMBRA_SOURCE_DIR;

class Renderers : public TempDirTest {
 protected:
  // A shell script standing in for a renderer.
  std::string fake(const std::string& name, const std::string& body) const {
    const std::string p = path(name);
    std::ofstream(p) << "#!/bin/sh\n" << body << "\n";
    ::chmod(p.c_str(), 0755);
    return p;
  }
  std::vector<std::string> files() const {
    std::vector<std::string> found;
    for (const auto& e : fs::directory_iterator(dir_))
      found.push_back(e.path().filename().string());
    std::sort(found.begin(), found.end());
    return found;
  }
};

json calibration_scene(const std::string& shape) {
  return read_json_file(kSource + "/scenes/calibration/" + shape + ".json");
}

// A scene whose name tries every way out of a comment or a string.
Scene hostile_scene() {
  json doc = calibration_scene("cylinder");
  doc["name"] =
      "x\" }\n#include \"/etc/passwd\"\n#declare Evil = 1; // ';\n__import__('os').system('id')";
  doc["representation"] = "bump";
  doc["camera"]["width"] = 32;
  doc["camera"]["height"] = 32;
  return scene_from_json(doc, "<hostile>");
}

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
      EXPECT_TRUE(line.rfind("#version 3.7;", 0) == 0 || line.rfind("#declare Penumbra_H", 0) == 0)
          << line;
    }
  }
  EXPECT_GE(comment_lines, 1);
  // The name survives only reduced to the safe set, inside the first comment.
  EXPECT_NE(job.sdl.find(comment_safe(hostile_scene().name)), std::string::npos);
  for (char c : comment_safe(hostile_scene().name))
    EXPECT_TRUE(std::isalnum(c) || std::strchr(" _.+-", c)) << c;
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

TEST_F(Renderers, BlenderJobCarriesNoSceneStringsAndTheScriptRejectsCode) {
  const BlenderExport job = export_blender(hostile_scene());
  EXPECT_EQ(job.job_json.find("passwd"), std::string::npos);
  EXPECT_EQ(job.job_json.find("import"), std::string::npos);
  // A job whose enum fields carry code is refused by the fixed script, and
  // the code does not run.
  json bad = json::parse(job.job_json);
  const std::string marker = path("pwned");
  bad["shading"]["mode"] = "__import__('os').system('touch " + marker + "')";
  std::ofstream(path("job.json")) << bad.dump();
  for (const char* f : {kBlenderPositionsFile, kBlenderNormalsFile, kBlenderTrianglesFile})
    std::ofstream(path(f)) << "";
  const auto blender = find_executable("blender");
  ASSERT_TRUE(blender) << "blender is not installed (apt-get install blender)";
  const ProcessResult p =
      run_process({*blender, "-b", "--factory-startup", "-noaudio", "--python-exit-code", "1",
                   "--python", kSource + "/harness/blender_render.py", "--", "job.json", "out.exr"},
                  dir_.string(), path("blender.log"), 120);
  EXPECT_FALSE(p.ok());
  EXPECT_FALSE(fs::exists(marker));
  EXPECT_FALSE(fs::exists(path("out.exr")));
  EXPECT_NE(tail_lines(path("blender.log"), 20).find("/shading/mode"), std::string::npos)
      << tail_lines(path("blender.log"), 20);
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
  settings.executable = fake("blender", "echo started; sleep 60");
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

// The calibration set and its bounds (renderer issue): these are the same
// cases `penumbra calibrate` renders.
TEST_F(Renderers, CalibrationMeetsEveryBound) {
  CalibrationOptions options;
  options.output_dir = dir_.string();
  options.scenes_dir = kSource + "/scenes/calibration";
  options.jobs = 2;
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
}  // namespace penumbra
