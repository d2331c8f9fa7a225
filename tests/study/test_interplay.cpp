// The terminator-interplay section of a study: its renders are the scenes a
// user would write by hand (the baked map, the filter at each level, the
// method), its numbers are the profile comparison of those renders with the
// map's displacement, a rerun renders nothing, and its errors name the file
// and the pointer.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "malformed_study.h"
#include "study_options.h"
#include "temp_dir_test.h"

#include "analysis/metrics.h"
#include "evaluator/evaluator.h"
#include "image/bump_maps.h"
#include "image/image_io.h"
#include "scene/scene_json.h"
#include "study/study.h"
#include "util/files.h"

namespace penumbra {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kSource = PENUMBRA_SOURCE_DIR;
const std::string kScene = kSource + "/scenes/cylinder-grating.json";

// Every channel of `expected` holds the same bits in `actual` (which may
// order its channels differently: the cache's EXR is read back by name).
void expect_same_channels(const Image& actual, const Image& expected) {
  ASSERT_EQ(actual.width, expected.width);
  ASSERT_EQ(actual.height, expected.height);
  for (std::size_t c = 0; c < expected.channels.size(); ++c) {
    const int a = actual.channel_index(expected.channels[c]);
    ASSERT_GE(a, 0) << expected.channels[c];
    for (int y = 0; y < expected.height; ++y)
      for (int x = 0; x < expected.width; ++x)
        ASSERT_EQ(actual.at(x, y, a), expected.at(x, y, int(c)))
            << expected.channels[c] << " at " << x << ", " << y;
  }
}

class Interplay : public TempDirTest {
 protected:
  json study() const {
    return {{"version", 1},
            {"name", "interplay-test"},
            {"interplay",
             {{"scene", kScene},
              {"size", 128},
              {"filter", "pixar2014"},
              {"levels", {nullptr, 3}},
              {"methods", {"none", "estevez2019"}},
              {"set",
               {{"/camera/width", 40},
                {"/camera/height", 40},
                {"/camera/spp", 4},
                {"/displacement/edge_length", 0.02}}}}}};
  }
  std::string write(const json& j) const {
    std::ofstream(path("s.json")) << j.dump(2);
    return path("s.json");
  }
  StudyOptions options(std::vector<std::string>* log) const {
    return test_study_options(path("out"), log, "interplay: ");
  }
  // The scene a user writes by hand: the grating baked over the cylinder at
  // 128 texels around (penumbra bake --on shape), loaded as a height map.
  Scene by_hand(const std::vector<std::string>& sets) const {
    std::vector<Override> base{parse_override("/camera/width=40"),
                               parse_override("/camera/height=40"), parse_override("/camera/spp=4"),
                               parse_override("/displacement/edge_length=0.02")};
    const Scene analytic = load_scene(kScene, base);
    const MapLengths lengths = map_lengths(analytic.shape);
    const int rows = static_cast<int>(std::lround(128 * lengths.v / lengths.u));
    write_exr(bake_surface_map(analytic.shape, analytic.height.function, analytic.height.amplitude,
                               128, rows, MapKind::kHeight),
              path("hand.exr"));
    base.push_back(
        {"/height", json{{"type", "height-map"}, {"file", path("hand.exr")}, {"amplitude", 1}}});
    for (const std::string& s : sets) base.push_back(parse_override(s));
    return load_scene(kScene, base);
  }
};

TEST_F(Interplay, RowsAreTheHandWrittenRendersComparedWithTheMapsDisplacement) {
  std::vector<std::string> log;
  ASSERT_TRUE(run_study(load_study(write(study())), options(&log)).complete());
  const json report = json::parse(read_file(path("out/report.json")));
  const json& ip = report.at("interplay");
  ASSERT_EQ(ip.at("rows").size(), 4u);
  ASSERT_EQ(ip["map"]["size"], json({128, 41}));

  // The truth and the unfiltered estevez2019 row, rendered here by hand,
  // are the cache's entries bit for bit.
  const Image truth = read_image(path("out/" + ip["truth"].get<std::string>()));
  expect_same_channels(truth, render(by_hand({"/representation=displacement"})));
  const json& row = ip["rows"][1];
  ASSERT_EQ(row["method"], "estevez2019");
  ASSERT_TRUE(row["level"].is_null());
  const Image bump = read_image(path("out/" + row["image"].get<std::string>()));
  expect_same_channels(bump, render(by_hand({"/terminator/method=estevez2019"})));

  // Each row's number is the profile comparison of its render with the truth.
  const double scale = radiance_scale(by_hand({}));
  const Profile reference = terminator_profile(truth, scale);
  for (const json& r : ip["rows"]) {
    const Image image = read_image(path("out/" + r["image"].get<std::string>()));
    const double rmse =
        compare_profiles(terminator_profile(image, scale), reference).rmse_terminator;
    EXPECT_DOUBLE_EQ(r["rmse_terminator"].get<double>(), rmse) << r.dump();
    EXPECT_LE(r["rmse_terminator_ci"][0].get<double>(), r["rmse_terminator_ci"][1].get<double>());
  }
  // The filtered row differs from the unfiltered one: the filter was applied.
  EXPECT_NE(ip["rows"][0]["image"], ip["rows"][2]["image"]);
  EXPECT_NE(ip["rows"][0]["rmse_terminator"], ip["rows"][2]["rmse_terminator"]);
  ASSERT_FALSE(ip["findings"].empty());

  log.clear();
  ASSERT_TRUE(run_study(load_study(write(study())), options(&log)).complete());
  ASSERT_FALSE(log.empty());
  EXPECT_NE(log.back().find("0 rendered now, 6 from the cache"), std::string::npos) << log.back();
  EXPECT_EQ(json::parse(read_file(path("out/report.json")))["interplay"], ip);
}

// The section's renders are the run's: counted with it, rendered by its
// executor, stopped with it (no report from a partial run) and taken from
// the cache when it resumes.
TEST_F(Interplay, ItsRendersJoinTheRunsRenderPhase) {
  StudyOptions o = options(nullptr);
  o.max_new_renders = 2;
  const StudyRunStats stopped = run_study(load_study(write(study())), o);
  EXPECT_EQ(stopped.renders, 6u);
  EXPECT_EQ(stopped.rendered, 2u);
  EXPECT_EQ(stopped.not_started, 4u);
  EXPECT_FALSE(fs::exists(path("out/report.json")));
  o.max_new_renders = -1;
  const StudyRunStats rest = run_study(load_study(write(study())), o);
  EXPECT_TRUE(rest.complete());
  EXPECT_EQ(rest.renders, 6u);
  EXPECT_EQ(rest.cached, 2u);
  EXPECT_EQ(rest.rendered, 4u);
  EXPECT_TRUE(fs::exists(path("out/report.json")));
}

TEST_F(Interplay, MalformedSectionsNameFileAndPointer) {
  const std::vector<MalformedCase> cases = {
      {[](json& s) { s["colour"] = 1; }, "/interplay/colour", "unknown key"},
      {[](json& s) { s.erase("scene"); }, "/interplay/scene", "missing"},
      {[](json& s) { s["scene"] = "nope.json"; }, "/interplay/scene", "scene file"},
      {[](json& s) { s["size"] = 8; }, "/interplay/size", "[16, 16384]"},
      {[](json& s) { s["filter"] = "schilling1997"; }, "/interplay/filter", "with a BRDF"},
      {[](json& s) { s["levels"][1] = -1; }, "/interplay/levels/1", "null (unfiltered)"},
      {[](json& s) { s["levels"] = json::array(); }, "/interplay/levels", "non-empty"},
      {[](json& s) { s["methods"][1] = "bogus"; }, "/interplay/methods/1", "method id"},
      {[](json& s) { s["set"] = 3; }, "/interplay/set", "object"},
  };
  expect_refused(study(), "interplay", cases, [&](const json& j) { return write(j); });
}

}  // namespace
}  // namespace penumbra
