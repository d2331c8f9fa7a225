#include "study/ranking.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <thread>

#include <fmt/format.h>

#include "util/parallel.h"

namespace penumbra {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Per method label, its two errors in each selected variant (NaN: missing).
struct ErrorTable {
  std::vector<std::size_t> variants;  // plan indices
  std::vector<std::string> methods;   // in order of first appearance
  std::map<std::string, std::vector<double>> term, view, view_bias;
};

ErrorTable error_table(const Plan& plan, const std::vector<ComparisonRow>& rows,
                       const std::string& scene) {
  ErrorTable t;
  std::map<std::size_t, std::size_t> column;
  for (std::size_t v = 0; v < plan.variants.size(); ++v) {
    const Variant& var = plan.variants[v];
    if (var.section != SectionKind::kBump || (!scene.empty() && var.scene != scene)) continue;
    column[v] = t.variants.size();
    t.variants.push_back(v);
  }
  for (const ComparisonRow& row : rows) {
    const auto c = column.find(row.variant);
    if (c == column.end() || row.renderer != RendererKind::kEvaluator ||
        row.reference_renderer != RendererKind::kEvaluator)
      continue;
    if (!t.term.count(row.method)) {
      t.methods.push_back(row.method);
      t.term[row.method].assign(t.variants.size(), kNaN);
      t.view[row.method].assign(t.variants.size(), kNaN);
      t.view_bias[row.method].assign(t.variants.size(), kNaN);
    }
    t.term[row.method][c->second] = row.profile.rmse_terminator;
    t.view[row.method][c->second] = row.view.rmse_grazing;
    t.view_bias[row.method][c->second] = row.view.bias_grazing;
  }
  return t;
}

// x / baseline per variant; NaN where either is undefined or the baseline is 0.
std::vector<double> relative(const std::vector<double>& x, const std::vector<double>& baseline) {
  std::vector<double> r(x.size(), kNaN);
  for (std::size_t v = 0; v < x.size(); ++v)
    if (std::isfinite(x[v]) && std::isfinite(baseline[v]) && baseline[v] > 0.0)
      r[v] = x[v] / baseline[v];
  return r;
}

std::vector<double> finite(const std::vector<double>& x) {
  std::vector<double> out;
  for (double v : x)
    if (std::isfinite(v)) out.push_back(v);
  return out;
}

double mean(const std::vector<double>& x) {
  if (x.empty()) return kNaN;
  double sum = 0.0;
  for (double v : x) sum += v;
  return sum / double(x.size());
}

// 1 - mean(ratio) and its interval (the interval of 1 - mean, flipped).
void improvement(const std::vector<double>& ratio, double* value, Interval* interval) {
  const std::vector<double> r = finite(ratio);
  *value = 1.0 - mean(r);
  const Interval i = bootstrap_mean_interval(r, kRankingConfidence);
  *interval = {1.0 - i.high, 1.0 - i.low};
}

std::string method_rejection(const std::string& label) {
  const std::string id = label.substr(0, label.find('('));
  const auto m = method_from_id(id);
  return m ? std::string(method_info(*m).rejected) : std::string();
}

MethodStatistics method_statistics(const ErrorTable& t, const std::string& m,
                                   const std::vector<double>& combined) {
  MethodStatistics s;
  s.method = m;
  s.rejected = method_rejection(m);
  const std::vector<double> c = finite(combined);
  s.variants = c.size();
  s.combined = mean(c);
  s.combined_interval = bootstrap_mean_interval(c, kRankingConfidence);
  improvement(relative(t.term.at(m), t.term.at("none")), &s.terminator_improvement,
              &s.terminator_interval);
  s.terminator = compare_paired(t.term.at(m), t.term.at("none"), kRankingConfidence);
  s.view = compare_paired(t.view.at(m), t.view.at("none"), kRankingConfidence);
  const std::vector<double> bias = finite(t.view_bias.at(m));
  s.view_bias = mean(bias);
  s.view_bias_interval = bootstrap_mean_interval(bias, kRankingConfidence);
  double darker_sum = 0.0;
  for (double b : bias)
    if (b < 0.0) ++s.view_darker, darker_sum += b;
  s.view_darker_mean = s.view_darker ? darker_sum / double(s.view_darker) : 0.0;
  return s;
}

// Every pair of methods on C, Holm-adjusted as one family.
std::vector<PairStatistics> pair_statistics(
    const std::vector<MethodStatistics>& methods,
    const std::map<std::string, std::vector<double>>& combined) {
  std::vector<PairStatistics> pairs;
  for (std::size_t i = 0; i < methods.size(); ++i)
    for (std::size_t j = i + 1; j < methods.size(); ++j) {
      PairStatistics p;
      p.a = methods[i].method, p.b = methods[j].method;
      pairs.push_back(std::move(p));
    }
  // 190 bootstraps of 10^4 resamples for 20 methods: most of a warm study's
  // report time. Each has its own seed, so the threads do not change them.
  run_parallel(
      static_cast<int>(std::thread::hardware_concurrency()), pairs.size(), [&](std::size_t k) {
        pairs[k].combined =
            compare_paired(combined.at(pairs[k].a), combined.at(pairs[k].b), kRankingConfidence);
      });
  std::vector<double> raw;
  for (const PairStatistics& p : pairs) raw.push_back(p.combined.p);
  const std::vector<double> adjusted = holm_adjust(raw);
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    pairs[k].p_holm = adjusted[k];
    pairs[k].tied = pairs[k].combined.n == 0 || pairs[k].combined.interval.contains(0.0) ||
                    adjusted[k] >= kSignificance;
  }
  return pairs;
}

bool tied(const std::vector<PairStatistics>& pairs, const std::string& a, const std::string& b) {
  for (const PairStatistics& p : pairs)
    if ((p.a == a && p.b == b) || (p.a == b && p.b == a)) return p.tied;
  return true;
}

}  // namespace

RankingStatistics ranking_statistics(const Plan& plan, const std::vector<ComparisonRow>& rows,
                                     const std::string& scene) {
  RankingStatistics s;
  s.scene = scene;
  const ErrorTable t = error_table(plan, rows, scene);
  s.variants = t.variants.size();
  if (!t.term.count("none")) return s;  // no raw bump to measure against
  std::map<std::string, std::vector<double>> combined;
  for (const std::string& m : t.methods) {
    std::vector<double> sum(t.variants.size()), none_sum(t.variants.size());
    for (std::size_t v = 0; v < t.variants.size(); ++v) {
      sum[v] = t.term.at(m)[v] + t.view.at(m)[v];
      none_sum[v] = t.term.at("none")[v] + t.view.at("none")[v];
    }
    combined[m] = relative(sum, none_sum);
    s.methods.push_back(method_statistics(t, m, combined[m]));
  }
  std::sort(s.methods.begin(), s.methods.end(),
            [](const MethodStatistics& a, const MethodStatistics& b) {
              if (std::isnan(a.combined) != std::isnan(b.combined)) return std::isnan(b.combined);
              return a.combined != b.combined ? a.combined < b.combined : a.method < b.method;
            });
  s.pairs = pair_statistics(s.methods, combined);
  for (std::size_t i = 0; i < s.methods.size(); ++i)
    s.methods[i].rank = i > 0 && tied(s.pairs, s.methods[i - 1].method, s.methods[i].method)
                            ? s.methods[i - 1].rank
                            : static_cast<int>(i + 1);
  s.headline = headline_sentences(s);
  return s;
}

namespace {

std::string percent(double fraction) {
  return fmt::format("{:.0f} %", 100.0 * fraction);
}

std::string percent_interval(const Interval& i) {
  return fmt::format("[{:.0f}, {:.0f}]", 100.0 * i.low, 100.0 * i.high);
}

// A method's label, marked when the literature rejects it.
std::string named(const std::string& method, const std::string& rejected) {
  return rejected.empty() ? method : method + " [rejected in the literature]";
}

std::string named(const RankingStatistics& s, const std::string& method) {
  for (const MethodStatistics& m : s.methods)
    if (m.method == method) return named(method, m.rejected);
  return method;
}

std::string p_text(double p) {
  return p < 0.001 ? std::string("p < 0.001") : fmt::format("p = {:.2g}", p);
}

// "M lowers (raises) the terminator error of raw bump by X % [a, b]; better in
// W of N variants (sign test p)".
std::string versus_none(const MethodStatistics& m, std::size_t variants) {
  const bool lowers = m.terminator_improvement >= 0.0;
  const Interval& i = m.terminator_interval;
  const std::string tie = i.contains(0.0) ? "; its interval contains 0: a tie"
                          : m.terminator.p >= kSignificance
                              ? "; the sign test does not confirm it: a tie"
                              : "";
  return fmt::format(
      "{} {} the terminator-region profile RMSE of raw bump by {} {} (95 % CI), better in {} of "
      "{} variants ({}){}.",
      named(m.method, m.rejected), lowers ? "lowers" : "raises",
      percent(std::abs(m.terminator_improvement)),
      percent_interval(lowers ? i : Interval{-i.high, -i.low}), m.terminator.a_better, variants,
      p_text(m.terminator.p), tie);
}

// Which methods are darker than the truth where the viewer looks edge-on.
std::string darker_at_grazing_views(const RankingStatistics& s) {
  std::string list;
  for (const MethodStatistics& m : s.methods)
    if (m.view_darker > 0)
      list += fmt::format("{}{} in {} of {} variants (mean signed error there {:+.2f} %)",
                          list.empty() ? "" : "; ", named(m.method, m.rejected), m.view_darker,
                          m.variants, 100.0 * m.view_darker_mean);
  if (list.empty()) return "";
  const MethodStatistics* none = nullptr;
  for (const MethodStatistics& m : s.methods)
    if (m.method == "none") none = &m;
  return fmt::format(
      "Darker than the displacement ground truth at grazing views (view angle 60-75 deg, lit "
      "head-on; signed errors in % of albedo*E/pi), where raw bump is {:+.2f} % on average: {}.",
      100.0 * (none ? none->view_bias : std::numeric_limits<double>::quiet_NaN()), list);
}

// "M adds error at grazing views: ...", for a method significantly worse
// than raw bump on E_view.
std::string worse_view(const MethodStatistics& m) {
  return fmt::format(
      "{} adds error where the viewer looks at grazing angles: its grazing-view RMSE is {:+.2f} % "
      "[{:+.2f}, {:+.2f}] of albedo*E/pi above raw bump's (worse in {} of {} variants, {}); its "
      "mean signed error there is {:+.2f} % [{:+.2f}, {:+.2f}] ({} than the ground truth){}.",
      named(m.method, m.rejected), 100.0 * m.view.mean_difference, 100.0 * m.view.interval.low,
      100.0 * m.view.interval.high, m.view.b_better, m.view.n, p_text(m.view.p),
      100.0 * m.view_bias, 100.0 * m.view_bias_interval.low, 100.0 * m.view_bias_interval.high,
      m.view_bias < 0.0 ? "darker" : "brighter", m.rejected.empty() ? "" : " (" + m.rejected + ")");
}

}  // namespace

std::vector<std::string> headline_sentences(const RankingStatistics& s) {
  std::vector<std::string> out;
  if (s.methods.empty()) return out;
  const MethodStatistics& best = s.methods.front();
  std::string tied_with;
  for (std::size_t i = 1; i < s.methods.size(); ++i)
    if (s.methods[i].rank == best.rank)
      tied_with += (tied_with.empty() ? "" : ", ") + named(s, s.methods[i].method);
  out.push_back(fmt::format(
      "Closest to the displacement ground truth over {} variants: {} (combined error {} {} of "
      "raw bump's, 95 % CI){}.",
      s.variants, named(best.method, best.rejected), percent(best.combined),
      percent_interval(best.combined_interval),
      tied_with.empty() ? "" : "; tied with " + tied_with + " (paired, Holm-adjusted)"));
  for (const MethodStatistics& m : s.methods)
    if (m.method != "none" && m.rank <= best.rank + 1) out.push_back(versus_none(m, m.variants));
  for (const PairStatistics& p : s.pairs)
    if (p.tied && p.a != "none" && p.b != "none" && p.combined.n > 0 &&
        (p.a == best.method || p.b == best.method))
      out.push_back(
          fmt::format("{} and {} are tied (mean paired difference of the combined error {:+.1f} "
                      "percentage points of raw bump's {}, Holm-adjusted {}).",
                      named(s, p.a), named(s, p.b), 100.0 * p.combined.mean_difference,
                      fmt::format("[{:+.1f}, {:+.1f}]", 100.0 * p.combined.interval.low,
                                  100.0 * p.combined.interval.high),
                      p_text(p.p_holm)));
  for (const MethodStatistics& m : s.methods)
    if (m.view.interval.low > 0.0 && m.view.p < kSignificance) out.push_back(worse_view(m));
  if (std::string darker = darker_at_grazing_views(s); !darker.empty())
    out.push_back(std::move(darker));
  for (const MethodStatistics& m : s.methods)
    if (!m.rejected.empty() && m.rank == best.rank)
      out.push_back(fmt::format("{} is {}; it is ranked for comparison, not recommended.", m.method,
                                m.rejected));
  return out;
}

std::vector<AgreementSummary> agreement_summaries(const std::vector<AgreementRow>& rows) {
  std::vector<AgreementSummary> out;
  std::map<std::pair<int, std::string>, std::vector<double>> values;
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
    const std::vector<double>& v = values[{static_cast<int>(renderer), what}];
    AgreementSummary a;
    a.renderer = renderer, a.what = what, a.variants = v.size();
    a.mean = mean(v);
    a.interval = bootstrap_mean_interval(v, kRankingConfidence);
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
