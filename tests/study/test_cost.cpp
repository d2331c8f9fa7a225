// The dry run's cost estimate: rates from the study's own cache entries when
// there are some, the built-in table otherwise, and a table that covers
// every kind of render a plan can hold.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "image/image_io.h"
#include "study/cache.h"
#include "study/cost.h"
#include "study/plan.h"
#include "study/study_file.h"
#include "temp_dir_test.h"

namespace penumbra {
namespace {

using nlohmann::json;

class Cost : public TempDirTest {
 protected:
  // 2 variants x (truth + 2 methods) with the evaluator, 32x32 at 4 spp.
  Plan plan() {
    const json study = {
        {"version", 1},
        {"name", "cost"},
        {"scenes", {std::string(PENUMBRA_SOURCE_DIR) + "/scenes/calibration/sphere.json"}},
        {"set",
         {{"/camera/width", 32},
          {"/camera/height", 32},
          {"/camera/spp", 4},
          {"/displacement/edge_length", 0.04}}},
        {"axes", {{{"pointer", "/height/amplitude"}, {"values", {0.01, 0.02}}}}},
        {"methods", {"none", "chiang2019"}},
        {"renderers", {"evaluator"}}};
    std::ofstream(path("s.json")) << study.dump();
    std::filesystem::create_directories(path("cache"));
    Plan p = plan_study(load_study(path("s.json")), 8.0 * kGiB);
    assign_keys(p, {{RendererKind::kEvaluator, {"penumbra test", "digest"}}});
    return p;
  }
  // A cache entry that says it took `wall` seconds on `threads` threads.
  void store(const RenderCache& cache, const Job& job, const std::string& wall,
             const std::string& threads) {
    Image image;
    image.width = image.height = 1;
    image.channels = {"R", "G", "B", "A"};
    image.pixels = {0, 0, 0, 1};
    cache.store(job.key, image, {{kCostWallAttribute, wall}, {kCostThreadsAttribute, threads}});
  }
};

TEST_F(Cost, EveryKindOfRenderHasAPositiveBuiltInModel) {
  for (RendererKind r : all_renderers())  // a new renderer needs its prices too
    for (Representation rep :
         {Representation::kSmooth, Representation::kBump, Representation::kDisplacement})
      for (bool tessellated : {false, true}) {
        const auto m = built_in_cost(r, rep, tessellated);
        ASSERT_TRUE(m.has_value()) << to_string(r) << " " << int(rep) << tessellated;
        EXPECT_GT(m->per_msample, 0.0);
        EXPECT_GT(m->fixed, 0.0);  // every render costs something however small
        EXPECT_GE(m->per_mtriangle, 0.0);
      }
}

TEST_F(Cost, AnEmptyCacheIsPricedAtTheBuiltInModel) {
  const Plan p = plan();
  const RenderCache cache(path("cache"));
  const CostEstimate e = estimate_cost(p, cache, std::vector<char>(p.jobs.size(), 1), {}, 2);
  double total = 0.0;
  std::size_t renders = 0;
  for (const CostLine& line : e.lines) {
    EXPECT_EQ(line.measured, 0u);
    const RenderCostModel m = *built_in_cost(line.renderer, line.representation, line.tessellated);
    EXPECT_EQ(line.model.per_msample, m.per_msample);
    EXPECT_EQ(line.model.fixed, m.fixed);
    // Every job is 32 x 32 x 4 = 4096 pixel samples; the truths build a mesh.
    double expected = 0.0;
    for (const Job& job : p.jobs)
      if (job.renderer == line.renderer && job.representation == line.representation)
        expected += m.core_seconds(4096e-6, job.resources.triangles / 1e6);
    EXPECT_DOUBLE_EQ(line.core_seconds, expected);
    if (line.representation == Representation::kDisplacement) {
      EXPECT_GT(p.jobs[p.variants[0].jobs[0]].resources.triangles, 0.0);
    }
    total += line.core_seconds;
    renders += line.renders;
  }
  EXPECT_EQ(renders, p.jobs.size());
  EXPECT_DOUBLE_EQ(e.core_seconds, total);
  // 2 variants x 2 methods, the evaluator alone: 4 comparisons; no checks;
  // the wall time is the renders (and the renderer probe) on 2 cores plus
  // the report.
  EXPECT_EQ(e.comparisons, 4u);
  EXPECT_EQ(e.checks_core_seconds, 0.0);
  EXPECT_EQ(e.cores, 2);
  EXPECT_GT(e.wall_seconds, e.core_seconds / 2 + e.report_seconds);
  EXPECT_LT(e.wall_seconds, e.core_seconds / 2 + e.report_seconds + 2.0);
}

TEST_F(Cost, TheConvergenceChecksArePricedFromTheirFirstRound) {
  const Plan p = plan();
  const RenderCache cache(path("cache"));
  // The first round of one truth: its mesh at half the edge length (4x the
  // triangles) and 4x its samples.
  Job truth = p.jobs[static_cast<std::size_t>(p.truth(0, RendererKind::kEvaluator))];
  Job finer = truth, more = truth;
  finer.resources.triangles *= 4;
  more.refine(std::make_shared<const std::vector<Override>>(
                  std::vector<Override>{{"/camera/spp", 4 * truth.scene().camera.spp}}),
              nullptr);
  const CostEstimate none = estimate_cost(p, cache, std::vector<char>(p.jobs.size(), 1));
  const CostEstimate with =
      estimate_cost(p, cache, std::vector<char>(p.jobs.size(), 1), {finer, more});
  const RenderCostModel m =
      *built_in_cost(RendererKind::kEvaluator, Representation::kDisplacement, false);
  const double first = m.core_seconds(4096e-6, finer.resources.triangles / 1e6) +
                       m.core_seconds(4 * 4096e-6, truth.resources.triangles / 1e6);
  EXPECT_EQ(with.first_checks, 2u);
  EXPECT_DOUBLE_EQ(with.first_checks_core_seconds, first);
  EXPECT_DOUBLE_EQ(with.checks_core_seconds, kCheckRoundsRatio * first);
  EXPECT_NEAR(with.wall_seconds - none.wall_seconds, kCheckRoundsRatio * first, 1e-9);
}

TEST_F(Cost, CachedRendersOfTheSameKindSetTheSampleRateAsTheirMedian) {
  const Plan p = plan();
  const RenderCache cache(path("cache"));
  std::vector<char> to_render(p.jobs.size(), 1);
  // The first variant's bump renders are cached: 1 s x 2 threads, 3 s x 2,
  // and one entry with no cost recorded (it is not counted).
  std::vector<std::size_t> bump;
  for (std::size_t i : p.variants[0].jobs)
    if (p.jobs[i].representation == Representation::kBump) bump.push_back(i);
  ASSERT_EQ(bump.size(), 2u);
  store(cache, p.jobs[bump[0]], "1.000", "2");
  store(cache, p.jobs[bump[1]], "3.000", "2");
  to_render[bump[0]] = to_render[bump[1]] = 0;
  const CostEstimate e = estimate_cost(p, cache, to_render);
  bool seen = false;
  for (const CostLine& line : e.lines) {
    if (line.representation != Representation::kBump) {
      EXPECT_EQ(line.measured, 0u);
      continue;
    }
    seen = true;
    const double fixed = line.model.fixed;
    EXPECT_EQ(line.measured, 2u);
    EXPECT_EQ(line.renders, 2u);  // the second variant's
    // The rate left after the fixed part: median of 2 and 6 core-s.
    EXPECT_DOUBLE_EQ(line.model.per_msample, (4.0 - fixed) / 4096e-6);
    EXPECT_DOUBLE_EQ(line.core_seconds, 2 * 4.0);
    EXPECT_DOUBLE_EQ(line.core_seconds_low, 2 * 2.0);  // the fastest entry's rate
    EXPECT_DOUBLE_EQ(line.core_seconds_high, 2 * 6.0);
  }
  EXPECT_TRUE(seen);
}

TEST_F(Cost, EntriesWithDamagedCostAttributesAreIgnored) {
  const Plan p = plan();
  const RenderCache cache(path("cache"));
  std::vector<char> to_render(p.jobs.size(), 1);
  for (std::size_t i : p.variants[0].jobs) {
    store(cache, p.jobs[i], "-1", "x");
    to_render[i] = 0;
  }
  for (const CostLine& line : estimate_cost(p, cache, to_render).lines)
    EXPECT_EQ(line.measured, 0u);
}

}  // namespace
}  // namespace penumbra
