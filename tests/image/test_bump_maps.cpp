// Height maps from files and `penumbra pyramid`: the written levels read
// back against sums computed here from the height values, 16-bit PNGs made
// by OpenImageIO's oiiotool, and bad inputs refused with nothing written.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>

#include "cli_test.h"
#include "image/bump_maps.h"
#include "image/exr_file.h"
#include "image/image_io.h"
#include "temp_dir_test.h"

namespace penumbra {
namespace {

namespace fs = std::filesystem;

class BumpMaps : public TempDirTest {
 protected:
  // A w x h single-channel EXR "Y" of heights(x, y).
  template <typename F>
  std::string write_heights(const std::string& name, int w, int h, F heights,
                            std::vector<std::string> channels = {"Y"}) {
    Image image;
    image.width = w;
    image.height = h;
    image.channels = channels;
    image.pixels.resize(std::size_t(w) * h * channels.size());
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (std::size_t c = 0; c < channels.size(); ++c) image.at(x, y, int(c)) = heights(x, y);
    write_exr_file(image, path(name), {});  // unchecked: NaN heights are a case
    return path(name);
  }
};

float grating(int x, int y) {
  return float(0.1 * std::sin(2 * kPi * x / 8.0) + 0.05 * std::cos(2 * kPi * y / 4.0));
}

TEST_F(BumpMaps, PyramidCommandWritesEveryLevelWithItsChannels) {
  const std::string heights = write_heights("heights.exr", 32, 16, grating);
  const CliResult r = run_penumbra(
      {"pyramid", heights, "-o", path("pyr"), "--texel-size", "0.01", "--height-scale", "2"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("6 levels"), std::string::npos) << r.out;
  std::ifstream in(path("pyr/pyramid.json"));
  const nlohmann::json manifest = nlohmann::json::parse(in);
  ASSERT_EQ(manifest["levels"].size(), 6u);
  EXPECT_EQ(manifest["texel_size"], 0.01);
  EXPECT_EQ(manifest["edge"], "wrap");

  // Level 0: central differences of 2 x the file's heights over 0.01,
  // v up (rows down), wrapped at the edges.
  const Image level0 = read_image(path("pyr/level_00.exr"));
  ASSERT_EQ(level0.width, 32);
  const int fu = level0.channel_index("bump.f_u"), fv = level0.channel_index("bump.f_v");
  ASSERT_GE(fu, 0);
  ASSERT_GE(fv, 0);
  double mu_u = 0, mu_v = 0, n = 32 * 16;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 32; ++x) {
      const double du = 2 * (grating((x + 1) % 32, y) - grating((x + 31) % 32, y)) / 0.02;
      const double dv = -2 * (grating(x, (y + 1) % 16) - grating(x, (y + 15) % 16)) / 0.02;
      EXPECT_NEAR(level0.at(x, y, fu), du, 1e-5 * (1 + std::abs(du)));
      EXPECT_NEAR(level0.at(x, y, fv), dv, 1e-5 * (1 + std::abs(dv)));
      mu_u += level0.at(x, y, fu) / n;
      mu_v += level0.at(x, y, fv) / n;
    }
  Covariance2 k;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 32; ++x) {
      const double du = level0.at(x, y, fu) - mu_u, dv = level0.at(x, y, fv) - mu_v;
      k.a += du * du / n;
      k.b += du * dv / n;
      k.c += dv * dv / n;
    }
  // The 1x1 level's D reproduces the covariance of every level-0 offset.
  const Image top = read_image(path("pyr/level_05.exr"));
  ASSERT_EQ(top.width, 1);
  ASSERT_EQ(top.height, 1);
  const RoughnessFactor d{top.at(0, 0, top.channel_index("roughness.d1")),
                          top.at(0, 0, top.channel_index("roughness.d2")),
                          top.at(0, 0, top.channel_index("roughness.d3"))};
  const Covariance2 back = covariance_from_factor(d);
  const double tol = 1e-5 * (k.a + k.c);
  EXPECT_NEAR(back.a, k.a, tol);
  EXPECT_NEAR(back.b, k.b, tol);
  EXPECT_NEAR(back.c, k.c, tol);
  EXPECT_GT(k.a, 100.0);  // the grating's slopes, not a flat map
  EXPECT_NEAR(top.at(0, 0, top.channel_index("roughness.lambda1")), std::sqrt(std::max(k.a, k.c)),
              1e-3 * std::sqrt(k.a));  // b ~ 0 for these separable gratings
  const float normal_length = top.at(0, 0, top.channel_index("normal.length"));
  EXPECT_GT(normal_length, 0.0f);
  EXPECT_LT(normal_length, 1.0f);
}

TEST_F(BumpMaps, RerunReplacesAPyramidButNeverAnotherFolder) {
  const std::string heights = write_heights("heights.exr", 8, 8, grating);
  ASSERT_EQ(run_penumbra({"pyramid", heights, "-o", path("pyr"), "-q"}).code, 0);
  ASSERT_EQ(run_penumbra({"pyramid", heights, "-o", path("pyr"), "-q"}).code, 0);
  EXPECT_TRUE(fs::exists(path("pyr/level_03.exr")));
  fs::create_directories(path("mine"));
  std::ofstream(path("mine/notes.txt")) << "keep";
  const CliResult r = run_penumbra({"pyramid", heights, "-o", path("mine")});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("not a pyramid folder"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(path("mine/notes.txt")));
  EXPECT_FALSE(fs::exists(path("mine/pyramid.json")));
  // No temporary folder is left beside it.
  for (const auto& entry : fs::directory_iterator(dir_))
    EXPECT_EQ(entry.path().filename().string().find("penumbra-tmp"), std::string::npos)
        << entry.path();
}

TEST_F(BumpMaps, SixteenBitPngHeightsAreReadAsTheirNormalisedValues) {
  if (std::system("command -v oiiotool > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "oiiotool (openimageio-tools) is not installed";
  const auto ramp = [](int x, int y) { return float((x + 16 * y) / 255.0); };
  write_heights("ramp.exr", 16, 16, ramp);
  ASSERT_EQ(
      std::system(("oiiotool " + path("ramp.exr") + " -d uint16 -o " + path("ramp.png")).c_str()),
      0);
  const HeightMap map = read_height_map(path("ramp.png"));
  ASSERT_EQ(map.width, 16);
  ASSERT_EQ(map.height, 16);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x)  // 16-bit quantisation: half a step of 1/65535
      EXPECT_NEAR(map.heights[y * 16 + x], ramp(x, y), 0.5 / 65535 + 1e-7);
}

// A baked grating (whole periods over the extent, so it tiles) gives the
// analytic slope times the central difference's transfer sin(w t)/(w t),
// along u for a grating in x and along v (up) for one in y: the bake and
// the pyramid agree on the texel conventions.
TEST_F(BumpMaps, BakedGratingsGiveTheAnalyticSlopes) {
  const int size = 64;
  const double extent = 1.0, t = extent / size, amplitude = 0.01, frequency = 4.0;
  for (int axis = 0; axis < 2; ++axis) {
    const Vec3 direction = axis == 0 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
    const HeightFunction f = make_grating(direction, frequency, 0.3);
    const Image map = bake_height_map(f, amplitude, size, extent);
    const PyramidLevel level = offsets_from_heights(map.pixels, size, size, t, 1.0, MapEdge::kWrap);
    const double w = 2 * kPi * frequency, transfer = std::sin(w * t) / (w * t);
    for (int y = 0; y < size; y += 7)
      for (int x = 0; x < size; x += 5) {
        const Vec3 p{(x + 0.5) * t, (size - y - 0.5) * t, 0.0};
        const Vec3 g = evaluate_height(f, p).gradient * (amplitude * transfer);
        EXPECT_NEAR(level.offset(x, y).f_u, g.x, 2e-5) << "axis " << axis;
        EXPECT_NEAR(level.offset(x, y).f_v, g.y, 2e-5) << "axis " << axis;
      }
  }
  const CliResult r =
      run_penumbra({"bake", std::string(PENUMBRA_SOURCE_DIR) + "/scenes/cylinder-weave.json", "-o",
                    path("weave.exr"), "--size", "32"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(read_height_map(path("weave.exr")).width, 32);
  EXPECT_EQ(run_penumbra({"bake", std::string(PENUMBRA_SOURCE_DIR) + "/scenes/cylinder-weave.json",
                          "-o", path("weave.png")})
                .code,
            2);
  EXPECT_FALSE(fs::exists(path("weave.png")));
}

TEST_F(BumpMaps, BadHeightMapsExitTwoNamingTheFileAndWriteNothing) {
  const auto expect_refused = [&](const std::vector<std::string>& args, const std::string& says) {
    std::vector<std::string> full = {"pyramid"};
    full.insert(full.end(), args.begin(), args.end());
    full.insert(full.end(), {"-o", path("out")});
    const CliResult r = run_penumbra(full);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find(says), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(path("out")));
  };
  expect_refused({path("missing.exr")}, "missing.exr: no such file");
  std::ofstream(path("empty.exr")).flush();
  expect_refused({path("empty.exr")}, "empty.exr: cannot read it as an image");
  const float nan = std::numeric_limits<float>::quiet_NaN();
  write_heights("nan.exr", 6, 5, [&](int x, int y) { return x == 3 && y == 2 ? nan : 0.0f; });
  expect_refused({path("nan.exr")}, "texel (3, 2)");
  write_heights("rgb.exr", 4, 4, grating, {"R", "G", "B"});
  expect_refused({path("rgb.exr")}, "has 3 channels (R, G, B)");
  expect_refused({path("rgb.exr"), "--channel", "Z"}, "no channel \"Z\"");
  EXPECT_EQ(
      run_penumbra({"pyramid", path("rgb.exr"), "--channel", "G", "-o", path("g"), "-q"}).code, 0);
  const std::string ok = write_heights("ok.exr", 4, 4, grating);
  expect_refused({ok, "--edge", "mirror"}, "--edge");
  expect_refused({ok, "--texel-size", "0"}, "texel-size");
}

}  // namespace
}  // namespace penumbra
