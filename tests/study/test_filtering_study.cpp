// The filtering section of a study: its entries are the bump-filtering
// experiment (tests/analysis/test_filtering.cpp checks the experiment
// itself) on the heights the study names, measured once and reused until
// an input changes; the section's errors name the file and the pointer; the
// report page shows it.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "malformed_study.h"
#include "study_options.h"
#include "temp_dir_test.h"

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

class FilteringStudy : public TempDirTest {
 protected:
  std::string write(const std::string& name, const json& j) const {
    std::ofstream(path(name)) << j.dump(2);
    return path(name);
  }
  // A height map file: the weave scene baked at 48 texels, times `scale`.
  void write_map(double scale) const {
    const Scene scene = load_scene(kSource + "/scenes/cylinder-weave.json");
    Image map = bake_height_map(scene.height.function, scene.height.amplitude, 48, 1.0);
    for (float& v : map.pixels) v = static_cast<float>(v * scale);
    write_exr(map, path("weave.exr"));
  }
  json study() const {
    return {
        {"version", 1},
        {"name", "filtering-test"},
        {"filtering",
         {{"maps",
           {{{"name", "noise"},
             {"bake", kSource + "/scenes/cylinder-noise.json"},
             {"size", 64},
             {"extent", 1}},
            {{"name", "weave"}, {"file", "weave.exr"}, {"texel_size", 1.0 / 48}}}},
          {"runs",
           {{{"name", "box"}}, {{"name", "mip"}, {"lookup", "trilinear"}, {"shift", "random"}}}},
          {"alphas", {0.1, 0.4}},
          {"filters", {"beckmann-variance", "ggx-variance-estevez2019", "mip-only"}},
          {"max_level", 3},
          {"footprints", 6},
          {"sweep_step_deg", 2}}}};
  }
  StudyOptions options(std::vector<std::string>* log) const {
    return test_study_options(path("out"), log, "filtering ");
  }
  // report.json less its provenance (the date differs between runs).
  json report() const {
    json r = json::parse(read_file(path("out/report.json")));
    r.erase("provenance");
    return r;
  }
};

// The entry written by the study equals, byte for byte, the experiment run
// here directly on the same heights (baked here, or read from the file) with
// one thread where the study used two.
TEST_F(FilteringStudy, EachEntryIsTheExperimentOnTheHeightsItNames) {
  write_map(1.0);
  std::vector<std::string> log;
  ASSERT_TRUE(run_study(load_study(write("f.json", study())), options(&log)).complete());
  const json entries = report().at("filtering");
  ASSERT_EQ(entries.size(), 4u);
  EXPECT_EQ(entries[0]["map"], "noise");
  EXPECT_EQ(entries[1]["run"], "mip");
  EXPECT_EQ(entries[3]["json"], "filtering/weave/mip/filtering.json");

  const Scene noise = load_scene(kSource + "/scenes/cylinder-noise.json");
  const Image baked = bake_height_map(noise.height.function, noise.height.amplitude, 64, 1.0);
  const HeightMap file = read_height_map(path("weave.exr"));
  FilteringOptions o;
  o.alphas = {0.1, 0.4};
  o.filters = {RoughnessFilter::kBeckmannVariance, RoughnessFilter::kGgxVarianceEstevez2019,
               RoughnessFilter::kMipOnly};
  o.max_level = 3, o.footprints = 6, o.sweep_step_deg = 2.0, o.jobs = 1;
  struct Expected {
    std::vector<float> heights;
    int size;
    double texel;
    std::string source, edge, folder;
  };
  const std::vector<Expected> maps = {
      {baked.pixels, 64, 1.0 / 64, kSource + "/scenes/cylinder-noise.json", "clamp", "noise"},
      {file.heights, 48, 1.0 / 48, fs::path(path("weave.exr")).lexically_normal().string(), "wrap",
       "weave"}};
  for (const Expected& m : maps) {
    const auto pyramid = build_bump_pyramid(
        offsets_from_heights(m.heights, m.size, m.size, m.texel, 1.0,
                             m.edge == "wrap" ? MapEdge::kWrap : MapEdge::kClamp));
    for (const bool mip : {false, true}) {
      o.lookup = mip ? FilteringOptions::Lookup::kTrilinear : FilteringOptions::Lookup::kBox;
      o.random_shift = mip;
      const FilteringSource source{m.source, "Y", m.size, m.size, m.texel, 1.0, m.edge};
      const std::string expected =
          filtering_json(run_filtering_experiment(pyramid, o), o, source) + "\n";
      const std::string folder = path("out/filtering/" + m.folder + (mip ? "/mip" : "/box"));
      EXPECT_EQ(read_file(folder + "/filtering.json"), expected) << folder;
    }
  }
  EXPECT_EQ(log.size(), 4u);
  for (const std::string& line : log) EXPECT_NE(line.find("measured"), std::string::npos) << line;
}

// Unchanged inputs are read back; a changed map file re-measures that map's
// entries only; a damaged result is measured again, never read back.
TEST_F(FilteringStudy, EntriesAreReusedUntilTheirInputsChange) {
  write_map(1.0);
  std::vector<std::string> log;
  const std::string file = write("f.json", study());
  ASSERT_TRUE(run_study(load_study(file), options(&log)).complete());
  const json first = report();

  log.clear();
  ASSERT_TRUE(run_study(load_study(file), options(&log)).complete());
  ASSERT_EQ(log.size(), 4u);
  for (const std::string& line : log) EXPECT_NE(line.find("reused"), std::string::npos) << line;
  EXPECT_EQ(report(), first);

  write_map(2.0);  // steeper slopes: the weave entries change
  std::ofstream(path("out/filtering/noise/mip/filtering.json")) << "{\"format\": \"penumbra-f";
  log.clear();
  ASSERT_TRUE(run_study(load_study(file), options(&log)).complete());
  ASSERT_EQ(log.size(), 4u);
  EXPECT_NE(log[0].find("reused"), std::string::npos) << log[0];
  EXPECT_NE(log[1].find("measured"), std::string::npos) << log[1];  // damaged
  EXPECT_NE(log[2].find("measured"), std::string::npos) << log[2];
  EXPECT_NE(log[3].find("measured"), std::string::npos) << log[3];
  const json second = report();
  EXPECT_EQ(second["filtering"][1], first["filtering"][1]);  // the same bits again
  EXPECT_NE(second["filtering"][2]["findings"], first["filtering"][2]["findings"]);
}

TEST_F(FilteringStudy, MalformedSectionsNameFileAndPointer) {
  write_map(1.0);
  const std::vector<MalformedCase> cases = {
      {[](json& f) { f["colour"] = 1; }, "/filtering/colour", "unknown key"},
      {[](json& f) { f.erase("maps"); }, "/filtering/maps", "missing"},
      {[](json& f) { f["maps"] = json::array(); }, "/filtering/maps", "non-empty"},
      {[](json& f) { f["maps"][0]["file"] = "weave.exr"; }, "/filtering/maps/0", "exactly one"},
      {[](json& f) { f["maps"][0]["bake"] = "nope.json"; }, "/filtering/maps/0/bake", "no such"},
      {[](json& f) { f["maps"][1]["file"] = "nope.exr"; }, "/filtering/maps/1/file", "no such"},
      {[](json& f) { f["maps"][0]["size"] = 1; }, "/filtering/maps/0/size", "[2, 16384]"},
      {[](json& f) { f["maps"][0]["channel"] = "Y"; }, "/filtering/maps/0/channel", "unknown"},
      {[](json& f) { f["maps"][1]["edge"] = "mirror"; }, "/filtering/maps/1/edge", "\"wrap\""},
      {[](json& f) { f["maps"][1]["name"] = "noise"; }, "/filtering/maps/1/name", "repeats"},
      {[](json& f) { f["maps"][1]["name"] = "../x"; }, "/filtering/maps/1/name", "letters"},
      {[](json& f) { f["runs"][1]["lookup"] = "bilinear"; }, "/filtering/runs/1/lookup", "box"},
      {[](json& f) { f["runs"][1]["shift"] = 1; }, "/filtering/runs/1/shift", "[0, 1)"},
      {[](json& f) { f["filters"][0] = "schilling1997"; }, "/filtering/filters/0", "normalised"},
      {[](json& f) { f["filters"][1] = "blur"; }, "/filtering/filters/1", "roughness filter"},
      {[](json& f) { f["alphas"][0] = 0; }, "/filtering/alphas/0", "(0, 1]"},
      {[](json& f) { f["max_level"] = 15; }, "/filtering/max_level", "[0, 14]"},
      {[](json& f) { f["sweep_step_deg"] = 0; }, "/filtering/sweep_step_deg", "(0, 10]"},
  };
  expect_refused(study(), "filtering", cases, [&](const json& j) { return write("bad.json", j); });
}

// The page of a filtering-only study: the section, one part per entry with
// its table, findings and the three metric figures.
TEST_F(FilteringStudy, ReportPageShowsEveryEntry) {
  write_map(1.0);
  json j = study();
  j["filtering"]["maps"].erase(1);
  std::vector<std::string> log;
  StudyOptions o = options(&log);
  o.figures = true;
  const StudyRunStats stats = run_study(load_study(write("f.json", j)), o);
  ASSERT_TRUE(stats.complete());
  ASSERT_FALSE(stats.report_html.empty()) << read_file(path("out/report.log"));
  const std::string page = read_file(stats.report_html);
  EXPECT_NE(page.find("id=\"filtering\""), std::string::npos);
  for (const char* anchor : {"filtering-noise-box", "filtering-noise-mip"})
    EXPECT_NE(page.find(std::string("id=\"") + anchor + "\""), std::string::npos) << anchor;
  EXPECT_NE(page.find("Perceived roughness"), std::string::npos);
  for (const char* metric : {"profile_error", "width_ratio", "energy_ratio"})
    EXPECT_TRUE(fs::exists(path(std::string("out/figures/filtering-noise-mip-") + metric + ".png")))
        << metric;
}

}  // namespace
}  // namespace penumbra
