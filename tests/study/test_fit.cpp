// `penumbra fit` on a small finished study: the floor is below every shipped
// factor of its inputs, the held-out table never saw its family's renders,
// and refitting estevez2019 or deshmukh2020 on truths made with their own
// factor recovers their constants.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "core/vec.h"
#include "image/image_io.h"
#include "study/fit.h"
#include "study/study.h"
#include "study_options.h"
#include "temp_dir_test.h"

namespace penumbra {
namespace {

using nlohmann::json;

const std::string kSource = PENUMBRA_SOURCE_DIR;

class Fit : public TempDirTest {
 protected:
  // A study of the evaluator alone, 32 x 32 pixels at 4 spp, run into `name`.
  // `lowpoly`: the study's low-poly section, or null for none.
  std::string run_evaluator_study(const std::string& name, const json& scenes, const json& axes,
                                  const json& methods, const json& lowpoly = nullptr) {
    json study{{"version", 1},
               {"name", name},
               {"scenes", scenes},
               {"set",
                {{"/camera/width", 32},
                 {"/camera/height", 32},
                 {"/camera/spp", 4},
                 {"/displacement/edge_length", 0.02}}},
               {"axes", axes},
               {"methods", methods},
               {"renderers", {"evaluator"}},
               // One check each way, accepted at any change: the fit leaves out a
               // truth that did not converge, and these coarse truths test the
               // fit's arithmetic, not the truth's convergence.
               {"ground_truth",
                {{"tolerance", 1.0}, {"max_edge_refinements", 1}, {"max_spp_refinements", 1}}}};
    if (!lowpoly.is_null()) study["lowpoly"] = lowpoly;
    std::ofstream(path(name + ".json")) << study.dump(2);
    run_study(load_study(path(name + ".json")), test_study_options(path(name)));
    return path(name);
  }
  // Three scene families, four variants each.
  std::string run_small_study(const std::string& name) {
    return run_evaluator_study(
        name,
        {kSource + "/scenes/sphere-grating.json", kSource + "/scenes/cylinder-grating.json",
         kSource + "/scenes/sphere-weave.json"},
        {{{"pointer", "/height/amplitude"}, {"values", {0.01, 0.02}}},
         {{"pointer", "/light/direction"}, {"values", {{-1, 0, -0.2}, {-1, 0, 0.4}}}}},
        {"none", "estevez2019", "deshmukh2020", "chiang2019"});
  }
  // Coarser than the default grid (210 cells rather than 750), for time.
  static FactorGrid grid() {
    return {{{FactorInput::kLight, 50.0, 120.0, 2.0}, {FactorInput::kDeviation, 0.0, 36.0, 6.0}}};
  }
  static FitResult fit(const std::string& folder, int jobs = 0, FactorGrid g = grid()) {
    FitOptions o;
    o.folder = folder;
    o.jobs = jobs;
    o.resamples = 200;
    o.grid = std::move(g);
    return fit_study(o);
  }
};

// A paired difference is the difference of the two pooled errors it pairs,
// its interval is an interval, and a tie is exactly an interval holding 0.
void expect_paired(const PairedError& p, double a, double b, const std::string& what) {
  EXPECT_NEAR(p.difference.value, a - b, 1e-15) << what;
  EXPECT_LE(p.difference.interval.low, p.difference.interval.high) << what;
  EXPECT_EQ(p.tie, p.difference.interval.low <= 0.0 && 0.0 <= p.difference.interval.high) << what;
}

// Share groups: numbered from 1 in order of their leaders' shares; a
// leader has the highest share of its group and every member is tied with
// it, paired (the difference of the two shares).
void expect_share_groups(const std::vector<MethodShare>& shares) {
  std::map<std::string, const MethodShare*> by_method;
  for (const MethodShare& s : shares) by_method[s.method] = &s;
  int groups = 0;
  for (const MethodShare& s : shares) {
    if (!std::isfinite(s.share.value)) {
      EXPECT_EQ(s.group, 0) << s.method;
      continue;
    }
    ASSERT_GT(s.group, 0) << s.method;
    ASSERT_TRUE(by_method.count(s.leader)) << s.leader;
    const MethodShare& lead = *by_method.at(s.leader);
    EXPECT_EQ(lead.group, s.group) << s.method;
    EXPECT_EQ(lead.leader, lead.method);
    EXPECT_LE(s.share.value, lead.share.value) << s.method;
    EXPECT_TRUE(s.versus_leader.tie) << s.method;
    EXPECT_NEAR(s.versus_leader.difference.value, s.share.value - lead.share.value, 1e-12);
    groups = std::max(groups, s.group);
  }
  // Leaders in order of share: group g + 1's leader has a lower share than g's.
  for (const MethodShare& a : shares)
    for (const MethodShare& b : shares) {
      if (a.leader == a.method && b.leader == b.method && a.group < b.group) {
        EXPECT_GE(a.share.value, b.share.value) << a.method << " " << b.method;
      }
    }
  EXPECT_GT(groups, 1) << "every method in one group: the test shows nothing";
}

// The held-out table against the best shipped method (study and each
// family), and each refitted constant held out against its published value.
void expect_paired_differences(const FitResult& r) {
  const MethodShare* best = nullptr;
  for (const MethodShare& s : r.shares)
    if (s.method.rfind("fitted", 0) != 0 && (!best || s.error.value < best->error.value)) best = &s;
  ASSERT_NE(best, nullptr);
  EXPECT_EQ(r.best_method, best->method);
  expect_paired(r.held_out_minus_best, r.held_out_pooled.value, best->error.value, "study");
  for (const HeldOutFit& h : r.held_out)
    expect_paired(h.held_out_minus_best, h.held_out.value, h.best.value, h.family);
  ASSERT_EQ(r.constants.size(), 6u);  // k, d0, d1; s, p, q (probed)
  for (const FittedConstant& c : r.constants) {
    EXPECT_TRUE(c.held_out_defined) << c.constant;
    for (const PooledError* e : {&c.in_sample, &c.at_published, &c.held_out})
      EXPECT_LE(e->interval.low, e->interval.high) << c.constant;
    expect_paired(c.held_out_minus_published, c.held_out.value, c.at_published.value, c.constant);
  }
}

TEST_F(Fit, FloorIsBelowTheShippedFactorsAndHeldOutTablesNeverSawTheirFamily) {
  const std::string folder = run_small_study("study");
  const FitResult r = fit(folder);
  ASSERT_EQ(r.variants.size(), 12u);
  EXPECT_EQ(r.retraced_different, 0u);  // the tally's image is the cached render
  EXPECT_LE(r.study_floor.floor.value, r.study_floor.none.value);
  int on_grid = 0;
  for (const MethodShare& s : r.shares) {
    if (!s.on_grid_inputs) continue;
    ++on_grid;
    // Their table on the grid is one of the G the floor ranges over; the
    // solver's optimality (KKT residual) bounds how far above it may land.
    EXPECT_LE(r.study_floor.floor.value, s.grid_error * (1.0 + 1e-6)) << s.method;
  }
  EXPECT_EQ(on_grid, 2);  // estevez2019, deshmukh2020
  // The image RMSE's per-variant floors. Raw bump through the tally is the
  // report's image RMSE, to the float rounding of the report's pixels. G = 1
  // and the tabulated shipped factors are among the G a variant's floor
  // ranges over: none is below it, to the solver's optimality.
  EXPECT_LT(r.image.none_minus_report, 1e-6);
  EXPECT_LT(r.image.kkt_residual, 1e-8);
  for (const FitVariant& v : r.variants) {
    EXPECT_LE(v.image_floor, v.image_none * (1.0 + 1e-6)) << v.id;
    ASSERT_EQ(v.image_on_grid.size(), 2u) << v.id;
    for (const auto& [method, e] : v.image_on_grid)
      EXPECT_GE(e, v.image_floor * (1.0 - 1e-6)) << v.id << " " << method;
  }
  EXPECT_LT(r.image.floor.value, r.image.none.value);
  EXPECT_EQ(r.image.methods.size(), r.shares.size());
  for (const MethodShare& s : r.image.methods) {
    EXPECT_EQ(s.on_grid_inputs, s.method == "estevez2019" || s.method == "deshmukh2020");
    if (s.on_grid_inputs) {
      EXPECT_GE(s.grid_error, r.image.floor.value * (1.0 - 1e-6)) << s.method;
    }
  }
  ASSERT_EQ(r.held_out.size(), 3u);
  expect_paired_differences(r);
  expect_share_groups(r.shares);
  expect_share_groups(r.image.methods);
  // The floor solves run several at once, shared between folds: one at a
  // time gives the same bits.
  const FitResult serial = fit(folder, 1);
  EXPECT_EQ(serial.table.values, r.table.values);
  EXPECT_EQ(serial.table_smoothness, r.table_smoothness);
  ASSERT_EQ(serial.held_out.size(), r.held_out.size());
  for (std::size_t k = 0; k < r.held_out.size(); ++k) {
    EXPECT_EQ(serial.held_out[k].held_out.value, r.held_out[k].held_out.value);
    EXPECT_EQ(serial.held_out[k].smoothness, r.held_out[k].smoothness);
  }

  // Delete one family's renders and fit again: the table fitted on what is
  // left (its smoothness chosen among the same two families) is the table
  // the full fit held that family out with, so it gives the same error on it.
  const HeldOutFit& held = r.held_out.front();
  const json report = json::parse(std::ifstream(folder + "/report.json"));
  for (const json& v : report.at("variants"))
    if (v.at("scene") == held.family)
      for (const json& render : v.at("renders"))
        if (render.at("exr").is_string())
          std::filesystem::remove(folder + "/" + render.at("exr").get<std::string>());
  const FitResult reduced = fit(folder);
  ASSERT_EQ(reduced.variants.size(), 8u);
  EXPECT_EQ(reduced.table_smoothness, held.smoothness);
  double sum = 0.0;
  int n = 0;
  for (const FitVariant& v : r.variants)
    if (v.family == held.family) {
      const double e = tally_rmse(v.data, reduced.table.values);
      sum += e * e, ++n;
    }
  EXPECT_NEAR(std::sqrt(sum / n), held.held_out.value, 1e-12);

  // A variant whose truth did not converge is left out and named: mark one
  // of a family still in the cache so in report.json and fit again.
  json marked = report;
  std::map<std::string, std::string> family_of;
  for (const json& v : report.at("variants")) family_of[v.at("id")] = v.at("scene");
  std::string left_out;
  for (json& g : marked.at("ground_truth").at("variants"))
    if (family_of.at(g.at("variant")) != held.family) {
      g["converged"] = false;
      left_out = g.at("variant");
      break;
    }
  ASSERT_FALSE(left_out.empty());
  std::ofstream(folder + "/report.json") << marked.dump();
  const FitResult unconverged = fit(folder);
  EXPECT_EQ(unconverged.variants.size(), 7u);
  EXPECT_EQ(unconverged.unconverged, std::vector<std::string>{left_out});
  for (const FitVariant& v : unconverged.variants) EXPECT_NE(v.id, left_out);
}

// Truths that are raw bump under estevez2019's own term with a known k:
// the refit finds it (to the golden section's 1e-4 in log k).
// A shading axis over every angle added to the grid: the floor of
// light,deviation on the same axes, summed out of the new tallies, is the
// floor a light,deviation fit finds (to the solver's tolerance), the new
// floor is never above it, chiang2019 (a function of all three angles) is
// tabulated on the grid, and the smoothed solves of its 1,260 cells are
// sparse (FloorOptions::dense_variables).
TEST_F(Fit, AShadingInputNeverRaisesTheFloorOfTheSameLightAndDeviationAxes) {
  const std::string folder = run_small_study("study");
  const FitResult plain = fit(folder);
  FactorGrid with_shading = grid();
  with_shading.axes.push_back({FactorInput::kShading, 0.0, 180.0, 30.0});
  ASSERT_GT(with_shading.cells(), FloorOptions().dense_variables);
  const FitResult r = fit(folder, 0, with_shading);
  EXPECT_EQ(grid_inputs(r.grid), "light,deviation,shading");
  ASSERT_EQ(r.nested.size(), 1u);
  const NestedFloor& n = r.nested[0];
  EXPECT_EQ(n.inputs, "light,deviation");
  EXPECT_NEAR(n.floor.floor.value, plain.study_floor.floor.value,
              1e-6 * plain.study_floor.floor.value);
  EXPECT_LE(r.study_floor.floor.value, n.floor.floor.value * (1.0 + 1e-6));
  expect_paired(n.gain, r.study_floor.floor.value, n.floor.floor.value, "nested");
  EXPECT_LT(n.gain.difference.value, 0.0) << "the shading input bought nothing: the test is weak";
  std::set<std::string> on_grid;
  for (const MethodShare& s : r.shares)
    if (s.on_grid_inputs) {
      on_grid.insert(s.method);
      EXPECT_LE(r.study_floor.floor.value, s.grid_error * (1.0 + 1e-6)) << s.method;
    }
  EXPECT_EQ(on_grid, (std::set<std::string>{"chiang2019", "deshmukh2020", "estevez2019"}));
  EXPECT_TRUE(r.constants.empty());  // fitted on light,deviation grids only
  EXPECT_EQ(r.table.values.size(), std::size_t(with_shading.cells()));
  EXPECT_TRUE(plain.nested.empty());
}

TEST(FitGrid, EachInputSetHasItsGridAndNoOtherSetIsTaken) {
  for (const std::string inputs : kFitInputSets) {
    const FactorGrid g = fit_grid(inputs);
    EXPECT_EQ(grid_inputs(g), inputs);
    for (const FactorAxis& a : g.axes) {
      EXPECT_NEAR(a.cells() * a.step_deg, a.max_deg - a.min_deg, 1e-9) << inputs;
      // No point leaves the grid through the shading axis: it spans every angle.
      if (a.input == FactorInput::kShading) {
        EXPECT_EQ(a.max_deg - a.min_deg, 180.0);
      }
    }
  }
  EXPECT_EQ(fit_grid("light,deviation").cells(), default_fit_grid().cells());
  EXPECT_THROW(fit_grid("light,shading"), std::invalid_argument);
}

TEST(FitGrid, StepsResizeTheNamedAxesAndRefuseWhatDoesNotDivideTheirRange) {
  const FactorGrid g = with_steps(fit_grid("light,deviation,shading"), {"shading=6", "light=2"});
  EXPECT_EQ(g.axes[0].step_deg, 2.0);
  EXPECT_EQ(g.axes[1].step_deg, fit_grid("light,deviation,shading").axes[1].step_deg);
  EXPECT_EQ(g.axes[2].step_deg, 6.0);
  EXPECT_EQ(g.cells(), 50 * 10 * 30);
  for (const std::vector<std::string>& bad :
       std::vector<std::vector<std::string>>{{"view=15"},       // not an axis of this set
                                             {"shading"},       // no degrees
                                             {"shading=7"},     // 180 / 7 is not whole
                                             {"shading=-6"},    // not positive
                                             {"shading=6deg"},  // not a number
                                             {"light=0.25", "shading=1"}})  // 720,000 cells
    EXPECT_THROW(with_steps(fit_grid("light,deviation,shading"), bad), std::invalid_argument)
        << bad[0];
}

TEST_F(Fit, RefittingEstevez2019OnItsOwnTermRecoversItsConstant) {
  const FitResult r = fit(run_small_study("study"));
  for (const double k : {1.0 / 8.0, 0.3}) {
    std::vector<TallyVariant> synthetic;
    for (const FitVariant& v : r.variants)
      synthetic.push_back({v.id, v.data.tally, v.data.tally.profile(estevez2019_table(r.grid, k))});
    EXPECT_NEAR(fit_estevez2019_k(synthetic, r.grid) / k, 1.0, 2e-3) << k;
  }
}

// shading-offset and the micro-shadowing methods refitted through the
// re-trace's probes (study/fit_probes.h). At the study's own value the
// probe's E is the E of the study's render of the method (the probe is
// that render, to float rounding: relative 1e-6). With every truth replaced
// by the method's own render at a value, the refit finds that value, at
// E = 0, in sample and held out.
TEST_F(Fit, ProbedConstantsAreTheirMethodsRendersAndRefitTheirValues) {
  const std::string folder = run_evaluator_study(
      "probes", {kSource + "/scenes/cylinder-grating.json", kSource + "/scenes/sphere-weave.json"},
      {{{"pointer", "/height/amplitude"}, {"values", {0.01, 0.02}}},
       {{"name", "shading"},
        {"values",
         {{{"id", "lambert"}, {"label", "Lambert"}, {"set", {{"/terminator/lobes", "diffuse"}}}},
          {{"id", "ggx-all"},
           {"label", "Lambert + GGX, factor on all lobes"},
           {"set",
            {{"/material/specular", {{"roughness", 0.3}, {"weight", 0.4}}},
             {"/terminator/lobes", "all"}}}}}}}},
      {"none",
       {{"id", "shading-offset"}, {"parameters", {{"s", 0.4}}}},
       "microshadow-chan2018",
       "microshadow-brinck2016"});
  const auto constant_of = [](const FitResult& r, const std::string& method) {
    for (const FittedConstant& c : r.constants)
      if (c.method == method) return c;
    ADD_FAILURE() << method << " not refitted";
    return FittedConstant{};
  };
  const FitResult r = fit(folder);
  ASSERT_EQ(r.variants.size(), 8u);
  for (const auto& [method, published] :
       {std::pair{"shading-offset", 0.4}, std::pair{"microshadow-chan2018", 2.0},
        std::pair{"microshadow-brinck2016", 2.0}}) {
    const FittedConstant c = constant_of(r, method);
    EXPECT_EQ(c.published, published) << method;
    EXPECT_GT(c.at_published.value, 0.0) << method;
    EXPECT_LE(c.probe_minus_rendered, 1e-6 * c.at_published.value) << method;
  }
  // Each truth replaced by the method's render: the method at its value is
  // the truth, E = 0 there and above 0 at the values around it.
  const json report = json::parse(std::ifstream(folder + "/report.json"));
  for (const auto& [label, method, value] :
       {std::tuple{"shading-offset(s=0.4)", "shading-offset", 0.4},
        std::tuple{"microshadow-chan2018", "microshadow-chan2018", 2.0}}) {
    for (const json& v : report.at("variants")) {
      std::string truth, render;
      for (const json& x : v.at("renders")) {
        if (x.at("renderer") != "evaluator" || !x.at("exr").is_string()) continue;
        if (x.at("representation") == "displacement") truth = x.at("exr");
        if (x.at("representation") == "bump" && x.at("method") == label) render = x.at("exr");
      }
      ASSERT_FALSE(truth.empty() || render.empty()) << v.at("id");
      std::filesystem::copy_file(folder + "/" + render, folder + "/" + truth,
                                 std::filesystem::copy_options::overwrite_existing);
    }
    const FittedConstant c = constant_of(fit(folder), method);
    EXPECT_EQ(c.fitted, value) << method;
    EXPECT_EQ(c.interval.low, value) << method;
    EXPECT_EQ(c.interval.high, value) << method;
    EXPECT_LE(c.in_sample.value, 1e-6) << method;
    EXPECT_LE(c.held_out.value, 1e-6) << method;
  }
}

// Truths that are raw bump under deshmukh2020's own factor with known
// constants: the refit finds them. The published pair is also where the
// search may start; the others are found by the search alone.
//
// Tolerance: Nelder-Mead stops when its vertices lie within 1e-6 degrees of
// the best in w = asin(d) at the deviation axis' two ends, which is
// |dd| <= (pi / 180) 1e-6 = 1.75e-8 in d1 and in d at the end e; d0 =
// (d_e - d1 cos e) / (1 - cos e) carries (1 + cos e) / (1 - cos e) times
// that. Ten times those bounds leaves room for a best vertex that is not yet
// the minimum (a narrow valley) and none for a search that stopped at a
// coarse node (1 degree away, 1.7e-2 in d).
TEST_F(Fit, RefittingDeshmukh2020OnItsOwnTermRecoversItsConstants) {
  const FitResult r = fit(run_small_study("study"));
  const double resolution = radians(1e-6), cos_end = std::cos(radians(r.grid.axes[1].max_deg));
  const double tolerance_d1 = 10.0 * resolution,
               tolerance_d0 = tolerance_d1 * (1.0 + cos_end) / (1.0 - cos_end);
  for (const Deshmukh2020Constants truth :
       {kDeshmukh2020Published, Deshmukh2020Constants{0.2, 0.03},
        Deshmukh2020Constants{0.3, 0.01}}) {
    std::vector<TallyVariant> synthetic;
    for (const FitVariant& v : r.variants)
      synthetic.push_back(
          {v.id, v.data.tally, v.data.tally.profile(deshmukh2020_table(r.grid, truth))});
    const Deshmukh2020Constants c = fit_deshmukh2020(synthetic, r.grid);
    EXPECT_NEAR(c.d0, truth.d0, tolerance_d0) << truth.d0;
    EXPECT_NEAR(c.d1, truth.d1, tolerance_d1) << truth.d1;
  }
}

// On the study's own truths: at the published pair the table is the shipped
// factor's (the same E to the bit as its on-grid error), and the pair fitted
// on every variant is never worse than it there.
TEST_F(Fit, Deshmukh2020FitIsNeverWorseThanItsPublishedConstants) {
  const FitResult r = fit(run_small_study("study"));
  double on_grid = std::numeric_limits<double>::quiet_NaN();
  for (const MethodShare& s : r.shares)
    if (s.method == "deshmukh2020") on_grid = s.grid_error;
  std::vector<FittedConstant> pair;
  for (const FittedConstant& c : r.constants)
    if (c.method == "deshmukh2020") pair.push_back(c);
  ASSERT_EQ(pair.size(), 2u);
  EXPECT_EQ(pair[0].constant.substr(0, 3), "d0 ");
  EXPECT_EQ(pair[1].constant.substr(0, 3), "d1 ");
  EXPECT_EQ(pair[0].published, kDeshmukh2020Published.d0);
  EXPECT_EQ(pair[1].published, kDeshmukh2020Published.d1);
  for (const FittedConstant& c : pair) {
    EXPECT_EQ(c.at_published.value, on_grid);
    EXPECT_LE(c.in_sample.value, c.at_published.value) << c.constant;
    EXPECT_TRUE(std::isfinite(c.held_out.value)) << c.constant;
    EXPECT_LE(c.interval.low, c.interval.high) << c.constant;
  }
  // d in (0, 1] at both ends of the grid's deviation axis.
  const double d1 = pair[1].fitted,
               d_end = pair[0].fitted +
                       (d1 - pair[0].fitted) * std::cos(radians(r.grid.axes[1].max_deg));
  for (const double d : {d1, d_end}) {
    EXPECT_GT(d, 0.0);
    EXPECT_LE(d, 1.0);
  }
}

// The cache paths of each low-poly variant's evaluator renders, by offset
// label ("analytic": the truth).
std::vector<std::map<std::string, std::string>> lowpoly_renders(const std::string& folder) {
  const json report = json::parse(std::ifstream(folder + "/report.json"));
  std::vector<std::map<std::string, std::string>> out;
  for (const json& v : report.at("lowpoly").at("variants")) {
    out.emplace_back();
    for (const json& r : v.at("renders"))
      if (r.at("renderer") == "evaluator" && r.at("exr").is_string())
        out.back()[r.at("offset")] = folder + "/" + r.at("exr").get<std::string>();
  }
  return out;
}

// The low-poly offsets' parameters: each value's E is the pooled image
// RMSE of the study's own comparisons (report.json, divided by albedo*E/pi
// = 0.8 W m^-2 sr^-1: albedo 0.8 under irradiance pi), and with each truth
// replaced by the render at one value, the refit finds that value, E = 0
// there, held out too.
TEST_F(Fit, OffsetParametersAreRefittedAmongTheirRendersAndHeldOutByScene) {
  const json epsilon = {{"id", "epsilon"}, {"parameters", {{"distance", 0.001}}}};
  json offsets = {"none", "gist2020", epsilon, epsilon, epsilon};
  offsets[3]["parameters"]["distance"] = 0.01;
  offsets[4]["parameters"]["distance"] = 0.1;
  const std::string folder = run_evaluator_study(
      "offsets", {kSource + "/scenes/sphere-grating.json"}, json::array(), {"none"},
      {{"scenes",
        {kSource + "/scenes/lowpoly/sphere.json", kSource + "/scenes/lowpoly/cylinder.json"}},
       {"set", {{"/camera/width", 32}, {"/camera/height", 32}, {"/camera/spp", 4}}},
       // Two lights rather than two tessellations: a scene's analytic truth
       // does not depend on the tessellation, so its variants would share it.
       {"axes",
        {{{"pointer", "/shape/tessellation/segments"}, {"values", {8}}},
         {{"pointer", "/light/direction"}, {"values", {{-1, 0.3, -0.2}, {-1, 0.3, 0.3}}}}}},
       {"offsets", offsets},
       {"renderers", {"evaluator"}}});
  const FitResult r = fit(folder);
  ASSERT_EQ(r.offset_parameters.size(), 1u);  // gist2020 and none have no parameter
  const FittedOffsetParameter& f = r.offset_parameters[0];
  EXPECT_EQ(f.fit.method, "epsilon");
  EXPECT_EQ(f.fit.reference, "Penumbra's default");
  EXPECT_EQ(f.fit.published, 0.01);
  EXPECT_EQ(f.values, (std::vector<double>{0.001, 0.01, 0.1}));
  EXPECT_EQ(f.variants, 4u);
  EXPECT_LE(f.report_difference, 1e-12);
  const json report = json::parse(std::ifstream(folder + "/report.json"));
  for (std::size_t k = 0; k < f.values.size(); ++k) {
    const std::string label = fmt::format("epsilon(distance={:g})", f.values[k]);
    double sum = 0.0;
    int n = 0;
    for (const json& c : report.at("lowpoly").at("comparisons"))
      if (c.at("offset") == label && c.at("renderer") == "evaluator") {
        sum += std::pow(c.at("image").at("rmse").get<double>() / 0.8, 2);
        ++n;
      }
    ASSERT_EQ(n, 4) << label;
    EXPECT_NEAR(f.errors[k].value, std::sqrt(sum / n), 1e-9 * f.errors[k].value) << label;
    EXPECT_LE(f.errors[k].interval.low, f.errors[k].value) << label;
    EXPECT_GE(f.errors[k].interval.high, f.errors[k].value) << label;
  }
  for (const double value : {0.01, 0.1}) {
    const std::string label = fmt::format("epsilon(distance={:g})", value);
    for (const auto& renders : lowpoly_renders(folder))
      std::filesystem::copy_file(renders.at(label), renders.at("analytic"),
                                 std::filesystem::copy_options::overwrite_existing);
    const FittedConstant c = fit(folder).offset_parameters.at(0).fit;
    EXPECT_EQ(c.fitted, value) << label;
    EXPECT_EQ(c.interval.low, value) << label;
    EXPECT_EQ(c.interval.high, value) << label;
    EXPECT_EQ(c.in_sample.value, 0.0) << label;
    EXPECT_EQ(c.held_out.value, 0.0) << label;
    EXPECT_EQ(c.at_bound, value == 0.1 ? "distance = 0.1" : "") << label;
    // The published 0.01 is the truth in the first round: a tie at 0.
    if (value == 0.01) continue;
    EXPECT_GT(c.at_published.value, 0.0);
    EXPECT_FALSE(c.held_out_minus_published.tie);
    EXPECT_LT(c.held_out_minus_published.difference.interval.high, 0.0);
  }

  // One family has nothing to fit on once it is held out: the main
  // section's single scene gives the constants no held-out error, and
  // fit.json writes null for it rather than the first value's error.
  EXPECT_TRUE(f.fit.held_out_defined);
  ASSERT_FALSE(r.constants.empty());
  for (const FittedConstant& c : r.constants) EXPECT_FALSE(c.held_out_defined) << c.method;
  for (const json& v : report.at("lowpoly").at("variants"))
    if (v.at("scene") == "cylinder")
      for (const json& render : v.at("renders"))
        if (render.at("exr").is_string())
          std::filesystem::remove(folder + "/" + render.at("exr").get<std::string>());
  const FitResult one = fit(folder);
  ASSERT_EQ(one.offset_parameters.size(), 1u);
  EXPECT_EQ(one.offset_parameters[0].variants, 2u);
  EXPECT_FALSE(one.offset_parameters[0].fit.held_out_defined);
  write_fit(one, path("fit-one"));
  const json written = json::parse(std::ifstream(path("fit-one/fit.json")));
  const json& offset = written.at("offset_parameters").at(0);
  EXPECT_TRUE(offset.at("error_fitted_held_out").is_null());
  EXPECT_TRUE(offset.at("held_out_minus_published").is_null());
  EXPECT_TRUE(written.at("constants").at(0).at("error_fitted_held_out").is_null());
}

// The fitted method in a study: its table named relative to the study file,
// rendered as the table says (a table of constants 0.5 halves a Lambertian
// raw-bump render exactly: Tally.FittedTablesOfConstantsAreExact), entered in
// the cache key by content: editing the table re-renders that job alone;
// the same content under another name renders nothing.
class FittedStudy : public TempDirTest {
 protected:
  void write_table(const std::string& name, double g) const {
    std::filesystem::create_directories(path("tables"));
    const json table{
        {"grid",
         {{{"input", "light"}, {"min_deg", 0}, {"max_deg", 90}, {"step_deg", 30}},
          {{"input", "deviation"}, {"min_deg", 0}, {"max_deg", 60}, {"step_deg", 30}}}},
        {"values", json::array({g, g, g, g, g, g})}};
    std::ofstream(path("tables/" + name)) << table.dump();
  }
  StudyRunStats run(const std::string& table) const {
    const json study{
        {"version", 1},
        {"name", "fitted"},
        {"scenes", {kSource + "/scenes/sphere-grating.json"}},
        {"set", {{"/camera/width", 16}, {"/camera/height", 16}, {"/camera/spp", 1}}},
        {"methods", {"none", {{"id", "fitted"}, {"parameters", {{"table", table}}}}}},
        {"renderers", {"evaluator"}},
        // One check each way, accepted at any change: the fit leaves out a
        // truth that did not converge, and these coarse truths test the
        // fit's arithmetic, not the truth's convergence.
        {"ground_truth",
         {{"tolerance", 1.0}, {"max_edge_refinements", 1}, {"max_spp_refinements", 1}}}};
    std::ofstream(path("study.json")) << study.dump();
    StudyOptions o = test_study_options(path("out"));
    o.fit = false;
    const StudyRunStats stats = run_study(load_study(path("study.json")), o);
    EXPECT_TRUE(stats.complete());
    return stats;
  }
  // The bump renders of the study by method, read from the cache entries
  // metrics.csv names.
  std::map<std::string, Image> bump_renders() const {
    std::ifstream csv(path("out/metrics.csv"));
    std::string line;
    std::getline(csv, line);
    std::vector<std::string> header;
    std::stringstream h(line);
    for (std::string cell; std::getline(h, cell, ',');) header.push_back(cell);
    const auto column = [&](const std::string& name) {
      return std::size_t(std::find(header.begin(), header.end(), name) - header.begin());
    };
    std::map<std::string, Image> out;
    while (std::getline(csv, line)) {
      std::vector<std::string> cells;
      std::stringstream row(line);
      for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
      if (cells.at(column("representation")) == "bump")
        out[cells.at(column("method"))] = read_image(path("out/" + cells.at(column("exr"))));
    }
    return out;
  }
};

TEST_F(FittedStudy, RendersItsTableAndReRendersWhenTheTableChanges) {
  write_table("half.json", 0.5);
  run("tables/half.json");
  std::map<std::string, Image> renders = bump_renders();
  ASSERT_EQ(renders.size(), 2u);
  const Image& none = renders.at("none");
  const Image& fitted = renders.at("fitted");
  ASSERT_EQ(none.pixels.size(), fitted.pixels.size());
  int lit = 0;
  for (int y = 0; y < none.height; ++y)
    for (int x = 0; x < none.width; ++x) {
      const float raw = none.at(x, y, 0);
      EXPECT_EQ(fitted.at(x, y, 0), 0.5f * raw) << x << " " << y;
      lit += raw > 0.0f;
    }
  EXPECT_GT(lit, 20);

  write_table("half.json", 1.0);  // edited in place: only the fitted job renders again
  EXPECT_EQ(run("tables/half.json").rendered, 1u);
  renders = bump_renders();
  EXPECT_EQ(renders.at("fitted").pixels, renders.at("none").pixels);

  write_table("copy.json", 1.0);  // the same content under another name
  EXPECT_EQ(run("tables/copy.json").rendered, 0u);
}

}  // namespace
}  // namespace penumbra
