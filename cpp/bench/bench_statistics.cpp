// The rankings' bootstrap (analysis/statistics.h): one 95 % interval of a
// mean over n values from 10,000 resamples, as a study's report draws some
// 1,500 of them, against the form it replaced (std::mt19937_64 one draw at
// a time, every mean sorted), which gives the same bits; and the two
// generators alone, per number drawn. One thread.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "analysis/mt19937_64_block.h"
#include "analysis/statistics.h"

namespace {

std::vector<double> skewed_values(std::size_t n) {
  std::mt19937_64 rng(11);
  std::lognormal_distribution<double> skewed(0.0, 1.0);
  std::vector<double> x(n);
  for (double& v : x) v = skewed(rng);
  return x;
}

penumbra::Interval sorted_bootstrap(const std::vector<double>& values, int resamples) {
  std::mt19937_64 rng(1);
  std::vector<double> means;
  for (int r = 0; r < resamples; ++r) {
    double sum = 0.0;
    for (std::size_t k = 0; k < values.size(); ++k)
      sum += values[penumbra::uniform_index(rng, values.size())];
    means.push_back(sum / double(values.size()));
  }
  std::sort(means.begin(), means.end());
  return {penumbra::quantile(means, 0.025), penumbra::quantile(means, 0.975)};
}

void bm_bootstrap(benchmark::State& state) {
  const std::vector<double> x = skewed_values(std::size_t(state.range(0)));
  for (auto _ : state)
    benchmark::DoNotOptimize(penumbra::bootstrap_mean_interval(x, 0.95, 10000, 1));
  state.SetItemsProcessed(state.iterations() * 10000 * state.range(0));
}

void bm_bootstrap_one_draw_at_a_time(benchmark::State& state) {
  const std::vector<double> x = skewed_values(std::size_t(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(sorted_bootstrap(x, 10000));
  state.SetItemsProcessed(state.iterations() * 10000 * state.range(0));
}

void bm_block_generator(benchmark::State& state) {
  penumbra::Mt19937_64Block rng(1);
  std::vector<std::uint64_t> out(48);
  for (auto _ : state) {
    rng.fill(out.data(), out.size());
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(out.size()));
}

void bm_standard_generator(benchmark::State& state) {
  std::mt19937_64 rng(1);
  std::vector<std::uint64_t> out(48);
  for (auto _ : state) {
    for (std::uint64_t& v : out) v = rng();
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(out.size()));
}

}  // namespace

BENCHMARK(bm_bootstrap)->Arg(12)->Arg(48)->Arg(96)->Unit(benchmark::kMillisecond);
BENCHMARK(bm_bootstrap_one_draw_at_a_time)
    ->Arg(12)
    ->Arg(48)
    ->Arg(96)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(bm_block_generator);
BENCHMARK(bm_standard_generator);
BENCHMARK_MAIN();
