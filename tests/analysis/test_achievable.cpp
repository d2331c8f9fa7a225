// The achievable floor on synthetic tallies whose answer is known: a truth
// that is raw bump times a known G is recovered, G's bounds hold, and no
// other table beats the floor on the variants it was fitted to.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <vector>

#include "analysis/achievable.h"

namespace penumbra {
namespace {

// light [60, 100) x deviation [0, 30) degrees in 10-degree cells: 4 x 3.
FactorGrid small_grid() {
  FactorGrid g;
  g.axes = {{FactorInput::kLight, 60.0, 100.0, 10.0}, {FactorInput::kDeviation, 0.0, 30.0, 10.0}};
  return g;
}

// A variant with 180 one-degree bins, all empty.
TallyVariant empty_variant() {
  TallyVariant v;
  v.tally.bin_degrees = v.truth.bin_degrees = 1.0;
  v.tally.count.assign(180, 0);
  v.tally.rest.assign(180, 0.0);
  v.tally.scaled.assign(180, {});
  v.truth.count.assign(180, 0);
  v.truth.value.assign(180, 0.0);
  return v;
}

// A variant whose bins 60..99 each hold 50 pixels of raw bump's light,
// spread over the cells at random; its truth is that light times `g_true`.
TallyVariant synthetic(const FactorGrid& grid, const std::vector<double>& g_true, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  TallyVariant v = empty_variant();
  v.id = "v" + std::to_string(seed);
  for (int b = 60; b < 100; ++b) {
    const std::size_t bin = static_cast<std::size_t>(b);
    v.tally.count[bin] = v.truth.count[bin] = 50;
    v.tally.rest[bin] = 5.0 * u(rng);  // light no factor scales (another lobe)
    double truth = v.tally.rest[bin];
    for (int c = 0; c < grid.cells(); ++c) {
      if (u(rng) < 0.3) continue;  // not every cell lights every bin
      const double light = 10.0 * u(rng) * std::cos(radians(double(b)));
      v.tally.scaled[bin].push_back({c, light});
      truth += light * g_true[static_cast<std::size_t>(c)];
    }
    v.truth.value[bin] = truth / 50.0;
  }
  return v;
}

std::vector<double> known_g() {
  return {1.0, 0.9, 0.7, 0.8, 0.6, 0.4, 0.5, 0.3, 0.2, 0.1, 0.05, 0.0};
}

TEST(Floor, RecoversTheFactorThatMadeTheTruthAndReachesZero) {
  const FactorGrid grid = small_grid();
  std::vector<TallyVariant> variants;
  for (unsigned s = 1; s <= 6; ++s) variants.push_back(synthetic(grid, known_g(), s));
  const FloorSolution f = solve_floor(grid, variants);
  ASSERT_EQ(f.g.size(), 12u);
  // 6 x 40 equations in 12 unknowns, consistent: G is recovered to the
  // solver's rounding, and every variant's error is 0 to that rounding.
  for (std::size_t c = 0; c < f.g.size(); ++c) EXPECT_NEAR(f.g[c], known_g()[c], 1e-8) << c;
  for (double e : f.variant_rmse) EXPECT_LT(e, 1e-9);
  EXPECT_LT(f.kkt_residual, 1e-10);
}

TEST(Floor, BoundsHoldAndNoOtherTableBeatsTheFloor) {
  const FactorGrid grid = small_grid();
  // The truth wants G = 3 in one cell and -0.5 in another: outside [0, 2].
  std::vector<double> g_true = known_g();
  g_true[0] = 3.0, g_true[11] = -0.5;
  std::vector<TallyVariant> variants;
  for (unsigned s = 10; s < 14; ++s) variants.push_back(synthetic(grid, g_true, s));
  const FloorSolution f = solve_floor(grid, variants);
  EXPECT_DOUBLE_EQ(f.g[0], 2.0);
  EXPECT_DOUBLE_EQ(f.g[11], 0.0);
  EXPECT_GT(f.objective, 0.0);
  EXPECT_LT(f.kkt_residual, 1e-10);
  // 200 random tables in the bounds, and the floor's own cells nudged by
  // 1e-3: none has a lower mean squared error.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 2.0);
  for (int k = 0; k < 200; ++k) {
    std::vector<double> g(12);
    for (double& x : g)
      x = k < 100 ? u(rng) : std::clamp(f.g[&x - g.data()] + 1e-3 * (u(rng) - 1.0), 0.0, 2.0);
    double mse = 0.0;
    for (const TallyVariant& v : variants) mse += std::pow(tally_rmse(v, g), 2) / 4.0;
    EXPECT_GE(mse, f.objective * (1.0 - 1e-12)) << k;
  }
}

TEST(Floor, CellsNoVariantLightsStayRawBumpWithoutAPriorAndFollowTheirNeighboursWithOne) {
  const FactorGrid grid = small_grid();
  std::vector<TallyVariant> variants{synthetic(grid, known_g(), 21)};
  for (auto& bin : variants[0].tally.scaled)  // nobody lights cell 5
    bin.erase(std::remove_if(bin.begin(), bin.end(), [](const auto& e) { return e.first == 5; }),
              bin.end());
  const FloorSolution plain = solve_floor(grid, variants);
  EXPECT_FALSE(plain.constrained[5]);
  EXPECT_EQ(plain.g[5], 1.0);
  FloorOptions smooth;
  smooth.smoothness = 1e-3;
  const FloorSolution prior = solve_floor(grid, variants, smooth);
  // Its neighbours along the light axis (cells 4 and 6) pull it between them.
  EXPECT_GT(prior.g[5], std::min(prior.g[4], prior.g[6]) - 0.05);
  EXPECT_LT(prior.g[5], std::max(prior.g[4], prior.g[6]) + 0.05);
}

// A smoothed solve with more variables than FloorOptions::dense_variables
// works on a sparse h; forced dense, the same problem reaches the same G
// (both exact on their active set, so to the factorisations' rounding).
TEST(Floor, SparseAndDenseSmoothedSolvesReachTheSameTable) {
  FactorGrid grid;  // 40 x 30 = 1200 cells
  grid.axes = {{FactorInput::kLight, 60.0, 100.0, 1.0}, {FactorInput::kDeviation, 0.0, 30.0, 1.0}};
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<TallyVariant> variants(6, empty_variant());
  for (TallyVariant& v : variants) {
    for (int b = 60; b < 100; ++b) {
      const std::size_t bin = std::size_t(b);
      v.tally.count[bin] = v.truth.count[bin] = 50;
      // Bin b lights its own light column at a few deviations, as a render does.
      std::map<int, double> cells;
      for (int k = 0; k < 8; ++k) cells[(b - 60) + 40 * int(30 * u(rng))] += 5.0 * u(rng);
      double truth = 0.0;
      for (const auto& [c, light] : cells) {
        v.tally.scaled[bin].push_back({c, light});
        truth += light * (0.2 + 0.6 * grid.centre(c)[1] / 30.0);
      }
      v.truth.value[bin] = truth * (1.0 + 0.05 * (u(rng) - 0.5)) / 50.0;
    }
  }
  FloorOptions sparse;
  sparse.smoothness = 1.0;
  FloorOptions dense = sparse;
  dense.dense_variables = 1 << 20;
  const FloorSolution a = solve_floor(grid, variants, sparse),
                      b = solve_floor(grid, variants, dense);
  double largest = 0.0;
  for (std::size_t c = 0; c < a.g.size(); ++c)
    largest = std::max(largest, std::abs(a.g[c] - b.g[c]));
  EXPECT_LT(largest, 1e-8);
  EXPECT_NEAR(a.objective, b.objective, 1e-10 * b.objective);
  EXPECT_LT(a.kkt_residual, 1e-9);
}

TEST(FactorGrid, CellsCentresAndTheOutside) {
  const FactorGrid grid = small_grid();
  FactorInputs in;
  in.deg[int(FactorInput::kLight)] = 75.0;
  in.deg[int(FactorInput::kDeviation)] = 12.0;
  EXPECT_EQ(grid.cell(in), 1 + 1 * 4);
  EXPECT_EQ(grid.centre(5), (std::vector<double>{75.0, 15.0}));
  in.deg[int(FactorInput::kLight)] = 100.0;  // the end is outside
  EXPECT_EQ(grid.cell(in), -1);
  FactorTable t{grid, std::vector<double>(12, 0.5)};
  EXPECT_EQ(t.at(in), 1.0);  // raw bump outside the grid
  // Multilinear between the centres: a table linear in the angles is
  // reproduced exactly inside them, and held constant towards the edges.
  std::vector<double> linear(12);
  for (int c = 0; c < 12; ++c) linear[std::size_t(c)] = grid.centre(c)[0] + 2.0 * grid.centre(c)[1];
  const FactorTable lt{grid, linear};
  const auto at = [&](double light, double deviation) {
    FactorInputs p;
    p.deg[int(FactorInput::kLight)] = light;
    p.deg[int(FactorInput::kDeviation)] = deviation;
    return lt.at(p);
  };
  EXPECT_NEAR(at(80.0, 20.0), 80.0 + 40.0, 1e-12);
  EXPECT_NEAR(at(71.0, 14.0), 71.0 + 28.0, 1e-12);
  EXPECT_NEAR(at(61.0, 2.0), 65.0 + 10.0, 1e-12);  // below the first centres: the corner node
  NodeWeights w;
  FactorInputs mid;
  mid.deg[int(FactorInput::kLight)] = 80.0;
  mid.deg[int(FactorInput::kDeviation)] = 15.0;
  ASSERT_EQ(grid.nodes(mid, &w), 2);
  EXPECT_EQ(w[0], (std::pair<int, double>{5, 0.5}));
  EXPECT_EQ(w[1], (std::pair<int, double>{6, 0.5}));
  // The four angles from vectors.
  const FactorInputs a = factor_inputs({0, 0, 1}, normalize({0, std::sin(0.2), std::cos(0.2)}),
                                       normalize({1, 0, 1}), {0, 0, 1});
  EXPECT_NEAR(a.deg[int(FactorInput::kLight)], 45.0, 1e-12);
  EXPECT_NEAR(a.deg[int(FactorInput::kDeviation)], degrees(0.2), 1e-12);
  EXPECT_NEAR(a.deg[int(FactorInput::kView)], 0.0, 1e-12);
}

}  // namespace
}  // namespace penumbra
