// The command line: exit codes, messages, and no half-written output.
#include <gtest/gtest.h>

#include "cli_test.h"
#include "temp_dir_test.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli/cli.h"
#include "image/image_io.h"
#include "scene/mesh_file.h"

namespace penumbra {
namespace {

namespace fs = std::filesystem;

const std::string kScenes = std::string(PENUMBRA_SOURCE_DIR) + "/scenes";

using Result = CliResult;

Result run(std::vector<std::string> args) {
  return run_penumbra(std::move(args));
}

class Cli : public TempDirTest {
 protected:
  // Nothing but the files named may exist: no temporary left behind either.
  void expect_only(const std::vector<std::string>& names) const {
    std::vector<std::string> found;
    for (const auto& e : fs::directory_iterator(dir_))
      found.push_back(e.path().filename().string());
    std::sort(found.begin(), found.end());
    std::vector<std::string> expected = names;
    std::sort(expected.begin(), expected.end());
    EXPECT_EQ(found, expected);
  }
  // sphere-grating.exr and cylinder-grating.exr, 16x16 at 1 spp: two
  // different scenes to compare.
  void render_sphere_and_cylinder() {
    for (const char* scene : {"sphere-grating", "cylinder-grating"})
      ASSERT_EQ(
          run({"render", kScenes + "/" + scene + ".json", "-o", path(std::string(scene) + ".exr"),
               "--width", "16", "--height", "16", "--spp", "1"})
              .code,
          kExitOk);
  }
};

// figure and table run harness/report.py on a finished study: a folder and
// an output given relative to where the user stands resolve from there, not
// from wherever the script runs (they once resolved from the temporary
// folder, and `penumbra figure results/default` found no report.json).
TEST_F(Cli, FigureAndTableTakePathsRelativeToTheWorkingFolder) {
  const std::string harness = std::string(PENUMBRA_SOURCE_DIR) + "/tests/harness";
  const std::string make = fmt::format(
      "/usr/bin/python3 -c \"import sys; sys.path.insert(0, '{}'); import report_fixture as fx; "
      "fx.write_fixture('{}', scenes=fx.SCENES[:1], lights=fx.LIGHTS[:1], "
      "methods=fx.METHODS[:4])\"",
      harness, path("study"));
  ASSERT_EQ(std::system(make.c_str()), 0) << make;
  const fs::path before = fs::current_path();
  fs::current_path(dir_);
  const Result table = run({"table", "study", "--format", "csv"});
  const Result figure = run({"figure", "study", "--kind", "ranking", "-o", "ranking.png"});
  fs::current_path(before);
  EXPECT_EQ(table.code, kExitOk) << table.err;
  EXPECT_NE(table.out.find("method"), std::string::npos) << table.out;
  EXPECT_EQ(figure.code, kExitOk) << figure.err;
  EXPECT_GT(fs::file_size(dir_ / "ranking.png"), 0u);
}

// bench --povray: one line per round whose ratio is POV-Ray's CPU seconds
// over the evaluator's, then their range and median; its renders go to a
// folder under TMPDIR that is gone afterwards. Times are not checked.
TEST_F(Cli, BenchAgainstPovrayPrintsPairedRoundsAndLeavesNothing) {
  const char* old_tmpdir = std::getenv("TMPDIR");
  const std::string saved = old_tmpdir ? old_tmpdir : "";
  ::setenv("TMPDIR", dir_.c_str(), 1);
  const Result r = run({"bench", "--povray", "3", "--size", "128", "--spp", "4"});
  if (old_tmpdir)
    ::setenv("TMPDIR", saved.c_str(), 1);
  else
    ::unsetenv("TMPDIR");
  ASSERT_EQ(r.code, kExitOk) << r.err;
  expect_only({});
  const std::regex round_line(R"((\d+) +([0-9.]+) +([0-9.]+) +([0-9.]+)x)");
  std::vector<double> ratios;
  std::istringstream lines(r.out);
  for (std::string line; std::getline(lines, line);) {
    std::smatch m;
    if (!std::regex_match(line, m, round_line)) continue;
    EXPECT_EQ(std::stoi(m[1]), int(ratios.size()) + 1);
    const double evaluator = std::stod(m[2]), povray = std::stod(m[3]);
    ratios.push_back(std::stod(m[4]));
    ASSERT_GT(evaluator, 0.0005) << r.out;
    // Printed to 3 decimals and the ratio to 1: the times are each within
    // 0.0005 of what was measured, so povray / evaluator is within
    // 0.0005 * (1 + povray / evaluator) / (evaluator - 0.0005) of the ratio
    // the tool divided, and the printed ratio within 0.05 of that.
    EXPECT_NEAR(ratios.back(), povray / evaluator,
                0.05 + 0.0005 * (1.0 + povray / evaluator) / (evaluator - 0.0005) + 1e-9)
        << r.out;
  }
  ASSERT_EQ(ratios.size(), 3u) << r.out;
  std::sort(ratios.begin(), ratios.end());
  EXPECT_NE(r.out.find(
                fmt::format("{:.1f}x to {:.1f}x, median {:.1f}x", ratios[0], ratios[2], ratios[1])),
            std::string::npos)
      << r.out;
  EXPECT_EQ(run({"bench", "--povray", "0"}).code, kExitBadInput);
}

TEST_F(Cli, MethodsListsEveryIdAsTextAndJson) {
  const Result text = run({"methods"});
  EXPECT_EQ(text.code, kExitOk);
  const Result js = run({"methods", "--json"});
  EXPECT_EQ(js.code, kExitOk);
  const auto list = nlohmann::json::parse(js.out);
  std::vector<std::string> ids;
  for (const auto& m : list) ids.push_back(m.at("id"));
  for (const char* id : {"none", "chiang2019", "chiang2019-sine", "estevez2019",
                         "estevez2019-reciprocal", "deshmukh2020", "shading-offset"}) {
    EXPECT_NE(std::find(ids.begin(), ids.end(), id), ids.end()) << id;
    EXPECT_NE(text.out.find(id), std::string::npos) << id;
  }
}

TEST_F(Cli, RenderWritesExrWithAnalysisChannelsAndPreview) {
  const Result r = run({"render", kScenes + "/sphere-grating.json", "-o", path("out.exr"),
                        "--preview", path("out.png"), "--width", "40", "--height", "30", "--spp",
                        "4", "--method", "chiang2019", "--set", "/light/direction=[-1,0.2,-0.3]"});
  ASSERT_EQ(r.code, kExitOk) << r.err;
  const Image image = read_image(path("out.exr"));
  EXPECT_EQ(image.width, 40);
  EXPECT_EQ(image.height, 30);
  for (const char* c :
       {"R", "G", "B", "A", "analysis.theta", "analysis.deviation", "analysis.G", "analysis.view"})
    EXPECT_GE(image.channel_index(c), 0) << c;
  EXPECT_TRUE(fs::exists(path("out.png")));
  // The preview is over black, as documented: no alpha channel.
  EXPECT_EQ(read_image(path("out.png")).channels.size(), 3u);
  expect_only({"out.exr", "out.png"});
}

// A mesh file where a scene is expected renders with a default scene that
// frames it: the whole mesh inside the image, a terminator across it, and
// --set on top (a height makes `--method` act on bumps); a file that is
// not a mesh is refused with its name, exit 2, nothing written.
TEST_F(Cli, RenderTakesAMeshFileFramedByADefaultScene) {
  std::ofstream(path("octahedron.obj"))
      << "v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n"
         "f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n";
  const Result r = run({"render", path("octahedron.obj"), "-o", path("out.exr"), "--width", "48",
                        "--height", "48", "--method", "estevez2019", "--set",
                        R"(/height={"type": "grating", "amplitude": 0.01, "frequency": 4,)"
                        R"( "direction": [1, 0, 0]})"});
  ASSERT_EQ(r.code, kExitOk) << r.err;
  std::map<std::string, std::string> attributes;
  const Image image = read_image(path("out.exr"), &attributes);
  const nlohmann::json scene = nlohmann::json::parse(attributes.at("penumbra:scene"));
  EXPECT_EQ(scene.at("shape").at("type"), "mesh");
  EXPECT_EQ(scene.at("terminator").at("method"), "estevez2019");
  // Framed: no covered pixel on the border, and the mesh's lit and dark
  // sides both in view.
  std::size_t covered = 0, lit = 0, dark = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const float a = image.at(x, y, 3);
      if (x == 0 || y == 0 || x == image.width - 1 || y == image.height - 1) {
        EXPECT_EQ(a, 0.0f) << x << ", " << y;
      }
      if (a < 1.0f) continue;
      ++covered;
      (image.at(x, y, 0) > 0.0f ? lit : dark) += 1;
    }
  EXPECT_GT(covered, 800u);  // the diamond fills 2 of the 2.2^2 square units
  EXPECT_GT(lit, 100u);
  EXPECT_GT(dark, 20u);
  std::ofstream(path("garbage.obj")) << "this is not a mesh\n";
  const Result bad = run({"render", path("garbage.obj"), "-o", path("bad.exr")});
  EXPECT_EQ(bad.code, kExitBadInput);
  EXPECT_NE(bad.err.find("garbage.obj"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(path("bad.exr")));
}

// A mesh file with --set /shape/node: the default scene frames that node
// and shades it with its own normal texture. The ClearCoat sample's tile
// R3_BaseLayerSample (RibsNormal.png) fills the view but for its margin,
// where the whole sample's 6 x 3 tiles and labels would leave most of it
// empty; a node the file lacks is exit 2 at /shape/node.
TEST_F(Cli, RenderFramesTheNodeASetNames) {
  const std::string gltf = "/usr/share/assimp/models/glTF2/ClearCoat-glTF/ClearCoatTest.gltf";
  ASSERT_TRUE(fs::exists(gltf)) << "apt-get install assimp-testmodels";
  const Result r = run({"render", gltf, "-o", path("tile.exr"), "--width", "48", "--height", "48",
                        "--set", "/shape/node=R3_BaseLayerSample"});
  ASSERT_EQ(r.code, kExitOk) << r.err;
  std::map<std::string, std::string> attributes;
  const Image image = read_image(path("tile.exr"), &attributes);
  const nlohmann::json scene = nlohmann::json::parse(attributes.at("penumbra:scene"));
  EXPECT_EQ(scene.at("height").at("type"), "normal-map");
  std::size_t covered = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) covered += image.at(x, y, 3) == 1.0f;
  EXPECT_GT(covered, 48u * 48u * 6 / 10) << "the tile is framed";
  const Result bad = run({"render", gltf, "-o", path("bad.exr"), "--set", "/shape/node=nothing"});
  EXPECT_EQ(bad.code, kExitBadInput);
  EXPECT_NE(bad.err.find("/shape/node"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(path("bad.exr")));
}

// `penumbra mesh` writes the triangles a scene stands for. PLY keeps the
// floats' bits: the mesh read back renders the tessellated sphere's smooth
// image bit for bit. OBJ keeps 9 significant digits, which name every float
// exactly: read back (Assimp's parser rounds), each coordinate is within one
// float ulp of the tessellation's (6e-8 of the unit radius). The shipped
// control sphere is this command's output, so the test fails when it is stale.
TEST_F(Cli, MeshWritesTheTrianglesASceneStandsFor) {
  const std::string sphere = kScenes + "/lowpoly/sphere.json";
  ASSERT_EQ(run({"mesh", sphere, "--segments", "12", "-o", path("s.ply")}).code, kExitOk);
  ASSERT_EQ(run({"mesh", sphere, "--segments", "12", "-o", path("s.obj")}).code, kExitOk);
  const std::vector<std::string> small = {"--width", "40", "--height", "40", "--spp", "4"};
  auto render_to = [&](std::vector<std::string> args, const std::string& out) {
    args.insert(args.end(), {"-o", path(out)});
    args.insert(args.end(), small.begin(), small.end());
    EXPECT_EQ(run(args).code, kExitOk) << out;
    return read_image(path(out));
  };
  const Image built_in = render_to({"render", sphere, "--segments", "12"}, "built-in.exr");
  const Image from_ply = render_to(
      {"render", sphere, "--set", R"(/shape={"type": "mesh", "file": ")" + path("s.ply") + "\"}"},
      "ply.exr");
  ASSERT_EQ(built_in.pixels.size(), from_ply.pixels.size());
  std::size_t differ = 0;
  for (std::size_t p = 0; p < built_in.pixels.size(); p += built_in.channels.size())
    for (std::size_t c = 0; c < 4; ++c) differ += built_in.pixels[p + c] != from_ply.pixels[p + c];
  EXPECT_EQ(differ, 0u);
  const LoadedMesh ply = load_mesh_file(path("s.ply"), {}, MeshNormals::kFile);
  const LoadedMesh obj = load_mesh_file(path("s.obj"), {}, MeshNormals::kFile);
  ASSERT_EQ(obj.surface->mesh.positions.size(), ply.surface->mesh.positions.size());
  ASSERT_EQ(obj.surface->mesh.triangles, ply.surface->mesh.triangles);
  for (std::size_t i = 0; i < ply.surface->mesh.positions.size(); ++i) {
    const float a = ply.surface->mesh.positions[i], b = obj.surface->mesh.positions[i];
    EXPECT_LE(std::abs(a - b), std::nextafter(std::abs(a), 2.0f) - std::abs(a)) << i;
  }
  // The truth of a mesh shape: the evaluator's subdivision, as exported.
  const Result truth = run({"mesh", kScenes + "/meshes/sphere-control.json", "--representation",
                            "displacement", "-o", path("truth.ply")});
  ASSERT_EQ(truth.code, kExitOk) << truth.err;
  EXPECT_NE(truth.out.find("displaced ground truth"), std::string::npos) << truth.out;
  EXPECT_GT(
      load_mesh_file(path("truth.ply"), {}, MeshNormals::kFile).surface->mesh.triangle_count(),
      ply.surface->mesh.triangle_count() * 100);
  const Result bad = run({"mesh", sphere, "-o", path("s.stl")});
  EXPECT_EQ(bad.code, kExitBadInput);
  EXPECT_NE(bad.err.find(".obj or .ply"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(path("s.stl")));
  // scenes/meshes/sphere-uv64.obj is this command's file, its first line
  // (the command that made it) aside.
  ASSERT_EQ(run({"mesh", sphere, "--segments", "64", "-o", path("uv64.obj")}).code, kExitOk);
  auto body = [](const std::string& file) {
    std::ifstream in(file);
    const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    return text.substr(std::min(text.size(), text.find('\n')));
  };
  EXPECT_TRUE(body(path("uv64.obj")) == body(kScenes + "/meshes/sphere-uv64.obj"))
      << "regenerate with: penumbra mesh scenes/lowpoly/sphere.json --segments 64 -o "
         "scenes/meshes/sphere-uv64.obj (and keep its first line)";
}

TEST_F(Cli, GlobalOptionsWorkAfterTheSubcommand) {
  const Result r = run({"render", kScenes + "/sphere-grating.json", "-o", path("out.exr"),
                        "--width", "8", "--height", "8", "--threads", "1"});
  EXPECT_EQ(r.code, kExitOk) << r.err;
}

TEST_F(Cli, UnknownSubcommandIsNamedWithTheValidOnes) {
  const Result r = run({"rendr", "x.json"});
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(
      r.err.find(
          "unknown subcommand \"rendr\" (expected one of: methods, renderers, render, export"),
      std::string::npos)
      << r.err;
}

TEST_F(Cli, EveryHelpListsEveryExitCode) {
  for (const char* command : {"render", "export", "compare", "calibrate", "run", "contour"}) {
    const Result r = run({command, "--help"});
    EXPECT_EQ(r.code, kExitOk) << command;
    for (const char* code : {"0 success", "1 a run failed", "2 bad input", "3 a comparison",
                             "128+N stopped by signal"})
      EXPECT_NE(r.out.find(code), std::string::npos) << command << " --help lacks " << code;
  }
}

TEST_F(Cli, RendererRefusesAMethodItDoesNotShipBeforeRunning) {
  const Result r = run({"render", kScenes + "/sphere-grating.json", "-o", path("out.exr"),
                        "--renderer", "povray", "--method", "chiang2019"});
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.err.find("povray does not offer the method \"chiang2019\""), std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("running"), std::string::npos) << r.err;
  expect_only({});  // not even a log
}

TEST_F(Cli, ExportTakesTheRenderShortcuts) {
  const Result r = run({"export", "--to", "povray", kScenes + "/sphere-grating.json", "-o",
                        path("pov"), "--width", "24", "--height", "20"});
  ASSERT_EQ(r.code, kExitOk) << r.err;
  EXPECT_NE(r.out.find("down to 24x20"), std::string::npos) << r.out;
}

TEST_F(Cli, CompareTextShowsSsimLikeTheJson) {
  // 48 px: enough fully covered pixels at grazing views for the viewer metric.
  ASSERT_EQ(run({"render", kScenes + "/sphere-grating.json", "-o", path("a.exr"), "--width", "48",
                 "--height", "48", "--spp", "1"})
                .code,
            kExitOk);
  const Result text = run({"compare", path("a.exr"), path("a.exr")});
  EXPECT_EQ(text.code, kExitOk) << text.err;
  EXPECT_NE(text.out.find("SSIM"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("RMSE grazing views"), std::string::npos) << text.out;
  const Result j = run({"compare", path("a.exr"), path("a.exr"), "--json"});
  ASSERT_EQ(j.code, kExitOk) << j.err;
  const nlohmann::json doc = nlohmann::json::parse(j.out);
  EXPECT_EQ(doc["view"]["rmse_grazing"], 0.0);
  EXPECT_EQ(doc["view"]["rmse_grazing_ci"], nlohmann::json({0.0, 0.0}));
}

TEST_F(Cli, CompareWritesTheDifferenceAndWarnsAboutDifferentScenes) {
  render_sphere_and_cylinder();
  const Result r = run({"compare", path("sphere-grating.exr"), path("cylinder-grating.exr"), "-o",
                        path("diff.exr")});
  EXPECT_EQ(r.code, kExitOk) << r.err;
  EXPECT_NE(r.err.find("show different scenes"), std::string::npos) << r.err;
  const Image a = read_image(path("sphere-grating.exr")),
              b = read_image(path("cylinder-grating.exr"));
  const Image d = read_image(path("diff.exr"));
  ASSERT_EQ(d.width, 16);
  const int r_d = d.channel_index("R"), r_a = a.channel_index("R"), r_b = b.channel_index("R");
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x)
      EXPECT_FLOAT_EQ(d.at(x, y, r_d), b.at(x, y, r_b) - a.at(x, y, r_a));
  // The same scene: no warning.
  const Result same = run({"compare", path("sphere-grating.exr"), path("sphere-grating.exr")});
  EXPECT_EQ(same.err.find("warning"), std::string::npos) << same.err;
}

TEST_F(Cli, CompareNamesTheImageThatLacksCoverage) {
  ASSERT_EQ(run({"render", kScenes + "/sphere-grating.json", "-o", path("a.exr"), "--width", "8",
                 "--height", "8", "--preview", path("p.png")})
                .code,
            kExitOk);
  const Result r = run({"compare", path("a.exr"), path("p.png"), "-o", path("d.exr")});
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.err.find(path("p.png") +
                       ": no A (coverage) channel and no --mask FILE or --threshold given"),
            std::string::npos)
      << r.err;
  expect_only({"a.exr", "p.png"});
}

// Every key of compare --json, as the label its text form prints it under:
// a metric added to the JSON without a text line fails here.
const std::map<std::string, std::string>& compare_text_labels() {
  static const std::map<std::string, std::string> labels{
      {"reference", "reference "},
      {"test", "test      "},
      {"coverage", "(coverage: "},
      {"radiance_scale", "albedo*E/pi = "},
      {"radiance_scale_unit", "W m^-2 sr^-1"},
      {"intervals", "intervals: 95 %"},
      {"pass", "pass"},
      {"profile/unit", "fraction of albedo*E/pi"},
      {"profile/rmse_terminator", "RMSE terminator [60,100) deg"},
      {"profile/rmse_terminator_ci", "RMSE terminator [60,100) deg"},
      {"profile/rmse_terminator_bootstrap_bias", "bootstrap bias of that RMSE"},
      {"profile/rmse_overall", "RMSE overall"},
      {"profile/max_error_terminator", "max error terminator"},
      {"profile/max_error_terminator_ci", "max error terminator"},
      {"profile/max_step", "largest bin step"},
      {"profile/reference_max_step", "largest bin step"},
      {"profile/position_deg", "terminator position"},
      {"profile/reference_position_deg", "terminator position"},
      {"profile/position_error_deg", "terminator position"},
      {"profile/position_error_deg_ci", "terminator position"},
      {"profile/width_deg", "transition width"},
      {"profile/reference_width_deg", "transition width"},
      {"profile/lit_bias", "lit-region bias"},
      {"profile/lit_bias_ci", "lit-region bias"},
      {"profile/common_bins", "common bins"},
      {"image/unit", "W m^-2 sr^-1"},
      {"image/mask_iou", "mask IoU"},
      {"image/rmse", "  RMSE  "},
      {"image/rmse_ci", "  RMSE  "},
      {"image/max_error", "  max error  "},
      {"image/mean_error", "mean error (test-reference)"},
      {"image/reference_mean", "reference mean"},
      {"image/peak", "reference peak"},
      {"image/ssim", "SSIM  "},
      {"image/ssim_kind", "masked SSIM: Gaussian 11x11"},
      {"image/pixels", "pixels fully covered in both: "},
      {"image/nonfinite", "NaN/Inf values"},
      {"view/unit", "fraction of albedo*E/pi"},
      {"view/grazing_deg", "pixels at [60, 75) deg"},
      {"view/rmse_grazing", "RMSE grazing views"},
      {"view/rmse_grazing_ci", "RMSE grazing views"},
      {"view/bias_grazing", "bias grazing views"},
      {"view/bias_grazing_ci", "bias grazing views"},
      {"view/pixels", "binned by view angle; "}};
  return labels;
}

TEST_F(Cli, CompareTextHasEveryMetricOfTheJson) {
  ASSERT_EQ(run({"render", kScenes + "/sphere-grating.json", "-o", path("a.exr"), "--width", "48",
                 "--height", "48", "--spp", "1"})
                .code,
            kExitOk);
  ASSERT_EQ(run({"render", kScenes + "/sphere-grating.json", "-o", path("b.exr"), "--width", "48",
                 "--height", "48", "--spp", "1", "--method", "chiang2019"})
                .code,
            kExitOk);
  const Result text = run({"compare", path("a.exr"), path("b.exr")});
  const Result j = run({"compare", path("a.exr"), path("b.exr"), "--json"});
  ASSERT_EQ(text.code, kExitOk) << text.err;
  ASSERT_EQ(j.code, kExitOk) << j.err;
  const nlohmann::json doc = nlohmann::json::parse(j.out);
  const auto& labels = compare_text_labels();
  for (const auto& [key, value] : doc.items()) {
    const bool section = key == "profile" || key == "image" || key == "view";
    if (!section) {
      ASSERT_TRUE(labels.count(key)) << "no text label for " << key;
      EXPECT_NE(text.out.find(labels.at(key)), std::string::npos) << key;
      continue;
    }
    for (const auto& [metric, unused] : value.items()) {
      const std::string name = key + "/" + metric;
      ASSERT_TRUE(labels.count(name)) << "no text label for " << name;
      EXPECT_NE(text.out.find(labels.at(name)), std::string::npos) << name << "\n" << text.out;
    }
  }
  // The values too, at the text's precision.
  EXPECT_NE(text.out.find(fmt::format("{:.6f}", doc["image"]["ssim"].get<double>())),
            std::string::npos);
  EXPECT_NE(text.out.find(fmt::format("{:.6g}", doc["image"]["reference_mean"].get<double>())),
            std::string::npos);
}

TEST_F(Cli, CompareDifferentScenesNamesWhatDiffersAndSameSceneRefuses) {
  render_sphere_and_cylinder();
  const Result warn = run({"compare", path("sphere-grating.exr"), path("cylinder-grating.exr")});
  EXPECT_EQ(warn.code, kExitOk) << warn.err;
  EXPECT_NE(warn.err.find("penumbra: warning:"), std::string::npos) << warn.err;
  EXPECT_NE(warn.err.find("/shape/type"), std::string::npos) << warn.err;
  const Result strict = run({"compare", path("sphere-grating.exr"), path("cylinder-grating.exr"),
                             "--same-scene", "-o", path("diff.exr")});
  EXPECT_EQ(strict.code, kExitBadInput);
  EXPECT_NE(strict.err.find("show different scenes (penumbra:scene differs at /shape/type"),
            std::string::npos)
      << strict.err;
  expect_only({"sphere-grating.exr", "cylinder-grating.exr"});
  // Sampling is no part of the scene: more samples, the same scene.
  ASSERT_EQ(run({"render", kScenes + "/sphere-grating.json", "-o", path("spp2.exr"), "--width",
                 "16", "--height", "16", "--spp", "2", "--method", "chiang2019"})
                .code,
            kExitOk);
  const Result same =
      run({"compare", path("sphere-grating.exr"), path("spp2.exr"), "--same-scene"});
  EXPECT_EQ(same.code, kExitOk) << same.err;
  EXPECT_EQ(same.err, "");
}

TEST_F(Cli, CompareDifferenceOutputIsCheckedBeforeAnythingIsRead) {
  ASSERT_EQ(run({"render", kScenes + "/sphere-grating.json", "-o", path("a.exr"), "--width", "8",
                 "--height", "8", "--spp", "1"})
                .code,
            kExitOk);
  const Result png = run({"compare", path("a.exr"), path("a.exr"), "-o", path("diff.png")});
  EXPECT_EQ(png.code, kExitBadInput);
  EXPECT_NE(png.err.find("-o " + path("diff.png") + ": expected a file name ending in .exr"),
            std::string::npos)
      << png.err;
  const Result folder =
      run({"compare", path("a.exr"), path("a.exr"), "-o", path("missing/diff.exr")});
  EXPECT_EQ(folder.code, kExitBadInput);
  EXPECT_NE(folder.err.find("does not exist"), std::string::npos) << folder.err;
  const Result proc = run({"compare", path("a.exr"), path("a.exr"), "-o", "/proc/diff.exr"});
  EXPECT_EQ(proc.code, kExitBadInput);
  EXPECT_NE(proc.err.find("/proc/diff.exr: "), std::string::npos) << proc.err;
  // Writing the difference over an input would destroy the reference.
  const auto before = fs::last_write_time(path("a.exr"));
  const Result self = run({"compare", path("a.exr"), path("a.exr"), "-o", path("a.exr")});
  EXPECT_EQ(self.code, kExitBadInput);
  EXPECT_NE(self.err.find("an input of the comparison"), std::string::npos) << self.err;
  EXPECT_EQ(fs::last_write_time(path("a.exr")), before);
  // A missing input: nothing written, although -o itself was fine.
  const Result missing = run({"compare", path("a.exr"), path("nope.exr"), "-o", path("diff.exr")});
  EXPECT_EQ(missing.code, kExitBadInput);
  EXPECT_NE(missing.err.find(path("nope.exr") + ": no such file"), std::string::npos)
      << missing.err;
  expect_only({"a.exr"});
}

// Another renderer's image: R, G, B only, no coverage, no analysis channels.
class CompareExternal : public Cli {
 protected:
  void SetUp() override {
    Cli::SetUp();
    ASSERT_EQ(run({"render", kScenes + "/sphere-grating.json", "-o", path("a.exr"), "--width", "48",
                   "--height", "48", "--spp", "1"})
                  .code,
              kExitOk);
    const Image a = read_image(path("a.exr"));
    Image rgb, mask;
    rgb.width = mask.width = a.width;
    rgb.height = mask.height = a.height;
    rgb.channels = {"R", "G", "B"};
    mask.channels = {"Y"};
    for (int y = 0; y < a.height; ++y)
      for (int x = 0; x < a.width; ++x) {
        for (const char* c : {"R", "G", "B"}) rgb.pixels.push_back(a.at(x, y, a.channel_index(c)));
        mask.pixels.push_back(a.at(x, y, a.channel_index("A")));
      }
    write_exr(rgb, path("rgb.exr"));
    write_exr(mask, path("mask.exr"));
  }
  nlohmann::json compare_json(std::vector<std::string> args, int code = kExitOk) {
    args.insert(args.begin(), "compare");
    args.push_back("--json");
    const Result r = run(args);
    EXPECT_EQ(r.code, code) << r.err;
    return r.code == kExitOk ? nlohmann::json::parse(r.out) : nlohmann::json();
  }
};

TEST_F(CompareExternal, AMaskImageGivesTheCoverage) {
  // The render's own coverage as --mask: the comparison with itself.
  const nlohmann::json doc =
      compare_json({path("a.exr"), path("rgb.exr"), "--mask", path("mask.exr")});
  EXPECT_EQ(doc["coverage"]["test"], "--mask " + path("mask.exr"));
  EXPECT_EQ(doc["coverage"]["reference"], "A channel");
  EXPECT_EQ(doc["image"]["mask_iou"], 1.0);
  EXPECT_EQ(doc["image"]["rmse"], 0.0);
  EXPECT_EQ(doc["image"]["ssim"], 1.0);
  EXPECT_EQ(doc["profile"]["rmse_overall"], 0.0);  // theta lent by the reference
  // The other way round: theta comes from the test.
  const nlohmann::json back =
      compare_json({path("rgb.exr"), path("a.exr"), "--mask", path("mask.exr")});
  EXPECT_EQ(back["profile"]["rmse_overall"], 0.0);
  expect_only({"a.exr", "rgb.exr", "mask.exr"});
}

TEST_F(CompareExternal, AThresholdGivesTheLitRegion) {
  const nlohmann::json bare = compare_json({path("a.exr"), path("rgb.exr"), "--threshold"});
  EXPECT_NE(bare["coverage"]["test"].get<std::string>().find("--threshold 0.05: lit where"),
            std::string::npos)
      << bare["coverage"];
  // Shadowed pixels count as background: the lit region is smaller than the object.
  EXPECT_LT(bare["image"]["mask_iou"].get<double>(), 1.0);
  EXPECT_GT(bare["image"]["mask_iou"].get<double>(), 0.2);
  const nlohmann::json given = compare_json({"--threshold=0.5", path("a.exr"), path("rgb.exr")});
  EXPECT_LT(given["image"]["mask_iou"], bare["image"]["mask_iou"]);
}

TEST_F(CompareExternal, TwoExternalImagesGetImageMetricsOnly) {
  const nlohmann::json doc = compare_json({path("rgb.exr"), path("rgb.exr"), "--no-mask"});
  EXPECT_TRUE(doc["profile"].is_null());
  EXPECT_TRUE(doc["view"].is_null());
  EXPECT_NE(doc["profile_skipped"].get<std::string>().find("no coverage"), std::string::npos);
  EXPECT_EQ(doc["image"]["pixels"], 48 * 48);
  EXPECT_EQ(doc["image"]["ssim"], 1.0);
  EXPECT_TRUE(doc["image"]["mask_iou"].is_null());
  const Result text = run({"compare", path("rgb.exr"), path("rgb.exr"), "--no-mask"});
  EXPECT_EQ(text.code, kExitOk);
  EXPECT_NE(text.out.find("profile and viewer metrics: not computed"), std::string::npos)
      << text.out;
  // A bound on the profile cannot be checked without one.
  const Result bound =
      run({"compare", path("rgb.exr"), path("rgb.exr"), "--no-mask", "--max-profile-rmse", "0.1"});
  EXPECT_EQ(bound.code, kExitBadInput);
  EXPECT_NE(bound.err.find("--max-profile-rmse: no profile to check"), std::string::npos)
      << bound.err;
  // A threshold is a fraction of albedo*E/pi, which neither image gives.
  const Result scale = run({"compare", path("rgb.exr"), path("rgb.exr"), "--threshold=0.1"});
  EXPECT_EQ(scale.code, kExitBadInput);
  EXPECT_NE(scale.err.find("--threshold is a fraction of albedo*E/pi"), std::string::npos)
      << scale.err;
  const Result wrong = run({"compare", path("rgb.exr"), path("rgb.exr"), "--mask", path("b.exr")});
  EXPECT_EQ(wrong.code, kExitBadInput);
  EXPECT_NE(wrong.err.find(path("b.exr") + ": no such file"), std::string::npos) << wrong.err;
}

TEST_F(CompareExternal, NoMaskSsimDiffersFromTheMaskedOne) {
  ASSERT_EQ(run({"render", kScenes + "/sphere-grating.json", "-o", path("b.exr"), "--width", "48",
                 "--height", "48", "--spp", "1", "--method", "chiang2019"})
                .code,
            kExitOk);
  const nlohmann::json masked = compare_json({path("a.exr"), path("b.exr")});
  const nlohmann::json full = compare_json({path("a.exr"), path("b.exr"), "--no-mask"});
  EXPECT_EQ(full["image"]["pixels"], 48 * 48);
  EXPECT_LT(masked["image"]["pixels"], 48 * 48);
  EXPECT_NE(masked["image"]["ssim"], full["image"]["ssim"]);
  EXPECT_EQ(masked["profile"], full["profile"]);  // the profile keeps the coverage
}

TEST_F(Cli, RenderRefusesANonExrOutputBeforeRendering) {
  const Result r = run({"render", kScenes + "/sphere-grating.json", "-o", path("x.png")});
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.err.find("-o " + path("x.png") +
                       ": expected a file name ending in .exr (got \".png\"): only OpenEXR holds"),
            std::string::npos)
      << r.err;
  const Result preview = run({"render", kScenes + "/sphere-grating.json", "-o", path("x.exr"),
                              "--preview", path("x.tif")});
  EXPECT_EQ(preview.code, kExitBadInput);
  EXPECT_NE(
      preview.err.find("--preview " + path("x.tif") + ": expected a file name ending in .png"),
      std::string::npos)
      << preview.err;
  expect_only({});
}

TEST_F(Cli, RenderRefusesAFolderThatTakesNoFilesBeforeRendering) {
  std::ofstream(path("file")) << "x";
  const Result under_file =
      run({"render", kScenes + "/sphere-grating.json", "-o", path("file/out.exr")});
  EXPECT_EQ(under_file.code, kExitBadInput);
  EXPECT_NE(under_file.err.find("does not exist"), std::string::npos) << under_file.err;
  const Result proc = run({"render", kScenes + "/sphere-grating.json", "-o", "/proc/out.exr"});
  EXPECT_EQ(proc.code, kExitBadInput);
  EXPECT_NE(proc.err.find("/proc/out.exr: "), std::string::npos) << proc.err;
  EXPECT_EQ(proc.out, "");  // no "wrote" line: nothing rendered
  expect_only({"file"});
}

TEST_F(Cli, ExportRefusesBadOutputsBeforeExporting) {
  std::ofstream(path("file")) << "x";
  const Result under_file =
      run({"export", "--to", "povray", kScenes + "/sphere-grating.json", "-o", path("file/pov")});
  EXPECT_EQ(under_file.code, kExitBadInput);
  EXPECT_NE(under_file.err.find("cannot create the output folder"), std::string::npos)
      << under_file.err;
  const Result proc =
      run({"export", "--to", "blender", kScenes + "/sphere-grating.json", "-o", "/proc"});
  EXPECT_EQ(proc.code, kExitBadInput);
  EXPECT_NE(proc.err.find("/proc/job.json: "), std::string::npos) << proc.err;
  // A method the renderer lacks: refused before the folder is made.
  const Result method = run({"export", "--to", "povray", kScenes + "/sphere-grating.json", "-o",
                             path("pov"), "--method", "chiang2019"});
  EXPECT_EQ(method.code, kExitBadInput);
  EXPECT_NE(method.err.find("povray does not offer the method \"chiang2019\""), std::string::npos)
      << method.err;
  expect_only({"file"});
}

TEST_F(Cli, BadSceneExitsTwoWithOneLineAndNoOutput) {
  std::ofstream(path("bad.json")) << R"({"version": 1, "camera": {}})";
  const Result r = run({"render", path("bad.json"), "-o", path("out.exr")});
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.err.find(path("bad.json") + ": /camera/position: missing required key"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1);
  expect_only({"bad.json"});
}

TEST_F(Cli, UnknownMethodListsTheValidIds) {
  const Result r = run({"render", kScenes + "/sphere-grating.json", "-o", path("out.exr"),
                        "--method", "chaing2019"});
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(
      r.err.find("/terminator/method: unknown method \"chaing2019\" (valid: none, chiang2019"),
      std::string::npos)
      << r.err;
  expect_only({});
}

TEST_F(Cli, UnwritableOutputExitsTwoBeforeRendering) {
  const Result r =
      run({"render", kScenes + "/sphere-grating.json", "-o", path("missing-folder/out.exr")});
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.err.find("does not exist"), std::string::npos) << r.err;
  expect_only({});
}

TEST_F(Cli, UnreadableSceneAndUsageErrorsExitTwo) {
  EXPECT_EQ(run({"render", path("nope.json"), "-o", path("out.exr")}).code, kExitBadInput);
  EXPECT_EQ(run({"render"}).code, kExitBadInput);
  EXPECT_EQ(run({"frobnicate"}).code, kExitBadInput);
  EXPECT_EQ(
      run({"render", kScenes + "/sphere-grating.json", "-o", path("o.exr"), "--spp", "0"}).code,
      kExitBadInput);
  expect_only({});
}

}  // namespace
}  // namespace penumbra
