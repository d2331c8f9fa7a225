// The nested sample pattern (core/sample_pattern.h): plain grids keep the
// jittered strata every render up to 16 samples has drawn, and a nested
// pattern holds the pattern of a quarter of its samples, to the bit, with
// one sample in every stratum of its own grid.
#include "core/sample_pattern.h"

#include <gtest/gtest.h>

#include <set>
#include <utility>

#include "core/light_sampling.h"
#include "core/random.h"

namespace penumbra {
namespace {

constexpr std::uint64_t kKey = 0x243f6a8885a308d3ull;

PatternKeys keys(bool shuffle) {
  return {kKey, shuffle, 0x13198a2eu};
}

// Where the point lies in the pixel, as the evaluator computes it.
std::pair<double, double> film(const StratumPoint& p, int spp) {
  int nx, ny;
  strata(spp, &nx, &ny);
  return {(p.sx + p.x) / nx, (p.sy + p.y) / ny};
}

TEST(SamplePattern, PlainGridsAreTheJitteredStrataOfEveryEarlierRender) {
  // The formula renders of up to 16 samples used before patterns nested
  // (stratum s, or its permute_index, jittered by SplitMix64 elements 2s
  // and 2s + 1): their bits must not change.
  for (int spp : {1, 2, 4, 7, 8, 16}) {
    int nx, ny;
    strata(spp, &nx, &ny);
    for (bool shuffle : {false, true})
      for (int s = 0; s < spp; ++s) {
        const int stratum =
            shuffle ? int(permute_index(std::uint32_t(s), std::uint32_t(spp), 0x13198a2eu)) : s;
        const StratumPoint p = stratum_point(s, spp, keys(shuffle));
        EXPECT_EQ(p.sx, stratum % nx);
        EXPECT_EQ(p.sy, stratum / nx);
        EXPECT_EQ(p.x, splitmix_double(kKey, 2 * std::uint64_t(s)));
        EXPECT_EQ(p.y, splitmix_double(kKey, 2 * std::uint64_t(s) + 1));
      }
  }
}

TEST(SamplePattern, WhichCountsNest) {
  EXPECT_FALSE(nests_quarter(16));  // plain: the bits of every 16-sample render stay
  EXPECT_TRUE(nests_quarter(64));
  EXPECT_TRUE(nests_quarter(256));
  EXPECT_TRUE(nests_quarter(32));   // 4 x 8 on 2 x 4
  EXPECT_FALSE(nests_quarter(72));  // 8 x 9 is not 3 x 6 halved
  EXPECT_FALSE(nests_quarter(66));
  EXPECT_TRUE(nests(16, 64));
  EXPECT_TRUE(nests(16, 1024));
  EXPECT_TRUE(nests(64, 64));
  EXPECT_FALSE(nests(4, 64));  // 16 is a plain grid: it does not hold 4's
  EXPECT_FALSE(nests(32, 64));
  EXPECT_FALSE(nests(0, 64));
}

TEST(SamplePattern, NestedPatternsHoldTheirQuarterToTheBitAndOneSamplePerStratum) {
  for (int spp : {32, 64, 256, 1024})
    for (bool shuffle : {false, true}) {
      int nx, ny;
      strata(spp, &nx, &ny);
      std::set<std::pair<int, int>> strata_seen;
      for (int s = 0; s < spp; ++s) {
        const StratumPoint p = stratum_point(s, spp, keys(shuffle));
        ASSERT_GE(p.x, 0.0);
        ASSERT_LT(p.x, 1.0);
        ASSERT_GE(p.y, 0.0);
        ASSERT_LT(p.y, 1.0);
        ASSERT_GE(p.sx, 0);
        ASSERT_LT(p.sx, nx);
        ASSERT_GE(p.sy, 0);
        ASSERT_LT(p.sy, ny);
        strata_seen.insert({p.sx, p.sy});
        if (s < spp / 4) {
          // The evaluator's film coordinates, bit for bit.
          const auto fine = film(p, spp);
          const auto coarse = film(stratum_point(s, spp / 4, keys(shuffle)), spp / 4);
          EXPECT_EQ(fine.first, coarse.first) << spp << " " << s;
          EXPECT_EQ(fine.second, coarse.second) << spp << " " << s;
        }
      }
      EXPECT_EQ(strata_seen.size(), std::size_t(spp)) << spp << (shuffle ? " shuffled" : "");
    }
}

TEST(SamplePattern, ShuffledFillDoesNotFollowTheCameraOrder) {
  // The light's pattern takes the free strata in a permuted order, so that
  // sample s's light stratum is not its camera stratum's twin.
  int same = 0;
  for (int s = 16; s < 64; ++s) {
    const StratumPoint a = stratum_point(s, 64, keys(false));
    const StratumPoint b = stratum_point(s, 64, keys(true));
    same += a.sx == b.sx && a.sy == b.sy;
  }
  EXPECT_LT(same, 8);  // of 48; about 1 expected by chance
}

}  // namespace
}  // namespace penumbra
