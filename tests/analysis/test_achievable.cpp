// The achievable floor on synthetic tallies whose answer is known: a truth
// that is raw bump times a known G is recovered, G's bounds hold, and no
// other table beats the floor on the variants it was fitted to; the same
// for the image RMSE's per-variant floor, over pixel rows that are exactly
// the image metric's pixels.
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

// 200 tables of small_grid() in the bounds [0, 2]: 100 at random, and 100
// of `floor`'s cells nudged by up to 1e-3, where a floor that is not the
// minimum would show first.
std::vector<std::vector<double>> tables_near(const std::vector<double>& floor) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 2.0);
  std::vector<std::vector<double>> tables(200, std::vector<double>(12));
  for (std::size_t k = 0; k < tables.size(); ++k)
    for (std::size_t c = 0; c < 12; ++c)
      tables[k][c] = k < 100 ? u(rng) : std::clamp(floor[c] + 1e-3 * (u(rng) - 1.0), 0.0, 2.0);
  return tables;
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
  // None of the other tables has a lower mean squared error.
  const std::vector<std::vector<double>> others = tables_near(f.g);
  for (std::size_t k = 0; k < others.size(); ++k) {
    const std::vector<double>& g = others[k];
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

// A 24 x 24 render, its tally and its truth: each pixel lights 2 to 5
// cells of small_grid() (a pixel's samples spread over nearby angles), with
// light no G scales beside them; the truth is that light times `g_true`
// plus `noise` (relative, uniform). A ring of pixels is partly covered in
// the render or the truth and carries a wild truth: no metric may see it.
struct SyntheticImage {
  Image render, truth;
  PixelTally tally;
};

SyntheticImage synthetic_image(const std::vector<double>& g_true, double noise, unsigned seed) {
  constexpr int kSize = 24;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  SyntheticImage s;
  for (Image* im : {&s.render, &s.truth}) {
    im->width = im->height = kSize;
    im->channels = rgba_channels();
    im->pixels.assign(std::size_t(kSize * kSize * 4), 0.0f);
  }
  s.tally.width = s.tally.height = kSize;
  s.tally.offsets.push_back(0);
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      const double rest = 0.3 * u(rng);
      double render = rest, truth = rest;
      std::map<int, double> cells;
      const int n = 2 + int(4 * u(rng));
      for (int k = 0; k < n; ++k) cells[int(12 * u(rng)) % 12] += 2.0 * u(rng);
      for (const auto& [c, light] : cells) {
        s.tally.cells.push_back(c);
        s.tally.light.push_back(light);
        render += light;
        truth += light * g_true[std::size_t(c)];
      }
      s.tally.rest.push_back(rest);
      s.tally.offsets.push_back(std::uint32_t(s.tally.cells.size()));
      truth *= 1.0 + noise * (u(rng) - 0.5);
      const bool edge = x == 0 || y == 0 || x == kSize - 1 || y == kSize - 1;
      if (edge) truth += 100.0;
      for (int c = 0; c < 3; ++c) {
        s.render.at(x, y, c) = float(render);
        s.truth.at(x, y, c) = float(truth);
      }
      s.render.at(x, y, 3) = edge && x % 2 ? 0.5f : 1.0f;
      s.truth.at(x, y, 3) = edge && !(x % 2) ? 0.9f : 1.0f;
    }
  return s;
}

// The rows are compare_images' pixels, and G = 1 gives its RMSE: the
// truth's and the render's values go through float as in the images.
TEST(ImageFloor, PixelRowsAreTheImageMetricsPixelsAndGOfOneIsItsRmse) {
  const SyntheticImage s = synthetic_image(known_g(), 0.2, 7);
  const double scale = 2.0;
  const PixelRows rows = pixel_rows(s.render, s.truth, s.tally, scale);
  const ImageMetrics m = compare_images(s.render, s.truth);
  EXPECT_EQ(rows.rows(), m.pixels);
  EXPECT_EQ(rows.rows(), 22u * 22u);
  // The tally's light is double where the render's pixels are float: 1e-6
  // relative is float's rounding of each pixel, with room.
  EXPECT_NEAR(pixel_rmse(rows, std::vector<double>(12, 1.0)), m.rmse / scale, 1e-6 * m.rmse);
  PixelTally small = s.tally;
  small.width = 23;
  EXPECT_THROW(pixel_rows(s.render, s.truth, small, scale), std::invalid_argument);
}

// A truth that is raw bump times a G inside the bounds: the floor finds G
// and an error of 0, both to the float rounding of the truth's pixels.
TEST(ImageFloor, RecoversTheFactorThatMadeTheTruthAndReachesZero) {
  const SyntheticImage s = synthetic_image(known_g(), 0.0, 8);
  const PixelRows rows = pixel_rows(s.render, s.truth, s.tally, 1.0);
  const FloorSolution f = solve_image_floor(small_grid(), rows);
  for (std::size_t c = 0; c < 12; ++c) EXPECT_NEAR(f.g[c], known_g()[c], 1e-5) << c;
  EXPECT_LT(f.variant_rmse.front(), 1e-6);
}

// A noisy truth that wants G outside [0, 2] in two cells: the bounds hold,
// and no table in them (random, or the floor's nudged) has a lower RMSE.
TEST(ImageFloor, BoundsHoldAndNoOtherTableBeatsTheFloor) {
  std::vector<double> g_true = known_g();
  g_true[0] = 3.0, g_true[11] = -0.5;
  const SyntheticImage s = synthetic_image(g_true, 0.3, 9);
  const PixelRows rows = pixel_rows(s.render, s.truth, s.tally, 1.0);
  const FloorSolution f = solve_image_floor(small_grid(), rows);
  EXPECT_DOUBLE_EQ(f.g[0], 2.0);
  EXPECT_DOUBLE_EQ(f.g[11], 0.0);
  EXPECT_GT(f.variant_rmse.front(), 0.0);
  EXPECT_LT(f.kkt_residual, 1e-10);
  const std::vector<std::vector<double>> others = tables_near(f.g);
  for (std::size_t k = 0; k < others.size(); ++k)
    EXPECT_GE(pixel_rmse(rows, others[k]), f.variant_rmse.front() * (1.0 - 1e-12)) << k;
}

// The sparse path of a floor without a prior, on a semidefinite problem:
// cells 4 and 5 are always lit together in the same ratio, so only their
// weighted sum is determined. The dense solve (LDLT with pivoting) and the
// sparse one (a proximal term) reach the same RMSE, and the determined
// combination, to the solvers' tolerance.
TEST(ImageFloor, SparseAndDenseSolvesReachTheSameFloorOnASemidefiniteProblem) {
  SyntheticImage s = synthetic_image(known_g(), 0.3, 10);
  PixelTally t = s.tally;
  t.offsets = {0}, t.cells.clear(), t.light.clear();
  for (std::size_t p = 0; p + 1 < s.tally.offsets.size(); ++p) {
    std::map<int, double> cells;
    for (std::uint32_t e = s.tally.offsets[p]; e < s.tally.offsets[p + 1]; ++e)
      cells[s.tally.cells[e] == 5 ? 6 : s.tally.cells[e]] += s.tally.light[e];
    if (cells.count(4)) cells[4] *= 0.5, cells[5] = cells[4];
    for (const auto& [c, light] : cells) t.cells.push_back(c), t.light.push_back(light);
    t.offsets.push_back(std::uint32_t(t.cells.size()));
  }
  s.tally = t;
  const PixelRows rows = pixel_rows(s.render, s.truth, s.tally, 1.0);
  FloorOptions sparse;
  sparse.dense_variables = 4;
  const FloorSolution a = solve_image_floor(small_grid(), rows, sparse),
                      b = solve_image_floor(small_grid(), rows);
  EXPECT_GT(a.variant_rmse.front(), 0.0);
  EXPECT_NEAR(a.variant_rmse.front(), b.variant_rmse.front(), 1e-9 * b.variant_rmse.front());
  EXPECT_NEAR(a.g[4] + a.g[5], b.g[4] + b.g[5], 1e-6);
  EXPECT_LT(a.kkt_residual, 1e-8);
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
