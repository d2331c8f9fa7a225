// ns per evaluation of every terminator factor, and of every method through
// shade() (what a camera sample pays: adjustment, factor and lobes, or the
// microfacet model), over a fixed pool of random configurations (so branch
// prediction sees realistic variety).
#include <benchmark/benchmark.h>

#include <vector>

#include "core/random.h"
#include "core/shading.h"
#include "core/terminator.h"

namespace {

using penumbra::ShadingVectors;
using penumbra::Vec3;

const std::vector<ShadingVectors>& pool() {
  static const std::vector<ShadingVectors> vectors = [] {
    std::vector<ShadingVectors> out;
    penumbra::Pcg32 rng(42);
    auto hemisphere = [&](double max_cos_deviation) {
      const double z = max_cos_deviation + (1.0 - max_cos_deviation) * rng.next_double();
      const double phi = 2.0 * penumbra::kPi * rng.next_double();
      const double r = std::sqrt(1.0 - z * z);
      return Vec3{r * std::cos(phi), r * std::sin(phi), z};
    };
    for (int i = 0; i < 4096; ++i)
      out.push_back({{0, 0, 1}, hemisphere(0.5), hemisphere(0.0), hemisphere(0.0)});
    return out;
  }();
  return vectors;
}

void bm_factor(benchmark::State& state, penumbra::TerminatorMethod method) {
  const auto& vectors = pool();
  penumbra::MethodSettings settings{method, 0.5, nullptr, nullptr, {}};
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(penumbra::terminator_factor(settings, vectors[i]));
    i = (i + 1) & 4095;
  }
}

// A Lambertian base with a GGX lobe, so that the glossy-only adjustments
// pay for their work too.
void bm_shade(benchmark::State& state, penumbra::TerminatorMethod method) {
  const auto& vectors = pool();
  penumbra::TerminatorSettings settings;
  settings.method = {method, 0.5, nullptr};
  settings.lobes = penumbra::Lobes::kAll;
  penumbra::Material material;
  material.specular_weight = 0.4;
  penumbra::Pcg32 rng(7);
  std::size_t i = 0;
  for (auto _ : state) {
    const ShadingVectors& v = vectors[i];
    benchmark::DoNotOptimize(
        penumbra::shade(settings, material, {v.ng, v.ng, v.ns, v.wi, v.wo}, &rng).value);
    i = (i + 1) & 4095;
  }
}

const int registered = [] {
  for (const auto& info : penumbra::all_methods()) {
    if (info.user_defined) continue;  // no function in a benchmark binary
    if (info.kind == penumbra::MethodKind::kFactor)
      benchmark::RegisterBenchmark(("factor/" + std::string(info.id)).c_str(), bm_factor,
                                   info.method);
    benchmark::RegisterBenchmark(("shade/" + std::string(info.id)).c_str(), bm_shade, info.method);
  }
  return 0;
}();

}  // namespace

BENCHMARK_MAIN();
