// Studies: expansion, cache, interruption and resume, reports, and the
// report in a real browser.
#include <gtest/gtest.h>

#include <algorithm>

#include "malformed_study.h"
#include "study_options.h"
#include "temp_dir_test.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include <map>
#include <set>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "analysis/contour.h"
#include "analysis/metrics.h"
#include "evaluator/evaluator.h"
#include "image/image_io.h"
#include "scene/scene_json.h"
#include "study/cache.h"
#include "study/figures.h"
#include "study/plan.h"
#include "study/report_files.h"
#include "study/study.h"
#include "util/process.h"

namespace penumbra {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kSource = PENUMBRA_SOURCE_DIR;

class Study : public TempDirTest {
 protected:
  std::string write(const std::string& name, const json& j) const {
    std::ofstream(path(name)) << j.dump(2);
    return path(name);
  }
  // A small study: 2 variants x (evaluator 1 + 3 methods, POV-Ray 2) renders,
  // and one convergence check of each evaluator truth (3 renders, one of
  // them the truth itself).
  json tiny() const {
    return {{"version", 1},
            {"name", "tiny"},
            {"scenes", {kSource + "/scenes/calibration/sphere.json"}},
            {"set",
             {{"/camera/width", 32},
              {"/camera/height", 32},
              {"/camera/spp", 4},
              {"/displacement/edge_length", 0.02}}},
            {"axes", {{{"pointer", "/height/amplitude"}, {"values", {0.01, 0.02}}}}},
            {"methods", {"none", "chiang2019", "estevez2019"}},
            {"renderers", {"evaluator", "povray"}},
            {"ground_truth", {{"max_edge_refinements", 1}, {"max_spp_refinements", 1}}}};
  }
  // tiny() at 8 x 8 pixels, the evaluator alone, with `method`.
  json tiny_evaluator(const std::string& method) const {
    json j = tiny();
    j["set"]["/camera/width"] = j["set"]["/camera/height"] = 8;
    j["methods"] = {method};
    j["renderers"] = {"evaluator"};
    return j;
  }
};

std::string read_text(const std::string& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The cache entry `exr` (its header's `attributes`) has the bits of its own
// scene, the one its header records, rendered alone. The cache stores the
// channels sorted by name: they are compared channel by channel.
template <typename Attributes>
void expect_its_own_render(const std::string& exr, const Attributes& attributes) {
  const Image cached = read_image(exr);
  const Image alone =
      penumbra::render(scene_from_json(json::parse(attributes.at("penumbra:scene")), exr));
  ASSERT_EQ(cached.pixels.size(), alone.pixels.size());
  for (const std::string& name : alone.channels) {
    const int a = alone.channel_index(name), c = cached.channel_index(name);
    ASSERT_GE(c, 0) << name;
    for (int y = 0; y < alone.height; ++y)
      for (int x = 0; x < alone.width; ++x)
        ASSERT_EQ(cached.at(x, y, c), alone.at(x, y, a)) << exr << " " << name;
  }
}

TEST_F(Study, InterruptedAndResumedEqualsCleanWithNoRenderDoneTwice) {
  const ::penumbra::Study study = load_study(write("tiny.json", tiny()));
  StudyOptions clean;
  clean.output_dir = path("clean");
  clean.parallelism = resolve_parallelism(2);
  clean.figures = false;
  // A dry run counts from the cache alone: the first round of checks (3
  // per variant) and the 12 planned renders, none cached yet.
  StudyOptions dry = clean;
  dry.dry_run = true;
  const StudyRunStats d0 = run_study(study, dry);
  EXPECT_EQ(d0.renders, 2u * (4 + 2));
  EXPECT_EQ(d0.cached, 0u);
  EXPECT_EQ(d0.planned_checks, 2u * 3);
  EXPECT_FALSE(fs::exists(path("clean")));
  const StudyRunStats a = run_study(study, clean);
  ASSERT_TRUE(a.complete());
  // Afterwards it replays the convergence from the cached checks and finds
  // every render the run used, with the settings the truths reached.
  const StudyRunStats d1 = run_study(study, dry);
  EXPECT_EQ(d1.planned_checks, 0u);
  EXPECT_EQ(d1.cached, d1.renders);
  // The plan, plus 3 check renders per variant; the truth is one of them.
  EXPECT_EQ(a.renders, 2u * (4 + 2) + 2u * 3);
  EXPECT_EQ(a.rendered, a.renders - 2);
  EXPECT_EQ(a.cached, 2u);

  StudyOptions first = clean;
  first.output_dir = path("resumed");
  first.max_new_renders = 5;  // the "interrupt"
  const StudyRunStats b1 = run_study(study, first);
  EXPECT_EQ(b1.rendered, 5u);
  EXPECT_EQ(b1.not_started, 2u * 3 - 5);                  // stopped inside the convergence checks
  EXPECT_FALSE(fs::exists(path("resumed/report.json")));  // no report from a partial study
  StudyOptions dry_resumed = dry;
  dry_resumed.output_dir = first.output_dir;
  EXPECT_EQ(run_study(study, dry_resumed).planned_checks, 1u);  // the check not started
  StudyOptions second = first;
  second.max_new_renders = -1;
  const StudyRunStats b2 = run_study(study, second);
  EXPECT_EQ(b2.cached, 5u + 2u);
  EXPECT_EQ(b2.rendered, a.rendered - 5);  // each render exactly once over both runs
  ASSERT_TRUE(b2.complete());
  EXPECT_EQ(report_without_provenance(path("clean/report.json")),
            report_without_provenance(path("resumed/report.json")));
  EXPECT_EQ(read_text(path("clean/metrics.csv")), read_text(path("resumed/metrics.csv")));
  // A third run renders nothing.
  const StudyRunStats b3 = run_study(study, second);
  EXPECT_EQ(b3.rendered, 0u);
  EXPECT_EQ(b3.cached, a.renders);
  // The report says the budget could not converge the truths, and why.
  const json report = json::parse(read_text(path("clean/report.json")));
  ASSERT_EQ(report["ground_truth"]["variants"].size(), 2u);
  EXPECT_FALSE(report["ground_truth"]["variants"][0]["converged"].get<bool>());
  EXPECT_NE(report["ground_truth"]["headline"].get<std::string>().find("0 of 2"),
            std::string::npos);
}

// A rerun takes every comparison from the study's comparison store, keeps
// every picture, and writes the same report; a damaged store is measured again, with a warning,
// to the same report; a render that changes is compared again, alone.
TEST_F(Study, ComparisonsAreKeptBetweenRunsAndGiveTheSameReport) {
  json j = tiny();
  j["renderers"] = {"evaluator"};
  const ::penumbra::Study study = load_study(write("tiny.json", j));
  const StudyOptions o = test_study_options(path("out"));
  const StudyRunStats first = run_study(study, o);
  ASSERT_TRUE(first.complete());
  EXPECT_EQ(first.comparisons_kept, 0u);
  EXPECT_EQ(first.comparisons_measured, 2u * 3);  // 3 methods x 2 variants
  // Every render's preview, and each test render's difference from its truth
  // and FLIP map against it.
  EXPECT_EQ(first.pictures_drawn, 2u * (1 + 3 + 3 + 3));
  EXPECT_EQ(first.pictures_kept, 0u);
  const std::string report = report_without_provenance(path("out/report.json"));
  const std::string csv = read_text(path("out/metrics.csv"));
  const StudyRunStats second = run_study(study, o);
  EXPECT_EQ(second.comparisons_measured, 0u);
  EXPECT_EQ(second.comparisons_kept, first.comparisons_measured);
  EXPECT_EQ(second.pictures_drawn, 0u);
  EXPECT_EQ(second.pictures_kept, first.pictures_drawn);
  EXPECT_EQ(report_without_provenance(path("out/report.json")), report);
  EXPECT_EQ(read_text(path("out/metrics.csv")), csv);

  const std::string store = path("out/cache/comparisons.bin");
  const std::string kept = read_text(store);
  std::ofstream(store, std::ios::binary | std::ios::trunc) << kept.substr(0, kept.size() - 1);
  const StudyRunStats damaged = run_study(study, o);
  EXPECT_EQ(damaged.comparisons_measured, first.comparisons_measured);
  ASSERT_EQ(damaged.warnings.size(), 1u);
  EXPECT_NE(damaged.warnings[0].find(store), std::string::npos) << damaged.warnings[0];
  EXPECT_EQ(report_without_provenance(path("out/report.json")), report);
  EXPECT_EQ(read_text(store), kept);  // rewritten whole

  // One render replaced by another image under its key (as a renderer that
  // is not deterministic would re-render it): only its comparison is new.
  std::string exr;  // "cache/KEY.exr"
  const json parsed = json::parse(report);
  for (const json& render : parsed["variants"][0]["renders"])
    if (render["method"] == "chiang2019") exr = render["exr"].get<std::string>();
  ASSERT_EQ(exr.rfind("cache/", 0), 0u) << exr;
  const std::string key = fs::path(exr).stem().string();
  const RenderCache cache(path("out/cache"));
  std::string reason;
  std::optional<Image> image = cache.lookup(key, &reason);
  ASSERT_TRUE(image) << reason;
  image->pixels[image->pixels.size() / 2] += 0.25f;
  std::vector<std::pair<std::string, std::string>> metadata;
  for (const auto& [name, value] : read_image_attributes(path("out/" + exr)))
    if (name.rfind("penumbra:", 0) == 0 && name != "penumbra:key" && name != "penumbra:checksum")
      metadata.push_back({name, value});
  cache.store(key, *image, metadata);
  const StudyRunStats changed = run_study(study, o);
  EXPECT_EQ(changed.comparisons_measured, 1u);
  EXPECT_EQ(changed.comparisons_kept, first.comparisons_measured - 1);
  EXPECT_EQ(changed.pictures_drawn, 3u) << "its preview, its difference and its FLIP map";
  EXPECT_EQ(changed.pictures_kept, first.pictures_drawn - 3);
}

// The evaluator renders the methods of a variant in one pass; each cache
// entry has the bits of its own scene (the one its header records) rendered
// alone.
TEST_F(Study, MethodsOfAVariantShareAPassWithTheBitsOfSeparateRenders) {
  json j = tiny();
  j["renderers"] = {"evaluator"};
  j["methods"] = {"none", "chiang2019", "estevez2019", "microshadow-chan2018",
                  "schuessler2017-walk"};
  const ::penumbra::Study study = load_study(write("tiny.json", j));
  const StudyRunStats stats = run_study(study, test_study_options(path("out")));
  ASSERT_TRUE(stats.complete());
  EXPECT_EQ(stats.method_batches, 2u);   // one per variant
  EXPECT_EQ(stats.batched_renders, 8u);  // all but the random walk
  const json report = json::parse(read_text(path("out/report.json")));
  int checked = 0;
  for (const json& variant : report["variants"])
    for (const json& render : variant["renders"]) {
      const std::string exr = path("out/" + render["exr"].get<std::string>());
      const auto attributes = read_image_attributes(exr);
      if (attributes.at("penumbra:representation") != "bump") continue;
      expect_its_own_render(exr, attributes);
      ++checked;
    }
  EXPECT_EQ(checked, 2 * 5);
}

// The displacement truths of variants that differ only in their light (and
// their convergence checks) share a pass; every truth in the cache has the
// bits of its own scene (the one its header records) rendered alone.
TEST_F(Study, TruthsOfOneGeometryShareAPassWithTheBitsOfSeparateRenders) {
  json j = tiny();
  j["renderers"] = {"evaluator"};
  j["methods"] = {"none"};
  j["axes"] = {{{"pointer", "/height/amplitude"}, {"values", {0.02}}},
               {{"pointer", "/light/direction"}, {"values", {{-1, 0, -0.2}, {-1, 0, 0.4}}}}};
  // 16 jittered samples: the sample check's 64 extend the truth's sums.
  j["set"]["/camera/spp"] = 16;
  j["set"]["/camera/jitter"] = true;
  const ::penumbra::Study study = load_study(write("tiny.json", j));
  const StudyRunStats stats = run_study(study, test_study_options(path("out")));
  ASSERT_TRUE(stats.complete());
  // The first round's truth, edge and sample checks: each a pass of both lights.
  EXPECT_GE(stats.truth_batches, 3u);
  EXPECT_EQ(stats.batched_truths, 2 * stats.truth_batches);
  int checked = 0, extended = 0;
  for (const auto& entry : fs::directory_iterator(path("out/cache"))) {
    if (entry.path().extension() != ".exr") continue;
    const std::string exr = entry.path().string();
    const auto attributes = read_image_attributes(exr);
    if (attributes.at("penumbra:representation") != "displacement") continue;
    expect_its_own_render(exr, attributes);  // extended or not, the bits of a render from scratch
    ++checked;
    extended +=
        attributes.count("penumbra:resumed_spp") && attributes.at("penumbra:resumed_spp") == "16";
  }
  EXPECT_GE(checked, 6);
  EXPECT_EQ(extended, 2) << "each light's sample check extends its truth's 16 samples";

  // Interrupted after the first render, inside a shared pass: the pass's
  // other truth is not cached, and the resumed run renders it once, and
  // every other render once, to the same report.
  StudyOptions first = test_study_options(path("resumed"));
  first.max_new_renders = 1;
  const StudyRunStats b1 = run_study(study, first);
  EXPECT_EQ(b1.rendered, 1u);
  StudyOptions second = first;
  second.max_new_renders = -1;
  const StudyRunStats b2 = run_study(study, second);
  ASSERT_TRUE(b2.complete());
  EXPECT_EQ(b1.rendered + b2.rendered, stats.rendered);
  EXPECT_EQ(report_without_provenance(path("out/report.json")),
            report_without_provenance(path("resumed/report.json")));

  // Each truth alone (--no-shared-truths): no truth pass, the same report
  // and metrics.csv to the byte.
  StudyOptions alone = test_study_options(path("alone"));
  alone.shared_truths = false;
  const StudyRunStats c = run_study(study, alone);
  ASSERT_TRUE(c.complete());
  EXPECT_EQ(c.truth_batches, 0u);
  EXPECT_EQ(report_without_provenance(path("out/report.json")),
            report_without_provenance(path("alone/report.json")));
  EXPECT_EQ(read_text(path("out/metrics.csv")), read_text(path("alone/metrics.csv")));
}

// A compound axis sets several pointers per value; a renderer that cannot
// render one value's scene (POV-Ray: the GGX lobe) renders the others, and
// the report lists the variants it left out, with the reason.
TEST_F(Study, CompoundAxisSetsSeveralPointersAndSkipsWhatARendererCannotRender) {
  json j = tiny();
  j["axes"] = {
      {{"name", "shading"},
       {"label", "material and lobes"},
       {"values",
        {{{"label", "Lambert"}, {"set", {{"/terminator/lobes", "diffuse"}}}},
         {{"label", "GGX, all lobes"},
          {"id", "ggx-all"},
          {"set", {{"/material/specular", {{"weight", 0.4}}}, {"/terminator/lobes", "all"}}}}}}}};
  j["methods"] = {"none", "cycles45", "schuessler2017-walk"};
  const ::penumbra::Study study = load_study(write("compound.json", j));
  StudyOptions o;
  o.output_dir = path("out");
  o.parallelism = resolve_parallelism(2);
  o.figures = false;
  ASSERT_TRUE(run_study(study, o).complete());
  const json report = json::parse(read_text(path("out/report.json")));
  const json& axis = report.at("axes").at(0);
  EXPECT_EQ(axis.at("pointer"), "shading");
  EXPECT_EQ(axis.at("values"), json({"Lambert", "GGX, all lobes"}));
  EXPECT_EQ(axis.at("sets").at(1).at("/terminator/lobes"), "all");
  // POV-Ray renders the Lambert variant only, and says why not the other.
  std::size_t povray = 0;
  for (const json& c : report.at("comparisons")) povray += c.at("renderer") == "povray";
  EXPECT_EQ(povray, 2u);  // none vs its own truth and vs the evaluator's, one variant
  bool listed = false;
  for (const json& m : report.at("missing"))
    if (m.contains("variants")) {
      listed = m.at("renderer") == "povray" && m.at("variants") == json({"v001"}) &&
               m.at("why").get<std::string>().find("GGX") != std::string::npos;
    }
  EXPECT_TRUE(listed) << report.at("missing").dump();
  // Short ids: the study's own, else made from the label; the CSV's axis
  // column holds them, not the labels.
  EXPECT_EQ(axis.at("value_ids"), json({"lambert", "ggx-all"}));
  const std::string csv = read_text(path("out/metrics.csv"));
  EXPECT_NE(csv.find(",ggx-all,"), std::string::npos);
  EXPECT_EQ(csv.find("GGX, all lobes"), std::string::npos);
}

TEST_F(Study, ReportIsWrittenAsDumpedAndCsvHasOneRowPerComparison) {
  const ::penumbra::Study study = load_study(write("tiny.json", tiny()));
  StudyOptions o;
  o.output_dir = path("out");
  o.parallelism = resolve_parallelism(2);
  o.figures = false;
  ASSERT_TRUE(run_study(study, o).complete());
  const std::string text = read_text(path("out/report.json"));
  const json report = json::parse(text);
  EXPECT_EQ(report.at("format"), "penumbra-report");
  EXPECT_EQ(report.at("version"), kReportFormatVersion);
  EXPECT_EQ(report.dump(1) + "\n", text);
  // Comparisons: per variant, evaluator 3 methods vs its ground truth, and
  // POV-Ray's none vs its own and vs the evaluator's.
  const auto& comparisons = report.at("comparisons");
  EXPECT_EQ(comparisons.size(), 2u * (3 + 2));
  std::istringstream csv(read_text(path("out/metrics.csv")));
  std::string line;
  std::size_t lines = 0, headers = 0;
  while (std::getline(csv, line)) {
    ++lines;
    headers += line.rfind("study,", 0) == 0;
  }
  EXPECT_EQ(headers, 1u);
  EXPECT_EQ(lines, comparisons.size() + 1);
  // The renderer that cannot provide a row says so.
  bool povray_chiang_missing = false;
  for (const json& m : report.at("missing"))
    povray_chiang_missing |= m.at("renderer") == "povray" && m.at("method") == "chiang2019";
  EXPECT_TRUE(povray_chiang_missing);
  // Every metric states a unit.
  EXPECT_TRUE(comparisons[0].at("profile").contains("unit"));
  EXPECT_TRUE(comparisons[0].at("image").contains("unit"));
}

TEST_F(Study, MalformedStudiesNameFileAndPointer) {
  const std::vector<MalformedCase> cases = {
      {[](json& j) { j["colour"] = 1; }, "/colour", "unknown key"},
      {[](json& j) { j["version"] = 7; }, "/version", "expected 1"},
      {[](json& j) { j.erase("scenes"); }, "/scenes", "missing"},
      {[](json& j) { j["scenes"] = {"no-such.json"}; }, "/scenes/0", "no such scene file"},
      {[](json& j) {
         j["methods"] = {"none", "bogus"};
       },
       "/methods/1", "unknown method"},
      {[](json& j) {
         j["renderers"] = {"evaluator", "mitsuba"};
       },
       "/renderers/1", "expected"},
      {[](json& j) { j["renderers"] = {"povray"}; }, "/renderers", "must include"},
      {[](json& j) {
         j["ground_truth"] = {{"tolerance", 0}};
       },
       "/ground_truth/tolerance", "expected a number in (0, 1]"},
      {[](json& j) {
         j["ground_truth"] = {{"max_spp_refinements", 9}};
       },
       "/ground_truth/max_spp_refinements", "expected an integer in [0, 5]"},
      {[](json& j) {
         j["ground_truth"] = {{"spp", 4}};
       },
       "/ground_truth/spp", "unknown key"},
      {[](json& j) { j["axes"][0]["values"] = json::array(); }, "/axes/0/values", "non-empty"},
      {[](json& j) { j["axes"][0]["pointer"] = "height"; }, "/axes/0/pointer", "JSON pointer"},
      {[](json& j) {
         j["plots"] = {
             {{"metric", "nonsense"}, {"x", "/height/amplitude"}, {"y", "/height/amplitude"}}};
       },
       "/plots/0/metric", "expected one of"},
      {[](json& j) {
         j["plots"] = {{{"metric", "image.ssim"}, {"x", "/nope"}, {"y", "/height/amplitude"}}};
       },
       "/plots/0/x", "axes"},
      {[](json& j) {
         j["figures"] = {{"methods", {"mitsuba3"}}};
       },
       "/figures/methods/0", "not in the study"},
      {[](json& j) {
         j["figures"] = {{"method", {"none"}}};
       },
       "/figures/method", "unknown key"},
      {[](json& j) {
         j["axes"] = {
             {{"name", "shading"},
              {"values",
               {{{"label", "a"}, {"id", "Bad Id"}, {"set", {{"/terminator/lobes", "all"}}}}}}}};
       },
       "/axes/0/values/0/id", "short id"},
      {[](json& j) {
         const json value = {
             {"label", "a"}, {"id", "same"}, {"set", {{"/terminator/lobes", "all"}}}};
         j["axes"] = {{{"name", "shading"}, {"values", {value, value}}}};
       },
       "/axes/0/values/1/id", "already used"},
  };
  expect_refused(tiny(), "", cases, [&](const json& j) { return write("bad.json", j); });
  // A pointer that names no scene value fails when the study expands, with
  // the scene file in the message.
  json j = tiny();
  j["axes"][0]["pointer"] = "/height/amplitud";
  StudyOptions o;
  o.output_dir = path("out");
  o.figures = false;
  EXPECT_THROW(run_study(load_study(write("bad.json", j)), o), InputError);
}

// A low-poly study: every offset against the analytic render; the analytic
// render is one per scene and renderer whatever the tessellation level.
TEST_F(Study, LowPolyStudyComparesEveryOffsetWithTheAnalyticSurface) {
  const json j = {
      {"version", 1},
      {"name", "tiny-lowpoly"},
      {"lowpoly",
       {{"scenes", {kSource + "/scenes/lowpoly/sphere.json"}},
        {"set", {{"/camera/width", 32}, {"/camera/height", 32}, {"/camera/spp", 4}}},
        {"axes", {{{"pointer", "/shape/tessellation/segments"}, {"values", {8, 64}}}}},
        {"convergence", "/shape/tessellation/segments"},
        {"offsets",
         {"none", "hanika2021", {{"id", "epsilon"}, {"parameters", {{"distance", 0.02}}}}}},
        {"renderers", {"evaluator"}}}}};
  StudyOptions o;
  o.output_dir = path("out");
  o.parallelism = resolve_parallelism(2);
  o.figures = false;
  const StudyRunStats stats = run_study(load_study(write("lp.json", j)), o);
  ASSERT_TRUE(stats.complete());
  EXPECT_EQ(stats.renders, 2u * (1 + 3));
  EXPECT_EQ(stats.rendered, 2u * 3 + 1);  // the shared analytic render once
  const json report = json::parse(read_text(path("out/report.json")));
  // Low-poly scenes have no bump methods: no (empty) rows in the bump ranking.
  EXPECT_TRUE(report.at("ranking").at("per_scene").empty()) << report.at("ranking").dump();
  const json& lowpoly = report.at("lowpoly");
  EXPECT_EQ(lowpoly.at("comparisons").size(), 2u * 3);
  EXPECT_EQ(lowpoly.at("convergence_axis"), "/shape/tessellation/segments");
  std::map<std::string, double> darkened_at_8;
  for (const json& c : lowpoly.at("comparisons")) {
    EXPECT_EQ(c.at("reference"), "evaluator:analytic");
    EXPECT_TRUE(c.at("shadow").contains("unit"));
    if (c.at("axis_values")[0] == 8)
      darkened_at_8[c.at("offset")] = c.at("shadow").at("darkened_fraction").get<double>();
  }
  EXPECT_GT(darkened_at_8.at("none"), darkened_at_8.at("hanika2021"));
  const json& overall = lowpoly.at("ranking").at("overall");
  ASSERT_EQ(overall.size(), 3u);
  // Each mean with its interval; each offset after the first paired with it
  // on the same scene and levels (here both levels of the one scene).
  EXPECT_TRUE(overall[0].at("versus_best").is_null());
  const double first = overall[0].at("darkened_fraction").get<double>();
  for (const json& e : overall) {
    const double mean = e.at("darkened_fraction").get<double>();
    EXPECT_LE(e.at("darkened_fraction_ci")[0].get<double>(), mean) << e.dump();
    EXPECT_GE(e.at("darkened_fraction_ci")[1].get<double>(), mean) << e.dump();
    if (e.at("versus_best").is_null()) continue;
    const json& vb = e.at("versus_best");
    EXPECT_EQ(vb.at("pairs"), 2);
    // Every pair shared: the mean difference is the difference of the means.
    const double d = vb.at("mean_difference").get<double>();
    EXPECT_NEAR(d, mean - first, 1e-12);
    const double low = vb.at("ci")[0].get<double>(), high = vb.at("ci")[1].get<double>();
    EXPECT_TRUE(low <= d && d <= high) << vb.dump();
    EXPECT_EQ(vb.at("tie").get<bool>(), low <= 0.0 && 0.0 <= high) << vb.dump();
  }
  // lowpoly.csv: one header, one row per comparison.
  std::istringstream csv(read_text(path("out/lowpoly.csv")));
  std::string line;
  std::size_t lines = 0;
  while (std::getline(csv, line)) ++lines;
  EXPECT_EQ(lines, lowpoly.at("comparisons").size() + 1);
  // A misspelt offset names its pointer.
  json bad = j;
  bad["lowpoly"]["offsets"][1] = "hanika";
  try {
    load_study(write("bad.json", bad));
    ADD_FAILURE() << "accepted an unknown offset";
  } catch (const InputError& e) {
    EXPECT_EQ(e.pointer(), "/lowpoly/offsets/1") << e.what();
  }
}

// The bump section's keys in a study without its scenes would sweep
// nothing: refused as unused, naming the key.
// The efficiency figure's render cost (StudyRunStats::render_core_seconds)
// is what the cache entries this run wrote record: wall seconds times
// threads, summed, within the rounding of their 3-decimal wall seconds.
TEST_F(Study, RenderCostIsTheSumOfWhatTheNewCacheEntriesRecord) {
  const StudyRunStats stats =
      run_study(load_study(write("cost.json", tiny_evaluator("chiang2019"))),
                test_study_options(path("out")));
  ASSERT_TRUE(stats.complete());
  double recorded = 0.0, rounding = 0.0;
  std::size_t entries = 0;
  for (const fs::directory_entry& e : fs::directory_iterator(path("out/cache"))) {
    if (e.path().extension() != ".exr") continue;
    std::map<std::string, std::string> attributes;
    read_image(e.path().string(), &attributes);
    const double threads = std::stod(attributes.at("penumbra:threads"));
    recorded += std::stod(attributes.at("penumbra:wall_seconds")) * threads;
    rounding += 0.0005 * threads;
    ++entries;
  }
  ASSERT_EQ(entries, stats.rendered);  // a fresh folder: every entry is this run's
  EXPECT_GT(stats.render_core_seconds, 0.0);
  EXPECT_NEAR(stats.render_core_seconds, recorded, rounding);
}

TEST_F(Study, BumpKeysWithoutScenesAreUnused) {
  const json lowpoly_only = {
      {"version", 1},
      {"lowpoly",
       {{"scenes", {kSource + "/scenes/lowpoly/sphere.json"}},
        {"axes", {{{"pointer", "/shape/tessellation/segments"}, {"values", {8}}}}},
        {"renderers", {"evaluator"}}}}};
  EXPECT_NO_THROW(load_study(write("good.json", lowpoly_only)));
  const std::vector<MalformedCase> cases = {
      {[](json& j) { j["methods"] = {"none"}; }, "/methods", "unused key"},
      {[](json& j) {
         j["set"] = {{"/camera/spp", 4}};
       },
       "/set", "unused key"},
      {[](json& j) { j["renderers"] = {"evaluator"}; }, "/renderers", "no /scenes"},
      {[](json& j) {
         j["figures"] = {{"methods", json::array()}};
       },
       "/figures", "unused key"},
  };
  expect_refused(lowpoly_only, "", cases, [&](const json& j) { return write("bad.json", j); });
}

// A sweep with more variants than the page shows (harness/penumbra_data.py,
// MAX_VARIANT_SECTIONS = 48): the page has 48 variant sections, the first
// and the last among them, says how many there are, and report.json and
// metrics.csv keep every variant.
// Every ranking is relative to raw bump: a study that does not name it gets
// it, and the notice reaches the log and the report.
TEST_F(Study, AStudyWithoutRawBumpGetsItAsTheBaselineAndSaysSo) {
  json j = tiny_evaluator("chiang2019");
  j["methods"] = {"chiang2019", "estevez2019"};
  j["ground_truth"] = {{"max_edge_refinements", 0}, {"max_spp_refinements", 0}};
  const ::penumbra::Study study = load_study(write("no-none.json", j));
  ASSERT_EQ(study.bump.methods.size(), 3u);
  EXPECT_EQ(study.bump.methods[0].id, "none");
  ASSERT_EQ(study.notices.size(), 1u);
  EXPECT_NE(study.notices[0].find("raw bump (\"none\")"), std::string::npos) << study.notices[0];
  StudyOptions o = test_study_options(path("out"));
  std::vector<std::string> log;
  o.log = [&](const std::string& line) { log.push_back(line); };
  o.figures = false;
  ASSERT_TRUE(run_study(study, o).complete());
  EXPECT_EQ(log.at(0), "notice: " + study.notices[0]);
  const json report = json::parse(read_text(path("out/report.json")));
  EXPECT_EQ(report["notices"], json::array({study.notices[0]}));
  EXPECT_EQ(report["statistics"]["overall"]["methods"].size(), 3u);
  // A study that names it gets no notice.
  j["methods"] = {"none", "chiang2019"};
  EXPECT_TRUE(load_study(write("with-none.json", j)).notices.empty());
}

TEST_F(Study, AReportOfManyVariantsShowsASampleAndSaysSo) {
  json j = tiny_evaluator("chiang2019");
  json amplitudes = json::array();
  for (int i = 0; i < 60; ++i) amplitudes.push_back(0.002 + 0.0005 * i);
  j["axes"] = {{{"pointer", "/height/amplitude"}, {"values", amplitudes}}};
  j["set"]["/camera/spp"] = 1;
  j["ground_truth"] = {{"max_edge_refinements", 0}, {"max_spp_refinements", 0}};
  StudyOptions o;
  o.output_dir = path("many");
  o.parallelism = resolve_parallelism(2);
  const StudyRunStats stats = run_study(load_study(write("many.json", j)), o);
  ASSERT_TRUE(stats.complete()) << (stats.failures.empty() ? "" : stats.failures[0]);
  const std::string html = read_text(stats.report_html);
  std::size_t sections = 0;
  for (std::size_t at = html.find("<h2 id=\"v-"); at != std::string::npos;
       at = html.find("<h2 id=\"v-", at + 1))
    ++sections;
  EXPECT_EQ(sections, 48u);
  EXPECT_NE(html.find("60 variants: the 48 sections below"), std::string::npos);
  const json report = json::parse(read_text(path("many/report.json")));
  ASSERT_EQ(report["variants"].size(), 60u);
  const std::string first = report["variants"][0]["id"], last = report["variants"][59]["id"];
  EXPECT_NE(html.find("<h2 id=\"v-" + first + "\""), std::string::npos) << first;
  EXPECT_NE(html.find("<h2 id=\"v-" + last + "\""), std::string::npos) << last;
  std::size_t profile_figures = 0;
  for (const auto& entry : fs::directory_iterator(path("many/figures")))
    if (entry.path().extension() == ".png" &&
        entry.path().filename().string().rfind("profile", 0) == 0)
      ++profile_figures;
  EXPECT_EQ(profile_figures, 48u);
}

// A rerun whose report.json, lowpoly.csv and scripts are unchanged keeps
// the figures (the bulk of a warm run); a missing figure, another HTML mode
// or another report.json draws them again, and so does `penumbra report`.
TEST_F(Study, UnchangedFiguresAreKeptAndAnyChangeRedrawsThem) {
  json j = tiny_evaluator("chiang2019");
  const ::penumbra::Study study = load_study(write("figures.json", j));
  std::vector<std::string> lines;
  StudyOptions o;
  o.output_dir = path("figures");
  o.parallelism = resolve_parallelism(2);
  o.log = [&](const std::string& line) { lines.push_back(line); };
  auto kept = [&] {
    lines.clear();
    const StudyRunStats stats = run_study(study, o);
    EXPECT_TRUE(stats.complete());
    EXPECT_TRUE(fs::exists(stats.report_html));
    return std::any_of(lines.begin(), lines.end(), [](const std::string& l) {
      return l.find("kept the figures and report.html of the last run") != std::string::npos;
    });
  };
  EXPECT_FALSE(kept()) << "a first run draws";
  EXPECT_TRUE(kept()) << "nothing changed";
  std::ifstream stamp(path("figures/figures/.inputs"));
  std::string digest, figure;
  ASSERT_TRUE(std::getline(stamp, digest) && std::getline(stamp, figure));
  ASSERT_TRUE(fs::remove(figure)) << figure;
  EXPECT_FALSE(kept()) << "a figure was missing";
  EXPECT_TRUE(fs::exists(figure));
  o.self_contained_html = true;
  EXPECT_FALSE(kept()) << "another HTML mode";
  EXPECT_TRUE(kept());
  j["set"]["/camera/spp"] = 2;  // other renders, so another report.json
  const ::penumbra::Study other = load_study(write("figures.json", j));
  lines.clear();
  run_study(other, o);
  EXPECT_EQ(std::count_if(lines.begin(), lines.end(),
                          [](const std::string& l) {
                            return l.find("kept the figures") != std::string::npos;
                          }),
            0);
  // Drawing on request (penumbra report) never reuses.
  lines.clear();
  draw_report(path("figures"), /*self_contained=*/true, "", 600.0,
              [&](const std::string& line) { lines.push_back(line); });
  EXPECT_TRUE(std::any_of(lines.begin(), lines.end(), [](const std::string& l) {
    return l.rfind("report.html", 0) == 0;
  })) << "the script ran";
  EXPECT_TRUE(fs::exists(path("figures/figures/.inputs")));
}

// Blender's renders of one mesh run one after another on one worker, sorted
// by method, so that its serving process keeps the mesh (and the material
// when that is the same too): every render of a group but its first says so
// in its log. Two variants that differ in light only share their meshes.
TEST_F(Study, BlenderRendersOfOneMeshFollowEachOtherOnOneWorker) {
  json j = tiny();
  j["set"]["/camera/width"] = j["set"]["/camera/height"] = 16;
  j["set"].erase("/camera/spp");
  j["axes"] = {{{"pointer", "/light/direction"}, {"values", {{-1, 0.3, -0.2}, {-1, -0.3, -0.2}}}}};
  j["methods"] = {"none", "chiang2019"};
  j["renderers"] = {"evaluator", "blender"};
  j["blender_spp"] = 2;
  const ::penumbra::Study study = load_study(write("blender.json", j));
  const StudyRunStats stats = run_study(study, test_study_options(path("out")));
  ASSERT_TRUE(stats.complete()) << (stats.failures.empty() ? "" : stats.failures[0]);
  std::size_t logs = 0, kept = 0, both_kept = 0;
  for (const auto& e : fs::directory_iterator(path("out/cache"))) {
    if (e.path().extension() != ".log") continue;
    const std::string log = read_text(e.path().string());
    if (log.find("blender_render.py: ") == std::string::npos) continue;
    ++logs;
    kept += log.find(" kept, ") != std::string::npos;
    both_kept += log.find("mesh and material kept, ") != std::string::npos;
  }
  // Bump: chiang2019 twice, then none twice, on one mesh; the two truths on
  // another.
  EXPECT_EQ(logs, 6u);
  EXPECT_EQ(kept, 4u);
  EXPECT_EQ(both_kept, 3u);
}

// How the study file is named on the command line (relative, absolute, with
// "./") does not change report.json: a warm run that names it otherwise
// keeps the figures rather than redrawing them for a path.
// Every study file the project ships plans; the quick study is a sample of
// the default one: each of its renders is one the default study makes too
// (the same scene, renderer and method), so that its numbers are the
// default study's numbers for those variants and the two share a cache.
TEST(ShippedStudies, EachPlansAndTheQuickStudyIsASampleOfTheDefault) {
  constexpr double kMemory = 8.0 * (1ull << 30);
  std::map<std::string, Plan> plans;
  for (const fs::directory_entry& e : fs::directory_iterator(kSource + "/scenes/studies")) {
    if (e.path().extension() != ".json") continue;
    // Throws (InputError) on a file or scene it cannot plan; filtering.json
    // has a filtering section only, and no renders in the plan.
    plans.emplace(e.path().stem().string(), plan_study(load_study(e.path().string()), kMemory));
  }
  ASSERT_TRUE(plans.count("default") && plans.count("quick"));
  auto identity = [](const Job& j) {
    return fmt::format("{} {} {} {}", static_cast<int>(j.renderer),
                       static_cast<int>(j.representation), j.method, j.scene_json().dump());
  };
  std::set<std::string> in_default;
  for (const Job& j : plans.at("default").jobs) in_default.insert(identity(j));
  const Plan& quick = plans.at("quick");
  std::size_t bump_variants = 0;
  for (const Variant& v : quick.variants) bump_variants += v.section == SectionKind::kBump;
  EXPECT_EQ(bump_variants, 8u);  // 2 scenes x 2 amplitudes x 2 light directions
  for (const Job& j : quick.jobs) EXPECT_TRUE(in_default.count(identity(j))) << j.label;
  EXPECT_LT(quick.jobs.size(), plans.at("default").jobs.size() / 4);
}

// The meshes study end to end, shrunk (24 px, 4 spp, coarse truths, two
// methods, the evaluator): every scene, assets included, gets its own
// ranking, and the headline says whether the analytic sphere's leader
// holds on each of the others.
TEST_F(Study, TheMeshesStudyRanksEachAssetAndSaysWhetherTheLeaderHolds) {
  json study = json::parse(std::ifstream(kSource + "/scenes/studies/meshes.json"));
  for (json& scene : study["scenes"])
    scene = kSource + "/scenes/studies/" + scene.get<std::string>();
  study["set"]["/camera/width"] = 24;
  study["set"]["/camera/height"] = 24;
  study["set"]["/camera/spp"] = 4;
  study["set"]["/displacement/edge_length"] = 0.02;
  study["methods"] = {"none", "estevez2019"};
  study["renderers"] = {"evaluator"};
  study["ground_truth"] = {
      {"tolerance", 1}, {"max_edge_refinements", 1}, {"max_spp_refinements", 1}};
  study.erase("figures");
  StudyOptions options = test_study_options(path("out"));
  options.fit = false;  // the fit's tests are its own (tests/analysis/test_achievable.cpp)
  run_study(load_study(write("meshes.json", study)), options);
  const json report = json::parse(std::ifstream(path("out/report.json")));
  std::vector<std::string> scenes;
  for (const json& r : report.at("statistics").at("per_scene"))
    scenes.push_back(r.at("scene").get<std::string>());
  EXPECT_EQ(scenes, (std::vector<std::string>{"sphere-weave", "sphere-control", "duck", "wuson"}));
  bool said = false;
  for (const json& line : report.at("statistics").at("headline"))
    said |= line.get<std::string>().rfind("On the first scene (sphere-weave), ", 0) == 0;
  EXPECT_TRUE(said) << report.at("statistics").at("headline").dump(1);
}

TEST_F(Study, TheStudyFilesSpellingDoesNotChangeTheReport) {
  write("named.json", tiny_evaluator("none"));
  const fs::path cwd = fs::current_path();
  fs::current_path(dir_);
  const ::penumbra::Study relative = load_study("./named.json");
  fs::current_path(cwd);
  run_study(load_study(path("named.json")), test_study_options(path("out")));
  const std::string absolute_report = report_without_provenance(path("out/report.json"));
  run_study(relative, test_study_options(path("out")));
  EXPECT_TRUE(report_without_provenance(path("out/report.json")) == absolute_report);
  EXPECT_NE(absolute_report.find("\"file\": \"" + path("named.json") + "\""), std::string::npos);
}

// The smoke study end to end, every renderer, then its report.html in
// headless Chromium at 1024 px: no console errors, every linked image
// decoded, nothing wider than the page, the headline's method table, the
// cross-renderer table and the renderer table present. Then the same page
// self-contained: every image a data: URI, nothing linked.
TEST_F(Study, SmokeStudyReportLoadsInChromium) {
  const ::penumbra::Study study = load_study(kSource + "/scenes/studies/smoke.json");
  StudyOptions o;
  o.output_dir = path("smoke");
  o.parallelism = resolve_parallelism(2);
  const StudyRunStats stats = run_study(study, o);
  ASSERT_TRUE(stats.complete()) << (stats.failures.empty() ? "" : stats.failures[0]);
  ASSERT_TRUE(fs::exists(stats.report_html));
  for (const char* ext : {"png", "svg", "pdf"})
    EXPECT_TRUE(fs::exists(path(std::string("smoke/figures/ranking.") + ext))) << ext;
  for (const char* ext : {"png", "pdf"})
    EXPECT_TRUE(fs::exists(path(std::string("smoke/figures/grid-v000.") + ext))) << ext;

  // A copy with a probe appended, beside the page so that its relative
  // links resolve: after load it writes into the DOM how many images
  // decoded, which elements reach past the window's right edge and which
  // tables are missing; --dump-dom prints it. The report itself has no script.
  std::string html = read_text(stats.report_html);
  EXPECT_EQ(html.find("data:image"), std::string::npos) << "the default page links its images";
  EXPECT_NE(html.find("src=\"images/"), std::string::npos);
  const std::string probe =
      "<script>window.addEventListener('load',function(){var i=document.images,ok=0;"
      "for(var k=0;k<i.length;k++){if(i[k].complete&&i[k].naturalWidth>0)ok++;}"
      "var w=document.documentElement.clientWidth,wide=[];"
      "document.querySelectorAll('body *').forEach(function(e){"
      "if(e.getBoundingClientRect().right>w+1)wide.push(e.tagName+(e.id?'#'+e.id:''));});"
      "var miss=['methods-table','agreement-table','renderers-table'].filter(function(t){"
      "return !document.querySelector('#'+t+' table tr td');});"
      "var b=document.body;b.setAttribute('data-probe',ok+'/'+i.length);"
      "b.setAttribute('data-wide',wide.length+':'+wide.slice(0,5).join(' '));"
      "b.setAttribute('data-missing','['+miss.join(' ')+']');});</script>";
  const auto body = html.rfind("</body>");
  ASSERT_NE(body, std::string::npos);
  html.insert(body, probe);
  std::ofstream(path("smoke/probe.html")) << html;
  const auto chromium = find_executable("chromium");
  ASSERT_TRUE(chromium) << "chromium is not installed (apt-get install chromium)";
  // A browser that crashes or hangs at start-up (seen once in CI, on a
  // machine that had just installed it) is the environment, not the page:
  // one more try with a fresh profile; both attempts' logs go to the failure.
  std::string log, earlier;
  for (int attempt = 0; attempt < 2; ++attempt) {
    const std::string profile = path("chromium-profile-" + std::to_string(attempt));
    const std::string log_file = path("chromium-" + std::to_string(attempt) + ".log");
    const ProcessResult p = run_process(
        {*chromium, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--user-data-dir=" + profile, "--enable-logging=stderr", "--v=0", "--window-size=1024,900",
         "--hide-scrollbars", "--virtual-time-budget=10000", "--dump-dom",
         "file://" + path("smoke/probe.html")},
        dir_.string(), log_file, 120);
    log = read_text(log_file);
    if (p.ok() && log.find("data-probe=") != std::string::npos) break;
    const std::string how = p.timed_out ? "timed out"
                            : p.signal  ? "killed by signal " + std::to_string(p.signal)
                            : p.ok()    ? "no probe output"
                                        : "exit code " + std::to_string(p.exit_code);
    earlier += "attempt " + std::to_string(attempt + 1) + ": " + how + "\n" +
               log.substr(log.size() > 4000 ? log.size() - 4000 : 0) + "\n";
    log.clear();
  }
  ASSERT_FALSE(log.empty()) << "Chromium did not load the page twice:\n" << earlier;
  EXPECT_EQ(log.find("Uncaught"), std::string::npos) << log;
  EXPECT_EQ(log.find(":CONSOLE("), std::string::npos) << log;
  EXPECT_EQ(log.find("ERR_FILE_NOT_FOUND"), std::string::npos) << log;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(log, m, std::regex("data-probe=\"(\\d+)/(\\d+)\""))) << log;
  const int page_images = std::stoi(m[2]);
  EXPECT_GT(page_images, 20);
  EXPECT_EQ(m[1], m[2]) << "images that did not decode";
  ASSERT_TRUE(std::regex_search(log, m, std::regex("data-wide=\"([^\"]*)\""))) << log;
  EXPECT_EQ(m[1].str().substr(0, 2), "0:") << "elements wider than the page: " << m[1];
  ASSERT_TRUE(std::regex_search(log, m, std::regex("data-missing=\"([^\"]*)\""))) << log;
  EXPECT_EQ(m[1], "[]") << "tables missing from the page";

  // Self-contained: the same page with every image inlined.
  const std::string linked_bytes = html.substr(0, body);
  draw_report(path("smoke"), /*self_contained=*/true);
  const std::string embedded = read_text(stats.report_html);
  EXPECT_EQ(embedded.find("src=\"images/"), std::string::npos);
  EXPECT_EQ(embedded.find("src=\"figures/"), std::string::npos);
  std::size_t images = 0;
  for (std::size_t at = 0;
       (at = embedded.find("<img src=\"data:image/png;base64,", at)) != std::string::npos; ++at)
    ++images;
  EXPECT_EQ(images, static_cast<std::size_t>(page_images)) << "every image inlined";
  EXPECT_GT(embedded.size(), 10 * linked_bytes.size());
}

}  // namespace
}  // namespace penumbra
