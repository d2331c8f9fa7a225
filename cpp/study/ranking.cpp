#include "study/ranking.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <thread>

#include <fmt/format.h>

#include "study/ranking_text.h"
#include "util/parallel.h"

namespace penumbra {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

using Values = std::vector<double>;

// Per method label, its errors in each selected variant (NaN: missing).
struct ErrorTable {
  std::vector<std::size_t> variants;  // plan indices
  std::vector<std::string> methods;   // in order of first appearance
  // Per ranked_quantities() entry but the first (C is derived), then the
  // signed grazing-view error.
  std::map<std::string, std::vector<Values>> quantity;
};

// What each ranked quantity reads from a comparison, ranked_quantities()[1..].
double quantity_of(const ComparisonRow& row, std::size_t q) {
  switch (q) {
    case 1:
      return row.profile.rmse_terminator;
    case 2:
      return row.view.rmse_grazing;
    case 3:
      return row.profile.position_error;
    case 4:
      return row.image.rmse;
    case 5:
      return row.image.ssim;
    case 6:
      return row.image.flip;
    default:
      return row.view.bias_grazing;
  }
}
constexpr std::size_t kTerm = 1, kView = 2, kBias = 7, kQuantities = 8;

ErrorTable error_table(const Plan& plan, const std::vector<ComparisonRow>& rows,
                       const std::vector<char>& selected) {
  ErrorTable t;
  std::map<std::size_t, std::size_t> column;
  for (std::size_t v = 0; v < plan.variants.size(); ++v) {
    if (plan.variants[v].section != SectionKind::kBump || !selected[v]) continue;
    column[v] = t.variants.size();
    t.variants.push_back(v);
  }
  for (const ComparisonRow& row : rows) {
    const auto c = column.find(row.variant);
    if (c == column.end() || row.renderer != RendererKind::kEvaluator ||
        row.reference_renderer != RendererKind::kEvaluator)
      continue;
    std::vector<Values>& q = t.quantity[row.method];
    if (q.empty()) {
      t.methods.push_back(row.method);
      q.assign(kQuantities, Values(t.variants.size(), kNaN));
    }
    for (std::size_t k = 1; k < kQuantities; ++k) q[k][c->second] = quantity_of(row, k);
  }
  return t;
}

// x / baseline per variant; NaN where either is undefined or the baseline is 0.
Values relative(const Values& x, const Values& baseline) {
  Values r(x.size(), kNaN);
  for (std::size_t v = 0; v < x.size(); ++v)
    if (std::isfinite(x[v]) && std::isfinite(baseline[v]) && baseline[v] > 0.0)
      r[v] = x[v] / baseline[v];
  return r;
}

Values finite(const Values& x) {
  Values out;
  for (double v : x)
    if (std::isfinite(v)) out.push_back(v);
  return out;
}

double mean(const Values& x) {
  if (x.empty()) return kNaN;
  double sum = 0.0;
  for (double v : x) sum += v;
  return sum / double(x.size());
}

MeanInterval mean_interval(const Values& x, double confidence) {
  const Values f = finite(x);
  return {mean(f), bootstrap_mean_interval(f, confidence)};
}

// 1 - mean(ratio) and its interval (the interval of 1 - mean, flipped).
void improvement(const Values& ratio, double confidence, double* value, Interval* interval) {
  const Values r = finite(ratio);
  *value = 1.0 - mean(r);
  const Interval i = bootstrap_mean_interval(r, confidence);
  *interval = {1.0 - i.high, 1.0 - i.low};
}

std::string method_rejection(const std::string& label) {
  const std::string id = label.substr(0, label.find('('));
  const auto m = method_from_id(id);
  return m ? std::string(method_info(*m).rejected) : std::string();
}

MethodStatistics method_statistics(const ErrorTable& t, const std::string& m,
                                   const Values& combined, double confidence) {
  const std::vector<Values>& q = t.quantity.at(m);
  const std::vector<Values>& none = t.quantity.at("none");
  MethodStatistics s;
  s.method = m;
  s.rejected = method_rejection(m);
  const Values c = finite(combined);
  s.variants = c.size();
  s.combined = mean(c);
  s.combined_interval = bootstrap_mean_interval(c, confidence);
  improvement(relative(q[kTerm], none[kTerm]), confidence, &s.terminator_improvement,
              &s.terminator_interval);
  s.terminator = compare_paired(q[kTerm], none[kTerm], confidence);
  s.view = compare_paired(q[kView], none[kView], confidence);
  const Values bias = finite(q[kBias]);
  s.view_bias = mean(bias);
  s.view_bias_interval = bootstrap_mean_interval(bias, confidence);
  double darker_sum = 0.0;
  for (double b : bias)
    if (b < 0.0) ++s.view_darker, darker_sum += b;
  s.view_darker_mean = s.view_darker ? darker_sum / double(s.view_darker) : 0.0;
  s.means.push_back(mean_interval(combined, kMeanConfidence));
  for (std::size_t k = 1; k < ranked_quantities().size(); ++k)
    s.means.push_back(mean_interval(q[k], kMeanConfidence));
  return s;
}

// Every pair of methods on C at the ranking's confidence.
std::vector<PairStatistics> pair_statistics(const std::vector<MethodStatistics>& methods,
                                            const std::map<std::string, Values>& combined,
                                            double confidence) {
  std::vector<PairStatistics> pairs;
  for (std::size_t i = 0; i < methods.size(); ++i)
    for (std::size_t j = i + 1; j < methods.size(); ++j) {
      PairStatistics p;
      p.a = methods[i].method, p.b = methods[j].method;
      pairs.push_back(std::move(p));
    }
  // 190 bootstraps for 20 methods. Each has its own seed, so the threads do
  // not change them.
  run_parallel(static_cast<int>(std::thread::hardware_concurrency()), pairs.size(),
               [&](std::size_t k) {
                 PairStatistics& p = pairs[k];
                 p.combined = compare_paired(combined.at(p.a), combined.at(p.b), confidence);
                 p.separated = p.combined.n > 0 && !p.combined.interval.contains(0.0);
               });
  return pairs;
}

// Orders the methods by mean C and assigns the rank groups.
void assign_groups(RankingStatistics& s, const std::map<std::string, Values>& combined) {
  std::sort(s.methods.begin(), s.methods.end(),
            [](const MethodStatistics& a, const MethodStatistics& b) {
              if (std::isnan(a.combined) != std::isnan(b.combined)) return std::isnan(b.combined);
              return a.combined != b.combined ? a.combined < b.combined : a.method < b.method;
            });
  std::vector<Values> values;
  for (const MethodStatistics& m : s.methods) values.push_back(combined.at(m.method));
  const std::vector<RankGroup> groups = rank_groups(values, s.confidence);
  for (std::size_t i = 0; i < s.methods.size(); ++i) {
    s.methods[i].rank = groups[i].group;
    s.methods[i].group_leader = s.methods[groups[i].leader].method;
    s.methods[i].versus_leader = groups[i].versus_leader;
  }
  // A group holds every method not separated from its leader, wherever its
  // mean falls: listed by group, then by mean.
  std::stable_sort(
      s.methods.begin(), s.methods.end(),
      [](const MethodStatistics& a, const MethodStatistics& b) { return a.rank < b.rank; });
}

}  // namespace

const std::vector<RankedQuantity>& ranked_quantities() {
  static const std::vector<RankedQuantity> q{
      {"combined_relative_error", "fraction of raw bump's E_term + E_view in the same variant"},
      {"profile.rmse_terminator", "fraction of albedo*E/pi"},
      {"view.rmse_grazing", "fraction of albedo*E/pi"},
      {"profile.position_error_deg", "degrees"},
      {"image.rmse", "W m^-2 sr^-1"},
      {"image.ssim", "unitless, [-1, 1], 1 = identical"},
      {"image.flip", "unitless, [0, 1], 0 = identical (HDR-FLIP at 67.02 pixels per degree)"}};
  return q;
}

const MethodStatistics* RankingStatistics::find(const std::string& method) const {
  for (const MethodStatistics& m : methods)
    if (m.method == method) return &m;
  return nullptr;
}

RankingStatistics ranking_statistics(const Plan& plan, const std::vector<ComparisonRow>& rows,
                                     const std::vector<char>& selected, bool all_pairs) {
  RankingStatistics s;
  const ErrorTable t = error_table(plan, rows, selected);
  s.variants = t.variants.size();
  if (!t.quantity.count("none")) return s;  // no raw bump to measure against
  s.confidence = simultaneous_confidence(kRankingFamilyConfidence, t.methods.size() - 1);
  const std::vector<Values>& none = t.quantity.at("none");
  std::map<std::string, Values> combined;
  for (const std::string& m : t.methods) {
    const std::vector<Values>& q = t.quantity.at(m);
    Values sum(t.variants.size()), none_sum(t.variants.size());
    for (std::size_t v = 0; v < t.variants.size(); ++v) {
      sum[v] = q[kTerm][v] + q[kView][v];
      none_sum[v] = none[kTerm][v] + none[kView][v];
    }
    combined[m] = relative(sum, none_sum);
    s.methods.push_back(method_statistics(t, m, combined[m], s.confidence));
  }
  assign_groups(s, combined);
  if (all_pairs) s.pairs = pair_statistics(s.methods, combined, s.confidence);
  s.headline = finding_sentences(s);
  return s;
}

RankingStatistics ranking_statistics(const Plan& plan, const std::vector<ComparisonRow>& rows,
                                     const std::string& scene) {
  std::vector<char> selected(plan.variants.size(), 0);
  for (std::size_t v = 0; v < plan.variants.size(); ++v)
    selected[v] = scene.empty() || plan.variants[v].scene == scene;
  RankingStatistics s = ranking_statistics(plan, rows, selected, scene.empty());
  s.scene = scene;
  return s;
}

std::string rank_rule_text(std::size_t methods) {
  const std::size_t comparisons = methods > 1 ? methods - 1 : 1;
  return fmt::format(
      "Rank groups: methods in order of their mean combined error; the best method not yet "
      "grouped leads the next group, which holds every later method whose paired difference "
      "from the leader (over the same variants) has an interval containing 0. Intervals of the "
      "combined error are {:.2f} % percentile-bootstrap intervals over variants, so that the "
      "{} {} of a step {} together at 95 % (Bonferroni over the {} methods ranked).",
      100.0 * simultaneous_confidence(kRankingFamilyConfidence, comparisons), comparisons,
      comparisons == 1 ? "comparison" : "comparisons", comparisons == 1 ? "holds" : "hold",
      methods);
}

std::vector<AgreementSummary> agreement_summaries(const std::vector<AgreementRow>& rows) {
  std::vector<AgreementSummary> out;
  std::map<std::pair<int, std::string>, Values> values;
  std::vector<std::pair<RendererKind, std::string>> order;
  for (const AgreementRow& row : rows) {
    const auto key = std::make_pair(static_cast<int>(row.renderer), row.what);
    if (!values.count(key)) order.push_back({row.renderer, row.what});
    if (std::isfinite(row.profile.rmse_terminator))
      values[key].push_back(row.profile.rmse_terminator);
    else
      values[key];
  }
  for (const auto& [renderer, what] : order) {
    const Values& v = values[{static_cast<int>(renderer), what}];
    AgreementSummary a;
    a.renderer = renderer, a.what = what, a.variants = v.size();
    a.mean = mean(v);
    a.interval = bootstrap_mean_interval(v, kMeanConfidence);
    for (double x : v) {
      a.max = std::max(a.max, x);
      a.above += x > kAgreementThreshold;
    }
    a.sentence = fmt::format(
        "{}{} against the evaluator's: terminator RMSE {:.2f} % [{:.2f}, {:.2f}] of albedo*E/pi "
        "(mean over {} variants, 95 % CI), at most {:.2f} %; {} {} above {:.0f} %.",
        renderer_info(renderer).name,
        what == "ground truth" ? std::string(" ground truth") : ", method " + what + ",",
        100 * a.mean, 100 * a.interval.low, 100 * a.interval.high, a.variants, 100 * a.max, a.above,
        a.above == 1 ? "variant" : "variants", 100 * kAgreementThreshold);
    out.push_back(std::move(a));
  }
  return out;
}

}  // namespace penumbra
