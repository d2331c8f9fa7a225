// `penumbra compare --flip`: mean FLIP with its interval in the text and the
// JSON, the error map as PNG or EXR, and output unchanged without --flip.
#include <gtest/gtest.h>

#include "cli_test.h"
#include "temp_dir_test.h"

#include <algorithm>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "analysis/flip.h"
#include "analysis/magma.h"
#include "cli/cli.h"
#include "image/image_io.h"

namespace penumbra {
namespace {

namespace fs = std::filesystem;

const std::string kScenes = std::string(PENUMBRA_SOURCE_DIR) + "/scenes";

class CompareFlip : public TempDirTest {
 protected:
  // a.exr (no method) and b.exr (chiang2019), 48 x 48 at 1 spp, with their
  // preview PNGs.
  void SetUp() override {
    TempDirTest::SetUp();
    for (const auto& [name, method] : {std::pair{"a", "none"}, std::pair{"b", "chiang2019"}})
      ASSERT_EQ(run_penumbra({"render", kScenes + "/sphere-grating.json", "-o",
                              path(std::string(name) + ".exr"), "--preview",
                              path(std::string(name) + ".png"), "--width", "48", "--height", "48",
                              "--spp", "1", "--method", method})
                    .code,
                kExitOk);
  }
  nlohmann::json compare_json(std::vector<std::string> args) {
    args.insert(args.begin(), "compare");
    args.push_back("--json");
    const CliResult r = run_penumbra(args);
    EXPECT_EQ(r.code, kExitOk) << r.err;
    return r.code == kExitOk ? nlohmann::json::parse(r.out) : nlohmann::json();
  }
  std::vector<std::string> files() const {
    std::vector<std::string> found;
    for (const auto& e : fs::directory_iterator(dir_)) found.push_back(e.path().filename());
    std::sort(found.begin(), found.end());
    return found;
  }
};

TEST_F(CompareFlip, WithoutFlipTheOutputHasNoFlip) {
  const nlohmann::json doc = compare_json({path("a.exr"), path("b.exr")});
  EXPECT_FALSE(doc.contains("flip"));
  const CliResult text = run_penumbra({"compare", path("a.exr"), path("b.exr")});
  EXPECT_EQ(text.out.find("FLIP"), std::string::npos) << text.out;
}

// Every key of the "flip" object, as the label its text form prints it under.
TEST_F(CompareFlip, TextHasEveryFlipKeyOfTheJson) {
  const std::map<std::string, std::string> labels{
      {"range", "HDR-FLIP"},
      {"pixels_per_degree", "67.02 pixels per degree"},
      {"pixels", "every pixel: 2304"},
      {"mean", "mean FLIP  "},
      {"mean_ci", "(95 % CI; 16 bands of rows, 400 resamples)"},
      {"exposures", "exposures  "},
      {"encoding", "reference linear, test linear"},
      {"map", "  map  "}};
  const std::vector<std::string> args{path("a.exr"), path("b.exr"), "--flip-map", path("map.png")};
  const nlohmann::json doc = compare_json(args);
  std::vector<std::string> text_args = args;
  text_args.insert(text_args.begin(), "compare");
  const CliResult text = run_penumbra(text_args);
  ASSERT_EQ(text.code, kExitOk) << text.err;
  ASSERT_TRUE(doc.contains("flip"));
  for (const auto& [key, value] : doc["flip"].items()) {
    ASSERT_TRUE(labels.count(key)) << "no text label for flip/" << key;
    EXPECT_NE(text.out.find(labels.at(key)), std::string::npos) << key << "\n" << text.out;
  }
  const nlohmann::json& f = doc["flip"];
  EXPECT_EQ(f["range"], "hdr");
  EXPECT_NEAR(f["pixels_per_degree"].get<double>(), kFlipDefaultPixelsPerDegree, 1e-12);
  EXPECT_NE(text.out.find(fmt::format("{:.6f}", f["mean"].get<double>())), std::string::npos);
  EXPECT_GT(f["mean"].get<double>(), 0.0);
  EXPECT_LE(f["mean_ci"][0].get<double>(), f["mean"].get<double>());
  EXPECT_GE(f["mean_ci"][1].get<double>(), f["mean"].get<double>());
  EXPECT_GE(f["exposures"]["count"].get<int>(), 2);
  EXPECT_EQ(f["map"], path("map.png"));
  // The same number as the library's.
  FlipOptions o;
  o.range = FlipRange::kHdr;
  EXPECT_DOUBLE_EQ(f["mean"].get<double>(),
                   mean_flip(flip_map(read_image(path("b.exr")), read_image(path("a.exr")), o)));
}

// The map: magma colours in a PNG, the values themselves in an EXR.
TEST_F(CompareFlip, MapIsWrittenAsMagmaPngOrFloatExr) {
  const nlohmann::json doc =
      compare_json({path("a.exr"), path("b.exr"), "--flip-map", path("map.exr")});
  const Image values = read_image(path("map.exr"));
  ASSERT_EQ(values.channels, std::vector<std::string>{"Y"});
  ASSERT_EQ(values.width, 48);
  double sum = 0.0;
  for (float v : values.pixels) sum += v;
  EXPECT_DOUBLE_EQ(sum / double(values.pixels.size()), doc["flip"]["mean"].get<double>());
  compare_json({path("a.exr"), path("b.exr"), "--flip-map", path("map.png")});
  const Image colours = read_image(path("map.png"));
  ASSERT_EQ(colours.channels.size(), 3u);
  for (int y = 0; y < 48; y += 7)
    for (int x = 0; x < 48; x += 5) {
      const auto c = magma_rgb8(values.at(x, y, 0));
      for (int k = 0; k < 3; ++k) ASSERT_EQ(std::lround(colours.at(x, y, k) * 255.0f), c[k]);
    }
}

// auto: LDR-FLIP for PNGs, decoded from sRGB; --flip=ldr on EXRs clamps the
// radiance, what the previews show; --ppd is the viewer's.
TEST_F(CompareFlip, ModeFollowsTheInputsAndPpdTheViewer) {
  const nlohmann::json png = compare_json({path("a.png"), path("b.png"), "--no-mask", "--flip"});
  EXPECT_EQ(png["flip"]["range"], "ldr");
  EXPECT_EQ(png["flip"]["encoding"]["test"], "srgb");
  EXPECT_TRUE(png["flip"]["exposures"].is_null());
  const nlohmann::json ldr = compare_json({path("a.exr"), path("b.exr"), "--flip=ldr"});
  EXPECT_EQ(ldr["flip"]["range"], "ldr");
  EXPECT_EQ(ldr["flip"]["encoding"]["test"], "linear");
  // The previews are the EXRs clamped and quantised to 8 bits.
  EXPECT_NEAR(png["flip"]["mean"].get<double>(), ldr["flip"]["mean"].get<double>(), 0.01);
  const nlohmann::json near =
      compare_json({path("a.exr"), path("b.exr"), "--flip=ldr", "--ppd", "20"});
  EXPECT_EQ(near["flip"]["pixels_per_degree"], 20.0);
  EXPECT_NE(near["flip"]["mean"], ldr["flip"]["mean"]);
}

TEST_F(CompareFlip, BadFlipOptionsAreRefusedBeforeAnythingIsWritten) {
  const std::vector<std::string> before = files();
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--flip-map", path("map.tif")}, "expected a file name ending in .png"},
      {{"--flip=off", "--flip-map", path("map.png")}, "--flip-map needs FLIP"},
      {{"--ppd", "30"}, "--ppd is FLIP's viewing distance"},
      {{"--flip=maybe"}, "maybe"},
      {{"--flip", "--ppd", "0"}, "--ppd"},
      {{"--flip-map", path("a.exr")}, "already a file of the comparison"},
      {{"--flip-map", path("missing/map.png")}, "does not exist"}};
  for (const auto& [extra, message] : cases) {
    std::vector<std::string> args{"compare", path("a.exr"), path("b.exr"), "-o", path("d.exr")};
    args.insert(args.end(), extra.begin(), extra.end());
    const CliResult r = run_penumbra(args);
    EXPECT_EQ(r.code, kExitBadInput) << message;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
  }
  EXPECT_EQ(files(), before);
}

}  // namespace
}  // namespace penumbra
