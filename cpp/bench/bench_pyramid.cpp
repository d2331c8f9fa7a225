// Schilling's bump and roughness pyramids: offsets from a height map and
// the whole pyramid, for square maps of 512 to 4096 texels a side (one
// thread). Peak memory of the command that writes them: `penumbra pyramid`
// prints it.
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "core/bump_pyramid.h"
#include "core/random.h"

namespace {

std::vector<float> noise_heights(int size) {
  std::vector<float> heights(std::size_t(size) * size);
  penumbra::Pcg32 rng(7);
  for (float& h : heights) h = float(rng.next_double());
  return heights;
}

void bm_offsets(benchmark::State& state) {
  const int size = int(state.range(0));
  const std::vector<float> heights = noise_heights(size);
  for (auto _ : state)
    benchmark::DoNotOptimize(penumbra::offsets_from_heights(heights, size, size, 1.0 / size, 0.01,
                                                            penumbra::MapEdge::kWrap));
  state.SetItemsProcessed(state.iterations() * std::int64_t(size) * size);
}

void bm_pyramid(benchmark::State& state) {
  const int size = int(state.range(0));
  const std::vector<float> heights = noise_heights(size);
  for (auto _ : state)
    benchmark::DoNotOptimize(penumbra::build_bump_pyramid(penumbra::offsets_from_heights(
        heights, size, size, 1.0 / size, 0.01, penumbra::MapEdge::kWrap)));
  state.SetItemsProcessed(state.iterations() * std::int64_t(size) * size);
}

}  // namespace

BENCHMARK(bm_offsets)->Arg(512)->Arg(4096)->Unit(benchmark::kMillisecond);
BENCHMARK(bm_pyramid)->Arg(512)->Arg(1024)->Arg(4096)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
