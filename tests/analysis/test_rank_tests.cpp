// The one ranking rule and the interaction test, on inputs whose answers
// are known: exact ties, clear separations, a chain of overlapping groups,
// and levels that do or do not change a method's error.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "analysis/rank_tests.h"

namespace penumbra {
namespace {

// n values around `mean`, with deterministic spread `sd` (alternating signs).
std::vector<double> around(double mean, double sd, std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sd);
  std::vector<double> out;
  for (std::size_t i = 0; i < n; ++i) out.push_back(mean + noise(rng));
  return out;
}

TEST(RankGroups, TiesShareTheLeadersGroupAndSeparatedItemsStartTheNext) {
  const std::vector<double> a = around(0.5, 0.05, 40, 1);
  std::vector<double> twin = a;  // exactly a: a difference of 0 in every variant
  std::vector<double> close = a, far = a;
  for (std::size_t v = 0; v < a.size(); ++v) {
    close[v] += v % 2 ? 0.01 : -0.01;  // mean difference 0, both signs
    far[v] += 0.3;                     // worse in every variant
  }
  const std::vector<RankGroup> g = rank_groups({a, twin, close, far}, 0.99);
  EXPECT_EQ(g[0].group, 1);
  EXPECT_EQ(g[1].group, 1);
  EXPECT_EQ(g[2].group, 1);
  EXPECT_EQ(g[3].group, 2);
  EXPECT_EQ(g[3].leader, 3u);  // it leads its own group
  EXPECT_EQ(g[2].leader, 0u);
  EXPECT_TRUE(g[2].versus_leader.interval.contains(0.0));
  EXPECT_EQ(g[0].versus_leader.n, 0u);  // the leader is not compared with itself
}

TEST(RankGroups, AChainIsCutAtTheLeaderNotAtTheNeighbour) {
  // b is within noise of a, c within noise of b but clearly above a: c starts
  // group 2 (led by c), though it overlaps b, because groups are decided
  // against their leader.
  const std::size_t n = 60;
  std::vector<double> a(n), b(n), c(n);
  for (std::size_t v = 0; v < n; ++v) {
    const double noise = v % 2 ? 0.02 : -0.02;
    a[v] = 1.0;
    b[v] = 1.0 + 0.004 + noise;       // mean +0.004, spread 0.02: tied with a
    c[v] = 1.0 + 0.03 + 0.2 * noise;  // +0.03 in every variant: separated from a
  }
  const std::vector<RankGroup> g = rank_groups({a, b, c}, 0.99);
  EXPECT_EQ(g[1].group, 1);
  EXPECT_EQ(g[2].group, 2);
  EXPECT_EQ(g[2].leader, 2u);
}

TEST(RankGroups, UndefinedValuesAreLeftOutAndTheSameBitsComeBack) {
  const std::vector<double> a = around(0.4, 0.02, 30, 3);
  std::vector<double> b = a;
  for (std::size_t v = 0; v < b.size(); ++v) b[v] += v % 2 ? 0.003 : -0.003;
  b[5] = std::nan("");
  const std::vector<RankGroup> g1 = rank_groups({a, b}, 0.975), g2 = rank_groups({a, b}, 0.975);
  EXPECT_EQ(g1[1].group, 1);
  EXPECT_EQ(g1[1].versus_leader.n, 29u);
  EXPECT_EQ(g1[1].versus_leader.interval.low, g2[1].versus_leader.interval.low);
  EXPECT_EQ(g1[1].versus_leader.interval.high, g2[1].versus_leader.interval.high);
}

TEST(SimultaneousConfidence, BonferroniOverTheComparisons) {
  EXPECT_DOUBLE_EQ(simultaneous_confidence(0.95, 19), 1.0 - 0.05 / 19);
  EXPECT_DOUBLE_EQ(simultaneous_confidence(0.95, 1), 0.95);
  EXPECT_DOUBLE_EQ(simultaneous_confidence(0.95, 0), 0.95);
}

// Blocks of three levels; y = block offset + effect(level) + noise.
struct Design {
  std::vector<double> y;
  std::vector<int> level, block;
};
Design design(double effect, std::size_t blocks, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.05);
  Design d;
  for (std::size_t b = 0; b < blocks; ++b)
    for (int l = 0; l < 3; ++l) {
      d.y.push_back(10.0 * double(b) + effect * l + noise(rng));  // blocks differ wildly
      d.level.push_back(l);
      d.block.push_back(static_cast<int>(b));
    }
  return d;
}

TEST(LevelPermutationTest, AStrongEffectGivesTheSmallestPAndNoEffectDoesNot) {
  const Design strong = design(0.5, 12, 7);
  const LevelTest t = level_permutation_test(strong.y, strong.level, strong.block, 999);
  EXPECT_EQ(t.blocks, 12u);
  EXPECT_DOUBLE_EQ(t.p, 1.0 / 1000.0);  // no permutation is as extreme
  // Without an effect, p is uniform; over 40 seeds about 5 % fall below 0.05.
  int below = 0;
  for (unsigned s = 0; s < 40; ++s) {
    const Design none = design(0.0, 12, 100 + s);
    below += level_permutation_test(none.y, none.level, none.block, 199).p < 0.05;
  }
  EXPECT_LE(below, 6);  // Binomial(40, 0.05): P(X > 6) < 0.01
}

TEST(LevelPermutationTest, BlockOffsetsDoNotMatterAndIncompleteBlocksAreDropped) {
  Design d = design(0.1, 8, 11);
  const LevelTest base = level_permutation_test(d.y, d.level, d.block, 499);
  Design shifted = d;
  for (std::size_t i = 0; i < d.y.size(); ++i) shifted.y[i] += 1000.0 * d.block[i];
  const LevelTest moved = level_permutation_test(shifted.y, shifted.level, shifted.block, 499);
  EXPECT_NEAR(moved.statistic, base.statistic, 1e-6);
  EXPECT_EQ(moved.p, base.p);
  d.y[4] = std::nan("");  // block 1 loses a level
  EXPECT_EQ(level_permutation_test(d.y, d.level, d.block, 99).blocks, 7u);
  EXPECT_EQ(level_permutation_test({1.0, 2.0}, {0, 1}, {0, 0}, 99).p, 1.0);  // one block
}

}  // namespace
}  // namespace penumbra
