// The command line: exit codes, messages, and no half-written output.
#include <gtest/gtest.h>

#include "cli_test.h"
#include "temp_dir_test.h"

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/cli.h"
#include "image/image_io.h"

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
};

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
  for (const char* scene : {"sphere-grating", "cylinder-grating"})
    ASSERT_EQ(
        run({"render", kScenes + "/" + scene + ".json", "-o", path(std::string(scene) + ".exr"),
             "--width", "16", "--height", "16", "--spp", "1"})
            .code,
        kExitOk);
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

TEST_F(Cli, CompareNamesTheImageThatLacksAChannel) {
  ASSERT_EQ(run({"render", kScenes + "/sphere-grating.json", "-o", path("a.exr"), "--width", "8",
                 "--height", "8", "--preview", path("p.png")})
                .code,
            kExitOk);
  const Result r = run({"compare", path("a.exr"), path("p.png")});
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.err.find(path("p.png") + ": no A channel"), std::string::npos) << r.err;
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
