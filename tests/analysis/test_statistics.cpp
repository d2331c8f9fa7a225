// The statistics behind rankings, on inputs whose answers are known exactly.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

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
