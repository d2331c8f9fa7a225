#include "analysis/rank_tests.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <random>

namespace penumbra {

double simultaneous_confidence(double family, std::size_t comparisons) {
  return 1.0 - (1.0 - family) / static_cast<double>(std::max<std::size_t>(1, comparisons));
}

namespace {

// compare_paired with more resamples: intervals far in the tails need them
// (at 99.7 % each tail holds about 26 of 20,000 means).
PairedComparison paired(const std::vector<double>& a, const std::vector<double>& b,
                        double confidence, std::uint64_t seed) {
  PairedComparison c = compare_paired(a, b, confidence, seed);
  if (c.n < 2) return c;
  std::vector<double> d;
  for (std::size_t v = 0; v < std::min(a.size(), b.size()); ++v)
    if (std::isfinite(a[v]) && std::isfinite(b[v])) d.push_back(a[v] - b[v]);
  c.interval = bootstrap_mean_interval(d, confidence, kRankResamples, seed);
  return c;
}

}  // namespace

std::vector<RankGroup> rank_groups(const std::vector<std::vector<double>>& values,
                                   double confidence, std::uint64_t seed) {
  std::vector<RankGroup> out(values.size());
  std::vector<char> grouped(values.size(), 0);
  int group = 0;
  for (std::size_t lead = 0; lead < values.size(); ++lead) {
    if (grouped[lead]) continue;
    ++group;
    grouped[lead] = 1;
    out[lead].group = group;
    out[lead].leader = lead;
    for (std::size_t i = lead + 1; i < values.size(); ++i) {
      if (grouped[i]) continue;
      PairedComparison c = paired(values[i], values[lead], confidence, seed);
      if (c.n == 0 || !c.interval.contains(0.0)) continue;
      grouped[i] = 1;
      out[i] = {group, lead, std::move(c)};
    }
  }
  return out;
}

namespace {

// The variance of the level means of `cells` (one row per block, one column
// per level).
double level_mean_variance(const std::vector<std::vector<double>>& cells, std::size_t levels) {
  std::vector<double> means(levels, 0.0);
  for (const std::vector<double>& row : cells)
    for (std::size_t l = 0; l < levels; ++l) means[l] += row[l];
  double mean = 0.0;
  for (double& m : means) mean += (m /= static_cast<double>(cells.size()));
  mean /= static_cast<double>(levels);
  double variance = 0.0;
  for (double m : means) variance += (m - mean) * (m - mean);
  return variance / static_cast<double>(levels);
}

}  // namespace

LevelTest level_permutation_test(const std::vector<double>& y, const std::vector<int>& level,
                                 const std::vector<int>& block, int permutations,
                                 std::uint64_t seed) {
  LevelTest t;
  int levels = 0;
  for (int l : level) levels = std::max(levels, l + 1);
  // block -> its value at each level (NaN: missing or undefined).
  std::map<int, std::vector<double>> rows;
  std::map<int, bool> broken;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 0; i < y.size(); ++i) {
    std::vector<double>& row = rows[block[i]];
    if (row.empty()) row.assign(static_cast<std::size_t>(levels), nan);
    double& cell = row[static_cast<std::size_t>(level[i])];
    if (!std::isnan(cell) || !std::isfinite(y[i])) broken[block[i]] = true;
    cell = y[i];
  }
  std::vector<std::vector<double>> cells;
  for (const auto& [b, row] : rows)
    if (!broken[b] &&
        std::all_of(row.begin(), row.end(), [](double v) { return std::isfinite(v); }))
      cells.push_back(row);
  t.blocks = cells.size();
  if (levels < 2 || cells.size() < 2) return t;
  const std::size_t n = static_cast<std::size_t>(levels);
  t.statistic = level_mean_variance(cells, n);
  std::mt19937_64 rng(seed);
  std::size_t as_large = 0;
  for (int r = 0; r < permutations; ++r) {
    for (std::vector<double>& row : cells)
      for (std::size_t k = n - 1; k > 0; --k) std::swap(row[k], row[uniform_index(rng, k + 1)]);
    // A relative margin, so that a permutation equal to the observed
    // arrangement counts whatever the summation order's rounding.
    as_large += level_mean_variance(cells, n) >= t.statistic * (1.0 - 1e-12);
  }
  t.p = (1.0 + static_cast<double>(as_large)) / (1.0 + static_cast<double>(permutations));
  return t;
}

}  // namespace penumbra
