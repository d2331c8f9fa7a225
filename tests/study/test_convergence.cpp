// Ground-truth convergence (study/convergence.h): the decision on synthetic
// changes, and the loop on a real plan: it stops at the tolerance, reports a
// variant its budget cannot converge, and gives the variant's evaluator jobs
// the settings it reached.
#include <gtest/gtest.h>

#include "temp_dir_test.h"

#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "evaluator/evaluator.h"
#include "study/convergence.h"
#include "study/plan.h"
#include "study/study_file.h"

namespace penumbra {
namespace {

using nlohmann::json;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

GroundTruthSettings budget(double tolerance, int edge, int spp) {
  GroundTruthSettings s;
  s.tolerance = tolerance, s.max_edge_refinements = edge, s.max_spp_refinements = spp;
  return s;
}

TEST(ConvergenceDecision, BothChangesBelowTheToleranceConverge) {
  const ConvergenceDecision d = decide_refinement(0.0009, 0.0002, 0, 0, budget(0.001, 2, 3));
  EXPECT_TRUE(d.done);
  EXPECT_TRUE(d.converged);
}

TEST(ConvergenceDecision, EachSettingAboveTheToleranceIsRefined) {
  const GroundTruthSettings s = budget(0.001, 2, 3);
  ConvergenceDecision d = decide_refinement(0.002, 0.0001, 0, 0, s);
  EXPECT_FALSE(d.done);
  EXPECT_TRUE(d.refine_edge);
  EXPECT_FALSE(d.refine_spp);
  d = decide_refinement(0.0001, 0.001, 0, 0, s);  // at the tolerance is not below it
  EXPECT_FALSE(d.refine_edge);
  EXPECT_TRUE(d.refine_spp);
  d = decide_refinement(0.002, 0.002, 0, 1, s);
  EXPECT_TRUE(d.refine_edge && d.refine_spp);
}

TEST(ConvergenceDecision, AnEdgeChangeLeftAtTheMeshBudgetIsCheckedWithMoreSamples) {
  const ConvergenceDecision d = decide_refinement(0.002, 0.0001, 1, 0, budget(0.001, 2, 3));
  EXPECT_FALSE(d.done);
  EXPECT_FALSE(d.refine_edge);
  EXPECT_TRUE(d.refine_spp);
}

TEST(ConvergenceDecision, ASpentBudgetOrAFailedCheckEndsUnconverged) {
  // Edge steps 1 of 2: its check already went to edge / 4; samples spent too.
  ConvergenceDecision d = decide_refinement(0.002, 0.0001, 1, 2, budget(0.001, 2, 3));
  EXPECT_TRUE(d.done);
  EXPECT_FALSE(d.converged);
  d = decide_refinement(0.0001, 0.002, 0, 2, budget(0.001, 2, 3));
  EXPECT_TRUE(d.done);
  EXPECT_FALSE(d.converged);
  d = decide_refinement(kNaN, 0.0001, 0, 0, budget(0.001, 2, 3));
  EXPECT_TRUE(d.done);
  EXPECT_FALSE(d.converged);
}

// ---- the loop on a real plan ------------------------------------------------

class Convergence : public TempDirTest {
 protected:
  // One variant: the calibration cylinder at 32 px, evaluator and POV-Ray.
  Plan plan() const {
    const json study = {
        {"version", 1},
        {"scenes", {std::string(PENUMBRA_SOURCE_DIR) + "/scenes/calibration/cylinder.json"}},
        {"set",
         {{"/camera/width", 32},
          {"/camera/height", 32},
          {"/camera/spp", 1},
          {"/camera/jitter", false},
          {"/displacement/edge_length", 0.04}}},
        {"methods", {"none", "chiang2019"}},
        {"renderers", {"evaluator", "povray"}}};
    std::ofstream(path("s.json")) << study.dump();
    return plan_study(load_study(path("s.json")), 8.0 * kGiB);
  }
  // Renders with the evaluator directly (no cache), counting renders.
  RenderBatch batch() {
    return [this](const std::vector<Job>& jobs, const std::vector<ChainState>&,
                  std::vector<std::string>* errors) {
      std::vector<std::optional<Image>> out;
      for (const Job& j : jobs) out.push_back(render(j.scene()));
      errors->assign(jobs.size(), "");
      renders += jobs.size();
      return out;
    };
  }
  std::size_t renders = 0;
};

TEST_F(Convergence, StopsAtTheFirstSettingsWhoseChangesAreBelowTheTolerance) {
  Plan p = plan();
  const auto loose = converge_truths(p, budget(1.0, 2, 3), 8.0 * kGiB, batch());
  ASSERT_EQ(loose.size(), 1u);
  EXPECT_TRUE(loose[0].converged);
  EXPECT_EQ(loose[0].steps.size(), 1u);  // one check: truth, edge / 2, spp x 4
  EXPECT_EQ(renders, 3u);

  // A tolerance between the first check's changes and 0 needs refinement;
  // every step but the last is above the tolerance, the last below it.
  const double first = std::max(loose[0].steps[0].edge_change, loose[0].steps[0].spp_change);
  ASSERT_GT(first, 0.0);
  Plan q = plan();
  const auto tight = converge_truths(q, budget(0.9 * first, 3, 4), 8.0 * kGiB, batch());
  ASSERT_EQ(tight.size(), 1u);
  const VariantConvergence& c = tight[0];
  ASSERT_GE(c.steps.size(), 2u);
  for (std::size_t k = 0; k + 1 < c.steps.size(); ++k)
    EXPECT_GE(std::max(c.steps[k].edge_change, c.steps[k].spp_change), 0.9 * first);
  if (c.converged) {
    EXPECT_LT(c.reached, 0.9 * first);
    EXPECT_EQ(c.reached, std::max(c.steps.back().edge_change, c.steps.back().spp_change));
  }
  // The variant's evaluator jobs use the settings reached; POV-Ray keeps its own.
  for (std::size_t j : q.variants[0].jobs) {
    const Job& job = q.jobs[j];
    if (job.renderer == RendererKind::kEvaluator) {
      EXPECT_EQ(job.scene().camera.spp, c.spp);
      EXPECT_EQ(job.scene().displacement.edge_length, c.edge_length);
    } else {
      EXPECT_EQ(job.scene().camera.spp, 1);
      EXPECT_EQ(job.scene().displacement.edge_length, 0.04);
    }
  }
}

// What a Slurm array task does with a chain (continue_chain, from the start
// and from a later state) leaves exactly the renders that the rounds then
// need: they decide the same from those alone, rendering nothing.
TEST_F(Convergence, AChainContinuedElsewhereLeavesWhatTheRoundsNeed) {
  Plan p = plan();
  const long t = p.truth(0, RendererKind::kEvaluator);
  ASSERT_GE(t, 0);
  const Job truth = p.jobs[t];
  std::map<std::string, Image> rendered;  // by scene
  const RenderBatch render_and_keep = [&](const std::vector<Job>& jobs,
                                          const std::vector<ChainState>& chains,
                                          std::vector<std::string>* errors) {
    EXPECT_EQ(chains.size(), 1u);
    std::vector<std::optional<Image>> out;
    for (const Job& j : jobs) out.push_back(rendered[j.scene_json().dump()] = render(j.scene()));
    errors->assign(jobs.size(), "");
    return out;
  };
  std::size_t missing = 0;
  const RenderBatch kept_only = [&](const std::vector<Job>& jobs, const std::vector<ChainState>&,
                                    std::vector<std::string>* errors) {
    std::vector<std::optional<Image>> out;
    for (const Job& j : jobs) {
      const auto it = rendered.find(j.scene_json().dump());
      missing += it == rendered.end();
      out.push_back(it == rendered.end() ? std::nullopt : std::optional<Image>(it->second));
    }
    errors->assign(jobs.size(), "");
    return out;
  };
  // A tolerance that needs more than one check.
  const GroundTruthSettings loose = budget(1.0, 2, 3);
  Plan a = plan();
  const double first = [&] {
    const auto r = converge_truths(a, loose, 8.0 * kGiB, batch());
    return std::max(r[0].steps[0].edge_change, r[0].steps[0].spp_change);
  }();
  const GroundTruthSettings tight = budget(0.9 * first, 3, 4);
  const VariantConvergence chain = continue_chain(truth, 0, 0, tight, 8.0 * kGiB, render_and_keep);
  const auto rounds = converge_truths(p, tight, 8.0 * kGiB, kept_only);
  EXPECT_EQ(missing, 0u);
  ASSERT_EQ(rounds.size(), 1u);
  EXPECT_GE(rounds[0].steps.size(), 2u);
  EXPECT_EQ(chain.steps.size(), rounds[0].steps.size());
  EXPECT_EQ(chain.converged, rounds[0].converged);
  EXPECT_EQ(chain.edge_length, rounds[0].edge_length);
  EXPECT_EQ(chain.spp, rounds[0].spp);
  EXPECT_EQ(chain.reached, rounds[0].reached);
  // Continued from the second check's state, it has the steps from there on.
  const ConvergenceStep& second = rounds[0].steps[1];
  const int edge_steps =
      int(std::lround(std::log2(truth.scene().displacement.edge_length / second.edge_length)));
  const int spp_steps = int(std::lround(std::log2(second.spp / truth.scene().camera.spp) / 2));
  const VariantConvergence later =
      continue_chain(truth, edge_steps, spp_steps, tight, 8.0 * kGiB, kept_only);
  EXPECT_EQ(missing, 0u);
  ASSERT_EQ(later.steps.size(), rounds[0].steps.size() - 1);
  EXPECT_EQ(later.steps[0].edge_length, second.edge_length);
  EXPECT_EQ(later.steps[0].spp, second.spp);
  EXPECT_EQ(later.edge_length, rounds[0].edge_length);
  EXPECT_EQ(later.spp, rounds[0].spp);
  // The variant's evaluator jobs at the settings reached, the others as planned.
  const Plan fresh = plan();
  for (std::size_t j : p.variants[0].jobs) {
    Job job = fresh.jobs[j];
    apply_convergence(job, chain);
    EXPECT_EQ(job.scene_json(), p.jobs[j].scene_json()) << job.label;
  }
}

TEST_F(Convergence, ReportsAVariantItsBudgetCannotConverge) {
  Plan p = plan();
  const auto r = converge_truths(p, budget(1e-12, 1, 1), 8.0 * kGiB, batch());
  ASSERT_EQ(r.size(), 1u);
  EXPECT_FALSE(r[0].converged);
  EXPECT_NE(r[0].why.find("budget"), std::string::npos) << r[0].why;
  EXPECT_EQ(r[0].steps.size(), 1u);
  EXPECT_EQ(r[0].edge_length, 0.04);  // nothing refined: the check was all it could afford
  EXPECT_EQ(r[0].spp, 1);
}

TEST_F(Convergence, AMemoryLimitStopsTheMeshRefinementAndSaysSo) {
  Plan p = plan();
  const double truth_memory = p.jobs[p.truth(0, RendererKind::kEvaluator)].resources.memory_bytes;
  // Enough for the truth (and its spp x 4 check, the same mesh), not for its
  // edge / 2 check: 4x the triangles.
  const auto r = converge_truths(p, budget(1e-12, 2, 3), truth_memory * (1.0 + 1e-9), batch());
  ASSERT_EQ(r.size(), 1u);
  EXPECT_FALSE(r[0].converged);
  EXPECT_NE(r[0].why.find("GiB"), std::string::npos) << r[0].why;
}

// A check finer than the triangles a truth may have (the scene reader's
// limit) ends that variant's mesh budget, as memory does, instead of
// failing the study. The calibration cylinder at edge 0.001 is 25 million
// triangles, its edge / 2 check 101 million; the renders themselves are of
// the scene at edge 0.04, each with a seed of its own, so that every change
// is above the tolerance.
TEST_F(Convergence, ATriangleLimitStopsTheMeshRefinementAndSaysSo) {
  const json study = {
      {"version", 1},
      {"scenes", {std::string(PENUMBRA_SOURCE_DIR) + "/scenes/calibration/cylinder.json"}},
      {"set",
       {{"/camera/width", 16},
        {"/camera/height", 16},
        {"/camera/spp", 1},
        {"/displacement/edge_length", 0.001}}},
      {"methods", {"none"}},
      {"renderers", {"evaluator"}}};
  std::ofstream(path("s.json")) << study.dump();
  Plan p = plan_study(load_study(path("s.json")), 8.0 * kGiB);
  std::uint64_t seed = 1;
  const RenderBatch cheap = [&](const std::vector<Job>& jobs, const std::vector<ChainState>&,
                                std::vector<std::string>* errors) {
    std::vector<std::optional<Image>> out;
    for (const Job& j : jobs) {
      Scene s = j.scene();
      s.displacement.edge_length = 0.04;
      s.camera.seed = seed++;
      out.push_back(render(s));
    }
    errors->assign(jobs.size(), "");
    return out;
  };
  const auto r = converge_truths(p, budget(1e-12, 2, 1), 8.0 * kGiB, cheap);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_FALSE(r[0].converged);
  EXPECT_NE(r[0].why.find("edge length 0.0005 cannot be rendered"), std::string::npos) << r[0].why;
  EXPECT_NE(r[0].why.find("million"), std::string::npos) << r[0].why;
  EXPECT_EQ(r[0].edge_length, 0.001);
}

TEST_F(Convergence, AZeroBudgetRendersNothingAndFlagsEveryTruth) {
  Plan p = plan();
  const auto r = converge_truths(p, budget(0.001, 0, 3), 8.0 * kGiB, batch());
  ASSERT_EQ(r.size(), 1u);
  EXPECT_FALSE(r[0].converged);
  EXPECT_EQ(renders, 0u);
}

}  // namespace
}  // namespace penumbra
