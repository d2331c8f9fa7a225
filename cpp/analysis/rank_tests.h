// The decisions a ranking makes from per-variant errors: which methods are
// separated (rank groups from paired intervals) and whether a method's
// effect depends on the level of a study axis (a permutation test within
// matched variants). Deterministic: fixed seeds, the same bits every run.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "analysis/statistics.h"

namespace penumbra {

// The confidence of each of `comparisons` intervals so that all hold
// together at `family` (Bonferroni): 1 - (1 - family) / comparisons.
double simultaneous_confidence(double family, std::size_t comparisons);

// Rank groups, the one rule every ranking in a report follows. `values[i]`
// holds item i's error per variant (lower is better; the same variants for
// every item, NaN where undefined), the items in ascending order of their
// mean. The best item not yet grouped leads the next group; the group is
// the leader and every later ungrouped item whose paired difference from
// the leader (item - leader) has an interval at `confidence` that contains
// 0. Groups are numbered 1, 2, ... in that order.
inline constexpr int kRankResamples = 20000;
struct RankGroup {
  int group = 0;
  std::size_t leader = 0;          // index of the group's leader
  PairedComparison versus_leader;  // item - leader (n = 0 for the leader itself)
};
std::vector<RankGroup> rank_groups(const std::vector<std::vector<double>>& values,
                                   double confidence, std::uint64_t seed = 1);

// Does the mean of y depend on the level? A permutation test with levels
// exchanged within blocks (matched observations: the variants that differ
// only in this level). Statistic: the variance of the level means over the
// blocks that hold every level once; p = (1 + #{T* >= T}) / (1 + R) over R
// permutations drawn from `seed`. NaN observations drop their block. 1 when
// fewer than two complete blocks or fewer than two levels remain.
struct LevelTest {
  double statistic = 0.0;
  double p = 1.0;
  std::size_t blocks = 0;  // complete blocks used
};
LevelTest level_permutation_test(const std::vector<double>& y, const std::vector<int>& level,
                                 const std::vector<int>& block, int permutations = 9999,
                                 std::uint64_t seed = 1);

}  // namespace penumbra
