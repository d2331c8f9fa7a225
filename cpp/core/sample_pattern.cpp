#include "core/sample_pattern.h"

#include <array>
#include <cstddef>

#include "core/light_sampling.h"
#include "core/random.h"

namespace penumbra {

bool nests_quarter(int spp) {
  if (spp <= kPlainPatternSamples || spp % 4 != 0) return false;
  int nx, ny, coarse_nx, coarse_ny;
  strata(spp, &nx, &ny);
  strata(spp / 4, &coarse_nx, &coarse_ny);
  return nx == 2 * coarse_nx && ny == 2 * coarse_ny;
}

bool nests(int fewer, int spp) {
  if (fewer <= 0 || fewer > spp) return false;
  while (spp > fewer) {
    if (!nests_quarter(spp)) return false;
    spp /= 4;
  }
  return spp == fewer;
}

namespace {

// strata() and nests_quarter() of a count, remembered per thread: a render
// asks for the same few counts (spp, spp/4, ...) at every sample, and
// computing them again cost a third of a 1024-sample truth's time.
struct Level {
  int spp = 0, nx = 1, ny = 1;
  bool nests = false;
};

Level level_of(int spp) {
  thread_local std::array<Level, 8> known{};
  thread_local std::size_t next = 0;
  for (const Level& l : known)
    if (l.spp == spp) return l;
  Level& l = known[next++ % known.size()];
  l.spp = spp;
  strata(spp, &l.nx, &l.ny);
  l.nests = nests_quarter(spp);
  return l;
}

StratumPoint jittered(int stratum_x, int stratum_y, int s, const PatternKeys& keys) {
  const auto n = 2 * static_cast<std::uint64_t>(s);
  return {stratum_x, stratum_y, splitmix_double(keys.key, n), splitmix_double(keys.key, n + 1)};
}

// A coarse point on the grid twice as fine: exact (binary scaling and a
// subtraction of 1 from a number in [1, 2) round nothing).
StratumPoint finer(const StratumPoint& p) {
  const int dx = p.x >= 0.5 ? 1 : 0, dy = p.y >= 0.5 ? 1 : 0;
  return {2 * p.sx + dx, 2 * p.sy + dy, 2.0 * p.x - dx, 2.0 * p.y - dy};
}

}  // namespace

StratumPoint stratum_point(int s, int spp, const PatternKeys& keys) {
  const Level level = level_of(spp);
  const int nx = level.nx;
  if (!keys.nested || !level.nests) {
    const int stratum =
        keys.shuffle
            ? static_cast<int>(permute_index(std::uint32_t(s), std::uint32_t(spp), keys.seed))
            : s;
    return jittered(stratum % nx, stratum / nx, s, keys);
  }
  const int quarter = spp / 4;
  if (s < quarter) return finer(stratum_point(s, quarter, keys));
  const auto fill = static_cast<std::uint32_t>(s - quarter);
  // Each level's fill-in shuffled by its own permutation.
  const std::uint32_t level_seed =
      static_cast<std::uint32_t>(mix64(std::uint64_t(keys.seed) ^ std::uint64_t(spp)) >> 32u);
  const int c =
      keys.shuffle ? static_cast<int>(permute_index(fill, std::uint32_t(spp - quarter), level_seed))
                   : static_cast<int>(fill);
  const StratumPoint coarse = finer(stratum_point(c / 3, quarter, keys));
  const int block_x = coarse.sx & ~1, block_y = coarse.sy & ~1;
  const int taken = (coarse.sx - block_x) + 2 * (coarse.sy - block_y);
  int child = c % 3;
  if (child >= taken) ++child;  // the k-th of the three strata the coarse sample left free
  return jittered(block_x + child % 2, block_y + child / 2, s, keys);
}

}  // namespace penumbra
