// Rankings with statistics on synthetic comparison tables whose answers are
// known: a clear winner, an exact tie, a method that darkens what the viewer
// sees.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "study/ranking.h"
#include "study/ranking_text.h"

namespace penumbra {
namespace {

struct Synthetic {
  Plan plan;
  std::vector<ComparisonRow> rows;
  // One evaluator row per (variant, method): terminator and grazing-view
  // errors and the signed grazing-view error, fractions of albedo*E/pi.
  void add(std::size_t v, const std::string& method, double term, double view, double bias) {
    while (plan.variants.size() <= v) {
      Variant var;
      var.id = "v" + std::to_string(plan.variants.size());
      var.scene = plan.variants.size() % 2 ? "odd" : "even";
      plan.variants.push_back(var);
    }
    ComparisonRow row;
    row.variant = v;
    row.job = plan.jobs.size();
    row.method = method;
    row.profile.rmse_terminator = term;
    row.view.rmse_grazing = view;
    row.view.bias_grazing = bias;
    plan.jobs.push_back(Job{});
    rows.push_back(row);
  }
};

const MethodStatistics& find(const RankingStatistics& s, const std::string& m) {
  for (const MethodStatistics& x : s.methods)
    if (x.method == m) return x;
  throw std::runtime_error("no " + m);
}

Synthetic table() {
  Synthetic t;
  for (std::size_t v = 0; v < 12; ++v) {
    const double hard = 1.0 + 0.5 * double(v);  // errors differ tenfold across variants
    t.add(v, "none", 0.10 * hard, 0.02 * hard, 0.02 * hard);
    t.add(v, "good", 0.05 * hard, 0.02 * hard, 0.02 * hard);  // halves the terminator error
    t.add(v, "twin", 0.05 * hard, 0.02 * hard, 0.02 * hard);  // exactly as good
    // The same terminator gain, but grazing views darkened well below the truth.
    t.add(v, "dark", 0.05 * hard, 0.10 * hard, -0.10 * hard);
  }
  return t;
}

TEST(Ranking, ClearWinnerExactTieAndAViewerPenalty) {
  const Synthetic t = table();
  const RankingStatistics s = ranking_statistics(t.plan, t.rows, "");
  ASSERT_EQ(s.methods.size(), 4u);
  EXPECT_EQ(s.variants, 12u);
  const MethodStatistics& good = find(s, "good");
  // Relative to none in each variant: exactly half, in every variant.
  EXPECT_NEAR(good.terminator_improvement, 0.5, 1e-12);
  EXPECT_NEAR(good.terminator_interval.low, 0.5, 1e-12);
  EXPECT_EQ(good.terminator.a_better, 12u);
  EXPECT_DOUBLE_EQ(good.terminator.p, 2.0 / 4096.0);
  EXPECT_NEAR(good.combined, 0.07 / 0.12, 1e-12);  // (0.05 + 0.02) / (0.10 + 0.02)
  // good and twin: an exact tie, one rank, first.
  EXPECT_EQ(good.rank, 1);
  EXPECT_EQ(find(s, "twin").rank, 1);
  // dark: the same terminator gain, but its grazing-view error is 5x raw
  // bump's: C = 0.15 / 0.12 = 1.25, ranked below raw bump, and the headline
  // says why and that it is darker than the truth.
  EXPECT_NEAR(find(s, "dark").combined, 1.25, 1e-12);
  EXPECT_NEAR(find(s, "dark").view.mean_difference, 0.08 * 3.75, 1e-12);  // mean of 0.08 h
  EXPECT_LT(find(s, "dark").view_bias, 0.0);
  EXPECT_GT(find(s, "dark").rank, find(s, "none").rank);
  bool tie_sentence = false, darkens = false;
  for (const std::string& line : s.headline) {
    tie_sentence |= line.find("good and twin are tied") != std::string::npos;
    darkens |= line.find("dark adds error where the viewer looks at grazing angles") !=
                   std::string::npos &&
               line.find("darker than the ground truth") != std::string::npos;
  }
  EXPECT_TRUE(tie_sentence) << s.headline.front();
  EXPECT_TRUE(darkens);
  EXPECT_NE(s.headline.front().find("Closest to the displacement ground truth over 12 variants"),
            std::string::npos)
      << s.headline.front();
}

TEST(Ranking, PerSceneSelectsItsVariantsAndNoBaselineGivesNoRanking) {
  const Synthetic t = table();
  EXPECT_EQ(ranking_statistics(t.plan, t.rows, "odd").variants, 6u);
  Synthetic without;
  without.add(0, "good", 0.1, 0.1, 0.0);
  EXPECT_TRUE(ranking_statistics(without.plan, without.rows, "").methods.empty());
}

// Two scenes x two amplitudes x twelve light directions. "flip" helps at
// A = 0.02 (0.7 of raw bump's error) and hurts at A = 0.005 (2.5 of it);
// "steady" is 0.8 of raw bump's everywhere. Raw bump's own error is ten
// times larger at A = 0.02, so the mean absolute error puts flip below raw
// bump while the ranking metric puts it above.
struct Sweep {
  Synthetic t;
  std::vector<StudyAxis> axes;
};
Sweep interaction_sweep() {
  Sweep s;
  StudyAxis amplitude;
  amplitude.pointer = "/height/amplitude";
  amplitude.label = "amplitude A (scene units)";
  amplitude.values = {0.005, 0.02};
  StudyAxis light;
  light.pointer = "/light/direction";
  light.label = "light direction";
  for (int k = 0; k < 12; ++k) light.values.push_back(nlohmann::json::array({-1, 0, 0.05 * k}));
  s.axes = {amplitude, light};
  std::size_t v = 0;
  for (const char* scene : {"cylinder", "sphere"})
    for (int l = 0; l < 12; ++l)
      for (int a = 0; a < 2; ++a, ++v) {
        const double none = a == 1 ? 0.1 : 0.01, jitter = 1.0 + 0.01 * ((l + a) % 3 - 1);
        s.t.add(v, "none", none, 0.0, 0.0);
        s.t.add(v, "flip", none * (a == 1 ? 0.7 : 2.5) * jitter, 0.0, 0.0);
        s.t.add(v, "steady", none * 0.8 * jitter, 0.0, 0.0);
        Variant& var = s.t.plan.variants[v];
        var.scene = scene;
        var.section = SectionKind::kBump;
        var.axis_values = {amplitude.values[static_cast<std::size_t>(a)],
                           light.values[static_cast<std::size_t>(l)]};
      }
  return s;
}

TEST(StudyStatistics, AnInteractionIsFoundRankedPerLevelAndSaidInTheLead) {
  const Sweep w = interaction_sweep();
  const StudyStatistics s = study_statistics(w.t.plan, w.t.rows, w.axes);
  ASSERT_EQ(s.by_axis.size(), 2u);
  const AxisStatistics& amp = s.by_axis[0];
  ASSERT_EQ(amp.levels.size(), 2u);
  for (const Interaction& i : amp.interactions)
    EXPECT_EQ(i.depends, i.method == "flip") << i.method << " p_holm " << i.p_holm;
  for (const Interaction& i : s.by_axis[1].interactions) EXPECT_FALSE(i.depends) << i.method;
  // Per level: flip first where it helps, behind raw bump where it hurts.
  EXPECT_EQ(amp.levels[1].ranking.methods.front().method, "flip");
  EXPECT_GT(amp.levels[0].ranking.find("flip")->rank, amp.levels[0].ranking.find("none")->rank);
  EXPECT_EQ(amp.levels[0].value_id, "0.005");
  // Overall, flip is worse than raw bump (mean C 1.6), steady leads.
  EXPECT_EQ(s.overall.methods.front().method, "steady");
  EXPECT_GT(s.overall.find("flip")->combined_interval.low, 1.0);
  ASSERT_GE(s.headline.size(), 3u);
  ASSERT_LE(s.headline.size(), 6u);
  bool said = false;
  for (const std::string& line : s.headline)
    said |= line.find("flip helps at amplitude A = 0.02") != std::string::npos &&
            line.find("hurts at amplitude A = 0.005") != std::string::npos &&
            line.find("depends on the amplitude A") != std::string::npos;
  EXPECT_TRUE(said) << s.headline[2];
  // The absolute mean disagrees (flip below raw bump) and a note says why.
  ASSERT_EQ(s.notes.size(), 1u);
  EXPECT_NE(s.notes[0].find("flip is below raw bump"), std::string::npos) << s.notes[0];
  EXPECT_NE(s.notes[0].find("largest at amplitude A = 0.02"), std::string::npos) << s.notes[0];
}

TEST(StudyStatistics, OneRuleDecidesEveryRankAndEveryVerdict) {
  // The leader sentence names exactly the methods of rank group 1, and a
  // method's "worse than raw bump" verdict is its interval above 1 at the
  // ranking's own confidence: the same intervals the groups use.
  const Sweep w = interaction_sweep();
  const StudyStatistics s = study_statistics(w.t.plan, w.t.rows, w.axes);
  for (const RankingStatistics* r :
       {&s.overall, &s.by_axis[0].levels[0].ranking, &s.by_axis[0].levels[1].ranking}) {
    const std::string lead = finding_sentences(*r).front();
    for (const MethodStatistics& m : r->methods) {
      const bool named = lead.find(" " + m.method) != std::string::npos;
      EXPECT_EQ(named, m.rank == 1) << m.method << ": " << lead;
      if (m.method != m.group_leader) {
        const MethodStatistics* leader = r->find(m.group_leader);
        EXPECT_EQ(leader->rank, m.rank);
        EXPECT_TRUE(m.versus_leader.interval.contains(0.0));
      }
    }
  }
  EXPECT_NE(s.headline[1].find("flip"), std::string::npos) << s.headline[1];
}

// Three kinds of light x two scenes x four amplitudes: "a" is half of raw
// bump's error under the sun and the sphere light but 0.9 of it under the
// environment, where "b" (0.7 elsewhere) is 0.4. The headline must say
// that the sun's winner a leaves the best rank group under the environment
// only, and who leads there.
TEST(StudyStatistics, TheHeadlineSaysWhetherTheSunsWinnerWinsUnderEveryLighting) {
  StudyAxis lighting;
  lighting.pointer = "lighting";
  lighting.label = "lighting (kinds of light)";
  lighting.values = {"sun", "sphere light", "environment"};
  lighting.ids = {"sun", "sphere", "env"};
  lighting.sets.resize(3);
  Synthetic t;
  std::size_t v = 0;
  for (int l = 0; l < 3; ++l)
    for (const char* scene : {"cylinder", "sphere"})
      for (int a = 0; a < 4; ++a, ++v) {
        const double none = 0.02 * (1 + a), jitter = 1.0 + 0.01 * ((l + a) % 3 - 1);
        t.add(v, "none", none, 0.0, 0.0);
        t.add(v, "a", none * (l == 2 ? 0.9 : 0.5) * jitter, 0.0, 0.0);
        t.add(v, "b", none * (l == 2 ? 0.4 : 0.7) / jitter, 0.0, 0.0);
        Variant& var = t.plan.variants[v];
        var.scene = scene;
        var.section = SectionKind::kBump;
        var.axis_values = {lighting.values[static_cast<std::size_t>(l)]};
      }
  StudyStatistics s = study_statistics(t.plan, t.rows, {lighting});
  ASSERT_EQ(s.by_axis.size(), 1u);
  // The synthetic plan has no scenes to read light types from.
  EXPECT_FALSE(s.by_axis[0].lighting);
  for (const std::string& line : s.headline)
    EXPECT_EQ(line.find("Under the sun"), std::string::npos) << line;
  s.by_axis[0].lighting = true;
  s.headline = lead_sentences(s);
  ASSERT_LE(s.headline.size(), 6u);
  std::string said;
  for (const std::string& line : s.headline)
    if (line.rfind("Under the sun (lighting), a leads at 50", 0) == 0) said = line;
  ASSERT_FALSE(said.empty()) << s.headline[0];
  EXPECT_NE(said.find("falls out of the best rank group under env (rank group 2"),
            std::string::npos)
      << said;
  EXPECT_NE(said.find("b leads at 40"), std::string::npos) << said;
  EXPECT_NE(said.find("stays in it under sphere: the winner changes"), std::string::npos) << said;
  // Where a also wins under the environment, the sentence says it never changes.
  for (ComparisonRow& r : t.rows)
    if (r.method == "a" && r.variant >= 16) r.profile.rmse_terminator *= 0.3 / 0.9;
  s = study_statistics(t.plan, t.rows, {lighting});
  s.by_axis[0].lighting = true;
  s.headline = lead_sentences(s);
  bool kept = false;
  for (const std::string& line : s.headline)
    kept |= line.find(
                "stays in the best rank group under all 2 other lightings (sphere and "
                "env): the ranking's winner does not change") != std::string::npos;
  EXPECT_TRUE(kept) << s.headline[0];
}

// A study of mesh assets says whether its first scene's leader (the
// reference shape) stays in the best rank group on each asset: here a leads
// on the sphere and on the duck, b on the wuson.
TEST(StudyStatistics, TheHeadlineSaysWhetherTheFirstScenesWinnerHoldsOnEveryAsset) {
  Synthetic t;
  std::size_t v = 0;
  for (const char* scene : {"sphere", "duck", "wuson"})
    for (int a = 0; a < 6; ++a, ++v) {
      const bool wuson = std::string(scene) == "wuson";
      const double none = 0.02 * (1 + a), jitter = 1.0 + 0.01 * (a % 3 - 1);
      t.add(v, "none", none, 0.0, 0.0);
      t.add(v, "a", none * (wuson ? 0.9 : 0.5) * jitter, 0.0, 0.0);
      t.add(v, "b", none * (wuson ? 0.4 : 0.7) / jitter, 0.0, 0.0);
      t.plan.variants[v].scene = scene;
      t.plan.variants[v].section = SectionKind::kBump;
    }
  StudyStatistics s = study_statistics(t.plan, t.rows, {});
  // The synthetic plan has no scenes to read shapes from: no mesh, no sentence.
  EXPECT_FALSE(s.mesh_scenes);
  for (const std::string& line : s.headline)
    EXPECT_EQ(line.find("On the first scene"), std::string::npos) << line;
  s.mesh_scenes = true;
  s.headline = lead_sentences(s);
  ASSERT_LE(s.headline.size(), 6u);
  std::string said;
  for (const std::string& line : s.headline)
    if (line.rfind("On the first scene (sphere), a leads at 50", 0) == 0) said = line;
  ASSERT_FALSE(said.empty()) << s.headline[0];
  EXPECT_NE(said.find("falls out of the best rank group on wuson (rank group 2"), std::string::npos)
      << said;
  EXPECT_NE(said.find("b leads at 40"), std::string::npos) << said;
  EXPECT_NE(said.find("stays in it on duck: the winner changes with the scene."), std::string::npos)
      << said;
}

TEST(Agreement, SummariesPerRendererAndWhatWithThresholdCounts) {
  std::vector<AgreementRow> rows;
  for (std::size_t v = 0; v < 10; ++v) {
    AgreementRow truth;
    truth.variant = v, truth.renderer = RendererKind::kPovray, truth.what = "ground truth";
    truth.profile.rmse_terminator = 0.002;  // always within 1 %
    rows.push_back(truth);
    AgreementRow bump = truth;
    bump.renderer = RendererKind::kBlender, bump.what = "chiang2019";
    bump.profile.rmse_terminator = v < 3 ? 0.02 : 0.005;  // 3 variants above 1 %
    rows.push_back(bump);
  }
  const std::vector<AgreementSummary> s = agreement_summaries(rows);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].renderer, RendererKind::kPovray);
  EXPECT_NEAR(s[0].mean, 0.002, 1e-15);
  EXPECT_EQ(s[0].above, 0u);
  EXPECT_NEAR(s[0].interval.low, 0.002, 1e-15);
  EXPECT_NEAR(s[1].mean, (3 * 0.02 + 7 * 0.005) / 10, 1e-15);
  EXPECT_EQ(s[1].above, 3u);
  EXPECT_NEAR(s[1].max, 0.02, 1e-15);
  EXPECT_NE(s[1].sentence.find("3 variants above 1 %"), std::string::npos) << s[1].sentence;
}

}  // namespace
}  // namespace penumbra
