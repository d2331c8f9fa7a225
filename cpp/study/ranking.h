// Rankings with statistics: each bump method against raw bump (`none`) and
// against each other, paired per variant, over the evaluator's renders
// compared with the evaluator's displacement ground truth.
//
// Per variant v and method m, two errors against the ground truth, both as
// fractions of albedo*E/pi and both RMS of binned means, so that the bump's
// phase averages out of each:
//   E_term(m, v)  the light's side: terminator-region profile RMSE (theta in
//                 [60, 100) deg, binned by the light angle);
//   E_view(m, v)  the viewer's side: grazing-view RMSE (lit pixels, theta <
//                 60 deg, binned by the view angle over [60, 75) deg), where
//                 a factor applied to wo darkens silhouettes that the
//                 light-angle profile never weighs (analysis/metrics.h).
// The one ranking metric (the primary metric) is the combined relative error
//   C(m, v) = (E_term(m, v) + E_view(m, v)) / (E_term(none, v) + E_view(none, v)),
// 1 for raw bump, lower is better; relative to `none` in each variant, so one
// hard scene does not dominate the mean, and a ratio of sums, so that a
// variant where raw bump's grazing-view error is near 0 does not divide by
// noise. Every other quantity (the mean absolute terminator RMSE, the
// whole-image RMSE) is reported beside it as a different quantity, and
// where it orders methods otherwise the report says why.
//
// Decisions follow one rule (analysis/rank_tests.h): rank groups from the
// intervals of paired differences of C with each group's leader, at a
// confidence that holds for all K - 1 comparisons of a step together
// (Bonferroni over the K ranked methods, family 95 %). Every interval of C
// in a ranking is at that confidence, so "better than raw bump" (C's
// interval below 1) and the rank groups never disagree about what a tie is.
// Whether a method's effect depends on an axis (amplitude, light, material)
// is a permutation test within matched variants, Holm-adjusted over methods
// and axes; where it does, each level is ranked on its own.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/rank_tests.h"
#include "analysis/statistics.h"
#include "study/compare.h"
#include "study/plan.h"

namespace penumbra {

inline constexpr double kRankingFamilyConfidence = 0.95;
inline constexpr double kSignificance = 0.05;
// Descriptive means (absolute errors per method): plain 95 % intervals.
inline constexpr double kMeanConfidence = 0.95;
inline constexpr int kInteractionPermutations = 9999;

// The per-variant quantities a ranking summarises as means with intervals:
// the primary metric first, then absolute errors in their own units.
struct RankedQuantity {
  const char* id;    // report.json key: "combined_relative_error", "profile.rmse_terminator", ...
  const char* unit;  // as the CSV and report.json state it
};
const std::vector<RankedQuantity>& ranked_quantities();

struct MeanInterval {
  double mean = 0.0;
  Interval interval;
};

// One method against raw bump over the variants.
struct MethodStatistics {
  std::string method;    // label
  std::string rejected;  // why the literature rejects it, "" if not
  std::size_t variants = 0;
  double combined = 0.0;       // mean C over variants
  Interval combined_interval;  // at the ranking's confidence
  // 1 - mean(E / E_none): the fraction of raw bump's error removed (negative:
  // added), with wins = variants where E < E_none.
  double terminator_improvement = 0.0;
  Interval terminator_interval;
  PairedComparison terminator;  // E_term(m) against E_term(none)
  // E_view(m) - E_view(none), fraction of albedo*E/pi: positive, the
  // method adds error at grazing views; with the mean signed error there
  // (negative: darker than the ground truth) over variants.
  PairedComparison view;
  double view_bias = 0.0;
  Interval view_bias_interval;
  // Variants where the method is darker than the truth at grazing views
  // (bias < 0), and its mean signed error over those.
  std::size_t view_darker = 0;
  double view_darker_mean = 0.0;
  int rank = 0;  // rank group, 1 = the best (analysis/rank_tests.h)
  std::string group_leader;
  PairedComparison versus_leader;  // C(m) - C(leader); n = 0 for the leader
  // Per ranked_quantities() entry, in its order: mean over variants with a
  // kMeanConfidence interval.
  std::vector<MeanInterval> means;
};

// Two methods, paired on C over the variants.
struct PairStatistics {
  std::string a, b;
  PairedComparison combined;  // C(a) - C(b): negative when a is better
  bool separated = false;     // its interval (at the ranking's confidence) excludes 0
};

struct RankingStatistics {
  std::string scene;  // "" for all variants
  std::size_t variants = 0;
  double confidence = kRankingFamilyConfidence;  // of each interval of C (simultaneous)
  std::vector<MethodStatistics> methods;         // by rank, `none` included
  std::vector<PairStatistics> pairs;             // every pair; overall ranking only
  std::vector<std::string> headline;             // findings in sentences, from the numbers above
  const MethodStatistics* find(const std::string& method) const;
};

// Over the bump section's variants of `scene` ("" for all).
RankingStatistics ranking_statistics(const Plan& plan, const std::vector<ComparisonRow>& rows,
                                     const std::string& scene);
// Over the bump variants with selected[v] set (plan indices); with every
// pair of methods compared when `all_pairs`.
RankingStatistics ranking_statistics(const Plan& plan, const std::vector<ComparisonRow>& rows,
                                     const std::vector<char>& selected, bool all_pairs);

// One level of an axis and the ranking over its variants.
struct LevelRanking {
  nlohmann::json value;
  std::string value_label, value_id;
  RankingStatistics ranking;
};

// Does method's C depend on the axis's level (analysis/rank_tests.h)?
struct Interaction {
  std::string method;
  LevelTest test;
  double p_holm = 1.0;  // over every method and axis of the study
  bool depends = false;
};

struct AxisStatistics {
  std::string pointer, label;  // the axis's pointer (or name) and label
  bool numeric = false;        // every value a plain number
  // Its levels light the scene with different kinds of light (distant,
  // sphere, quad, environment): the headline says whether the first
  // level's leader stays in the best rank group under the others.
  bool lighting = false;
  std::vector<LevelRanking> levels;
  std::vector<Interaction> interactions;  // every method but `none`
};

struct StudyStatistics {
  RankingStatistics overall;
  std::vector<RankingStatistics> per_scene;
  // Some scene is a mesh shape: the headline says whether the first
  // scene's leader stays in the best rank group on every other scene.
  bool mesh_scenes = false;
  std::vector<AxisStatistics> by_axis;
  std::vector<std::string> headline;  // the report's lead: 3 to 6 sentences
  // Where a differently defined quantity (the mean absolute terminator RMSE)
  // orders methods otherwise than the primary metric, and why.
  std::vector<std::string> notes;
};

// Everything the report says about the bump methods; `axes`: the bump
// section's axes, in the order of the variants' axis values.
StudyStatistics study_statistics(const Plan& plan, const std::vector<ComparisonRow>& rows,
                                 const std::vector<StudyAxis>& axes);

// Cross-renderer agreement: each external renderer's ground truth and each
// method it implements itself, against the evaluator's render of the same
// scene, by the terminator-region profile RMSE over the variants.
inline constexpr double kAgreementThreshold = 0.01;  // fraction of albedo*E/pi

struct AgreementSummary {
  RendererKind renderer = RendererKind::kPovray;
  std::string what;  // "ground truth" or a method label
  std::size_t variants = 0;
  double mean = 0.0, max = 0.0;  // terminator RMSE, fraction of albedo*E/pi
  Interval interval;             // bootstrap over variants
  std::size_t above = 0;         // variants above kAgreementThreshold
  std::string sentence;
};

std::vector<AgreementSummary> agreement_summaries(const std::vector<AgreementRow>& rows);

// The rule, in one sentence for the report.
std::string rank_rule_text(std::size_t methods);

}  // namespace penumbra
