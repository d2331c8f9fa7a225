// Where a pixel's samples lie: stratified on an nx x ny grid, jittered
// within their strata, and nested, so that a render at four times the
// samples holds the samples of the render it checks and can extend its sums
// instead of starting again (issue 45).
#pragma once

#include <cstdint>

namespace penumbra {

// The grid of `spp` strata: nx the largest divisor of spp not above its
// square root, ny = spp / nx (16 -> 4 x 4, 32 -> 4 x 8, 7 -> 1 x 7).
inline void strata(int spp, int* nx, int* ny) {
  int best = 1;
  for (int a = 1; a * a <= spp; ++a)
    if (spp % a == 0) best = a;
  *nx = best;
  *ny = spp / best;
}

// Patterns up to this many samples are plain jittered grids, sample s in
// stratum (s mod nx, s div nx): what every render of 16 samples or fewer
// has always drawn, so that their bits do not change.
constexpr int kPlainPatternSamples = 16;

// Whether the jittered pattern of `spp` samples nests the pattern of spp/4:
// above kPlainPatternSamples, spp a multiple of 4 whose grid is spp/4's
// halved both ways (64 on 16, 32 on 8, 256 on 64; not 72 on 18).
bool nests_quarter(int spp);

// Whether the first `fewer` samples of a `spp`-sample pattern are the
// `fewer`-sample pattern: spp = fewer x 4^k with each step nested.
bool nests(int fewer, int spp);

// How a pattern is drawn: the jitter of sample s is element (2s, 2s + 1)
// of the SplitMix64 sequence of `key` (core/random.h); `shuffle` permutes
// which stratum each sample takes (permute_index, seeded from `seed`), so
// that a pixel's light samples are stratified without following its camera
// samples.
// `nested` false: a plain grid at any count.
struct PatternKeys {
  std::uint64_t key = 0;
  bool shuffle = false;
  std::uint32_t seed = 0;
  bool nested = true;
};

// Sample s's stratum on its pattern's grid and its offset in [0, 1)^2
// within it: the point (sx + x) / nx, (sy + y) / ny of the pixel.
struct StratumPoint {
  int sx = 0, sy = 0;
  double x = 0.5, y = 0.5;
};

// Sample s in [0, spp) of a jittered pattern. Plain grids (no nesting): s
// takes stratum s (or its permuted index) with its jitter. Nested patterns
// (nests_quarter): the first spp/4 samples are the spp/4 pattern's, each
// in one of the four strata its coarse stratum splits into; sample
// spp/4 + c (c permuted when shuffled) takes the (c mod 3)-th stratum left
// free in coarse sample c div 3's block, jittered within it: every stratum
// of the fine grid holds one sample, as progressive jittered sampling
// places them (Christensen, Kensler and Kilpatrick 2018, "Progressive
// multi-jittered sample sequences", Sect. 3). A coarse sample is expressed
// on the fine grid exactly (stratum 2 sx + dx, offset 2 x - dx), so its
// point (sx + x) / nx has the bits it has on the coarse grid.
StratumPoint stratum_point(int s, int spp, const PatternKeys& keys);

}  // namespace penumbra
