// Statistics for comparing methods across a study's variants: paired
// differences, a percentile bootstrap interval of their mean, the exact sign
// test, and Holm's correction for a family of tests. Deterministic: the
// bootstrap draws from a fixed seed, so the same inputs give the same bits.
#pragma once

#include <cstddef>
#include <cstdint>
#include <random>
#include <vector>

namespace penumbra {

struct Interval {
  double low = 0.0, high = 0.0;
  bool contains(double x) const { return low <= x && x <= high; }
};

// Percentile bootstrap interval of the mean of `values` at `confidence`
// (e.g. 0.95): `resamples` resamples with replacement, drawn from `seed`.
// One value (or none) gives the degenerate interval [v, v] (or [NaN, NaN]).
Interval bootstrap_mean_interval(const std::vector<double>& values, double confidence = 0.95,
                                 int resamples = 10000, std::uint64_t seed = 1);

// A uniform index in [0, n) from 53 random bits (the bias is far below what
// a 10^4-resample bootstrap resolves). Written out because
// std::uniform_int_distribution differs between standard libraries, and the
// same seed must give the same bits everywhere.
std::size_t uniform_index(std::mt19937_64& rng, std::size_t n);

// The q-quantile (q in [0, 1]) of ascending `sorted` values, linear between
// order statistics; `sorted` must not be empty.
double quantile(const std::vector<double>& sorted, double q);

// Exact two-sided sign test of "positive and negative equally likely" for
// `positive` and `negative` counts (zeros dropped before): the probability of
// a split at least as uneven under Binomial(n, 1/2). 1 when n = 0.
double sign_test_p(std::size_t positive, std::size_t negative);

// Holm-Bonferroni adjusted p-values, in the order given (each at most 1).
std::vector<double> holm_adjust(const std::vector<double>& p);

// A paired comparison of two methods over the same variants: differences
// d_v = a_v - b_v of an error metric (negative: a is better).
struct PairedComparison {
  std::size_t n = 0;  // pairs with both values defined
  std::size_t a_better = 0, b_better = 0, equal = 0;
  double mean_difference = 0.0;  // mean of d_v
  Interval interval;             // bootstrap interval of that mean
  double p = 1.0;                // sign test, two-sided
};

// Pairs where either value is NaN are left out.
PairedComparison compare_paired(const std::vector<double>& a, const std::vector<double>& b,
                                double confidence = 0.95, std::uint64_t seed = 1);

}  // namespace penumbra
