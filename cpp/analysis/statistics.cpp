#include "analysis/statistics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

#include "analysis/mt19937_64_block.h"

namespace penumbra {

std::size_t uniform_index(std::mt19937_64& rng, std::size_t n) {
  const double u = static_cast<double>(rng() >> 11) * 0x1.0p-53;
  return std::min(n - 1, static_cast<std::size_t>(u * static_cast<double>(n)));
}

double quantile(const std::vector<double>& sorted, double q) {
  const double pos = q * static_cast<double>(sorted.size() - 1);
  const std::size_t i = static_cast<std::size_t>(std::floor(pos));
  const std::size_t j = std::min(i + 1, sorted.size() - 1);
  return sorted[i] + (pos - static_cast<double>(i)) * (sorted[j] - sorted[i]);
}

namespace {

// The indices of one resample of n values: uniform_index's arithmetic on
// the generator's next n outputs (below 2^53 and below n, the signed
// conversions give the unsigned ones' values), cloned for AVX-512 and AVX2
// so that the generator's loops run vectorised; integer and exact
// operations only, so every clone gives the same indices.
__attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default"))) void resample_indices(
    Mt19937_64Block& rng, std::uint64_t* bits, std::uint32_t* indices, std::size_t n) {
  rng.fill(bits, n);
  const double scale = static_cast<double>(static_cast<std::int64_t>(n));
  const std::int64_t last = static_cast<std::int64_t>(n) - 1;
  for (std::size_t k = 0; k < n; ++k) {
    const double u = static_cast<double>(static_cast<std::int64_t>(bits[k] >> 11)) * 0x1.0p-53;
    indices[k] = static_cast<std::uint32_t>(std::min(last, static_cast<std::int64_t>(u * scale)));
  }
}

// quantile() of the values sorted, with partial sorts: the two order
// statistics it reads are the same values.
double quantile_unsorted(std::vector<double>& values, double q) {
  const double pos = q * static_cast<double>(values.size() - 1);
  const std::size_t i = static_cast<std::size_t>(std::floor(pos));
  std::nth_element(values.begin(), values.begin() + std::ptrdiff_t(i), values.end());
  const double low = values[i];
  const double high = i + 1 < values.size()
                          ? *std::min_element(values.begin() + std::ptrdiff_t(i) + 1, values.end())
                          : low;
  return low + (pos - static_cast<double>(i)) * (high - low);
}

}  // namespace

Interval bootstrap_mean_interval(const std::vector<double>& values, double confidence,
                                 int resamples, std::uint64_t seed) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (values.empty()) return {nan, nan};
  if (values.size() == 1) return {values[0], values[0]};
  // The draws of std::mt19937_64(seed) through uniform_index, a resample's
  // worth at a time.
  Mt19937_64Block rng(seed);
  const std::size_t n = values.size();
  std::vector<std::uint64_t> bits(n);
  std::vector<std::uint32_t> indices(n);
  std::vector<double> means(static_cast<std::size_t>(resamples));
  for (double& mean : means) {
    resample_indices(rng, bits.data(), indices.data(), n);
    double sum = 0.0;
    for (std::size_t k = 0; k < n; ++k) sum += values[indices[k]];
    mean = sum / static_cast<double>(n);
  }
  const double tail = 0.5 * (1.0 - confidence);
  const double low = quantile_unsorted(means, tail);
  return {low, quantile_unsorted(means, 1.0 - tail)};
}

double sign_test_p(std::size_t positive, std::size_t negative) {
  const std::size_t n = positive + negative;
  if (n == 0) return 1.0;
  const std::size_t k = std::min(positive, negative);
  // P(X <= k) for X ~ Binomial(n, 1/2), in logs so that n in the thousands
  // does not overflow; doubled for two sides.
  double tail = 0.0;
  for (std::size_t i = 0; i <= k; ++i)
    tail += std::exp(std::lgamma(double(n) + 1) - std::lgamma(double(i) + 1) -
                     std::lgamma(double(n - i) + 1) - double(n) * std::log(2.0));
  return std::min(1.0, 2.0 * tail);
}

std::vector<double> holm_adjust(const std::vector<double>& p) {
  std::vector<std::size_t> order(p.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return p[a] < p[b]; });
  std::vector<double> adjusted(p.size());
  double running = 0.0;
  for (std::size_t rank = 0; rank < order.size(); ++rank) {
    const double m = static_cast<double>(p.size() - rank);
    running = std::max(running, std::min(1.0, m * p[order[rank]]));
    adjusted[order[rank]] = running;
  }
  return adjusted;
}

PairedComparison compare_paired(const std::vector<double>& a, const std::vector<double>& b,
                                double confidence, std::uint64_t seed) {
  PairedComparison c;
  std::vector<double> d;
  for (std::size_t v = 0; v < std::min(a.size(), b.size()); ++v) {
    if (!std::isfinite(a[v]) || !std::isfinite(b[v])) continue;
    const double diff = a[v] - b[v];
    d.push_back(diff);
    if (diff < 0)
      ++c.a_better;
    else if (diff > 0)
      ++c.b_better;
    else
      ++c.equal;
  }
  c.n = d.size();
  if (d.empty()) {
    c.mean_difference = std::numeric_limits<double>::quiet_NaN();
    c.interval = {c.mean_difference, c.mean_difference};
    return c;
  }
  c.mean_difference = std::accumulate(d.begin(), d.end(), 0.0) / static_cast<double>(d.size());
  c.interval = bootstrap_mean_interval(d, confidence, 10000, seed);
  c.p = sign_test_p(c.a_better, c.b_better);
  return c;
}

}  // namespace penumbra
