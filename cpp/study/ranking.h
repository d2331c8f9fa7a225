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
// The ranking metric is the combined relative error
//   C(m, v) = (E_term(m, v) + E_view(m, v)) / (E_term(none, v) + E_view(none, v)),
// 1 for raw bump, lower is better; relative to `none` in each variant, so one
// hard scene does not dominate the mean, and a ratio of sums, so that a
// variant where raw bump's grazing-view error is near 0 does not divide by
// noise. The whole-image RMSE is reported beside it but does not rank: it is
// dominated by per-pixel parallax, which no shading method can remove. Intervals: 95 % percentile
// bootstrap over variants (10,000 resamples, fixed seed). Tests: two-sided
// exact sign test over variants; between methods, Holm-adjusted across all
// pairs. Two methods are tied when the interval of their mean paired
// difference contains 0 or the adjusted p is at least 0.05.
#pragma once

#include <string>
#include <vector>

#include "analysis/statistics.h"
#include "study/compare.h"
#include "study/plan.h"

namespace penumbra {

inline constexpr double kRankingConfidence = 0.95;
inline constexpr double kSignificance = 0.05;

// One method against raw bump over the variants.
struct MethodStatistics {
  std::string method;    // label
  std::string rejected;  // why the literature rejects it, "" if not
  std::size_t variants = 0;
  double combined = 0.0;  // mean C over variants
  Interval combined_interval;
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
  int rank = 0;  // 1-based; tied methods share the rank of the first
};

// Two methods, paired on C over the variants.
struct PairStatistics {
  std::string a, b;
  PairedComparison combined;  // C(a) - C(b): negative when a is better
  double p_holm = 1.0;
  bool tied = true;
};

struct RankingStatistics {
  std::string scene;  // "" for all variants
  std::size_t variants = 0;
  std::vector<MethodStatistics> methods;  // by rank, `none` included
  std::vector<PairStatistics> pairs;
  std::vector<std::string> headline;  // sentences, from the numbers above
};

// Over the bump section's variants of `scene` ("" for all).
RankingStatistics ranking_statistics(const Plan& plan, const std::vector<ComparisonRow>& rows,
                                     const std::string& scene);

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

// The headline sentences of `s` (filled in by ranking_statistics).
std::vector<std::string> headline_sentences(const RankingStatistics& s);

}  // namespace penumbra
