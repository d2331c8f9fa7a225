// The statistics behind rankings, on inputs whose answers are known exactly.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "analysis/mt19937_64_block.h"
#include "analysis/statistics.h"

namespace penumbra {
namespace {

TEST(SignTest, ExactBinomialTails) {
  EXPECT_DOUBLE_EQ(sign_test_p(10, 0), 2.0 / 1024.0);
  EXPECT_NEAR(sign_test_p(8, 2), 2.0 * (1 + 10 + 45) / 1024.0, 1e-12);
  EXPECT_NEAR(sign_test_p(2, 8), sign_test_p(8, 2), 1e-15);
  EXPECT_DOUBLE_EQ(sign_test_p(5, 5), 1.0);  // capped: both tails overlap
  EXPECT_DOUBLE_EQ(sign_test_p(0, 0), 1.0);
  EXPECT_GT(sign_test_p(3000, 2900), 0.0);  // large n in logs, no overflow
}

TEST(Holm, AdjustsInRankOrderAndStaysMonotone) {
  const std::vector<double> adjusted = holm_adjust({0.01, 0.04, 0.03});
  EXPECT_NEAR(adjusted[0], 0.03, 1e-15);  // 3 x 0.01
  EXPECT_NEAR(adjusted[2], 0.06, 1e-15);  // 2 x 0.03
  EXPECT_NEAR(adjusted[1], 0.06, 1e-15);  // max(1 x 0.04, 0.06)
  EXPECT_EQ(holm_adjust({0.9, 0.8})[0], 1.0);
}

TEST(Bootstrap, DegenerateDataGiveDegenerateIntervalsAndTheSameBitsEveryTime) {
  const Interval c = bootstrap_mean_interval({0.3, 0.3, 0.3, 0.3});
  EXPECT_DOUBLE_EQ(c.low, 0.3);
  EXPECT_DOUBLE_EQ(c.high, 0.3);
  const std::vector<double> x{1, 2, 3, 4, 5, 6, 7, 8};
  const Interval a = bootstrap_mean_interval(x), b = bootstrap_mean_interval(x);
  EXPECT_EQ(a.low, b.low);
  EXPECT_EQ(a.high, b.high);
  EXPECT_TRUE(a.contains(4.5));
  EXPECT_TRUE(std::isnan(bootstrap_mean_interval({}).low));
}

TEST(Mt19937_64Block, GivesTheStandardEnginesSequence) {
  // Chunks that end before, at and after each 312-word refill.
  const std::vector<std::size_t> chunks{1, 7, 304, 312, 313, 1, 311, 624, 2, 1000};
  for (std::uint64_t seed : {0ull, 1ull, 5489ull, 0xffffffffffffffffull}) {
    std::mt19937_64 standard(seed);
    Mt19937_64Block block(seed);
    std::size_t drawn = 0;
    for (std::size_t n : chunks) {
      std::vector<std::uint64_t> out(n);
      block.fill(out.data(), n);
      for (std::size_t k = 0; k < n; ++k, ++drawn)
        ASSERT_EQ(out[k], standard()) << "seed " << seed << ", output " << drawn;
    }
  }
  // The standard's own check: the 10000th output of the default seed.
  Mt19937_64Block block(5489);
  std::vector<std::uint64_t> out(10000);
  block.fill(out.data(), out.size());
  EXPECT_EQ(out.back(), 9981545732273789042ull);
}

// The interval as first written: std::mt19937_64, one uniform_index per
// draw, all the means sorted. The block generator and partial sorts must
// give its bits.
Interval sorted_bootstrap(const std::vector<double>& values, double confidence, int resamples,
                          std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<double> means;
  for (int r = 0; r < resamples; ++r) {
    double sum = 0.0;
    for (std::size_t k = 0; k < values.size(); ++k)
      sum += values[uniform_index(rng, values.size())];
    means.push_back(sum / double(values.size()));
  }
  std::sort(means.begin(), means.end());
  const double tail = 0.5 * (1.0 - confidence);
  return {quantile(means, tail), quantile(means, 1.0 - tail)};
}

TEST(Bootstrap, GivesTheBitsOfTheOneDrawAtATimeSortedForm) {
  std::mt19937_64 data(11);
  std::lognormal_distribution<double> skewed(0.0, 1.0);
  for (std::size_t n : {2u, 3u, 12u, 48u, 311u, 313u, 1000u})
    for (int resamples : {1, 2, 999, 10000})
      for (double confidence : {0.95, 0.5})
        for (std::uint64_t seed : {1ull, 42ull}) {
          std::vector<double> x(n);
          for (double& v : x) v = skewed(data) - 1.0;
          const Interval want = sorted_bootstrap(x, confidence, resamples, seed);
          const Interval got = bootstrap_mean_interval(x, confidence, resamples, seed);
          EXPECT_EQ(got.low, want.low) << n << " values, " << resamples << " resamples";
          EXPECT_EQ(got.high, want.high) << n << " values, " << resamples << " resamples";
        }
}

// For normal data the 95 % interval of the mean is about 2 x 1.96 sigma /
// sqrt(n) wide: check the width against that within 15 % at n = 400.
TEST(Bootstrap, WidthFollowsTheStandardErrorOfTheMean) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> x(400);
  for (double& v : x) v = normal(rng);
  double mean = 0.0, var = 0.0;
  for (double v : x) mean += v / double(x.size());
  for (double v : x) var += (v - mean) * (v - mean) / double(x.size() - 1);
  const Interval i = bootstrap_mean_interval(x);
  const double expected = 2.0 * 1.96 * std::sqrt(var / double(x.size()));
  EXPECT_NEAR(i.high - i.low, expected, 0.15 * expected);
  EXPECT_TRUE(i.contains(mean));
}

TEST(PairedComparison, ClearWinnerAndExactTie) {
  const std::vector<double> a{0.10, 0.20, 0.15, 0.30, 0.12, 0.18, 0.22, 0.25};
  std::vector<double> b = a;
  for (double& v : b) v += 0.05;
  const PairedComparison win = compare_paired(a, b);
  EXPECT_EQ(win.a_better, a.size());
  EXPECT_NEAR(win.mean_difference, -0.05, 1e-12);
  EXPECT_LT(win.interval.high, 0.0);
  EXPECT_DOUBLE_EQ(win.p, 2.0 / 256.0);
  const PairedComparison tie = compare_paired(a, a);
  EXPECT_EQ(tie.equal, a.size());
  EXPECT_TRUE(tie.interval.contains(0.0));
  EXPECT_DOUBLE_EQ(tie.p, 1.0);
  std::vector<double> gap = a;
  gap[2] = std::nan("");
  EXPECT_EQ(compare_paired(gap, b).n, a.size() - 1);  // undefined pairs are left out
}

}  // namespace
}  // namespace penumbra
