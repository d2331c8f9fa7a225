// A terminator factor given as a table: G over a grid of angles at the
// shading point, constant within each cell. It is what `penumbra fit` fits
// (analysis/achievable.h) and what the `fitted` method looks up, and the
// grid on which the evaluator tallies raw bump's light so that the
// terminator profile of any such G is a linear function of its cells.
//
// The inputs are the cosines a factor method can see (Chiang et al. 2019
// use the first three, Conty Estevez et al. 2019 the first two), as angles:
//   light      theta_i = acos<Ng,wi>, the light's angle from the geometric normal
//   deviation  delta   = acos<Ng,Ns>, how far the bump tilts the normal
//   shading    theta_s = acos<Ns,wi>, the light's angle from the bump normal
//   view       theta_o = acos<Ng,wo>, the viewer's angle from the geometric normal
// all in degrees. A point outside the grid (beyond the last cell of an
// axis) is left to raw bump: G = 1 there.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>
#include <utility>
#include <vector>

#include "core/enum_names.h"
#include "core/vec.h"

namespace penumbra {

enum class FactorInput { kLight, kDeviation, kShading, kView };
inline constexpr EnumName<FactorInput> kFactorInputNames[] = {
    {"light", FactorInput::kLight},
    {"deviation", FactorInput::kDeviation},
    {"shading", FactorInput::kShading},
    {"view", FactorInput::kView}};

// One axis of the grid: [min_deg, max_deg) in cells of step_deg degrees.
struct FactorAxis {
  FactorInput input = FactorInput::kLight;
  double min_deg = 0.0, max_deg = 180.0, step_deg = 1.0;
  int cells() const;
};

// The four angles of a shading point, degrees.
struct FactorInputs {
  std::array<double, 4> deg{};  // indexed by FactorInput
};
FactorInputs factor_inputs(const Vec3& ng, const Vec3& ns, const Vec3& wi, const Vec3& wo);

inline constexpr std::size_t kMaxFactorAxes = 4;
// A point's nodes and their weights: at most 2^axes of them.
using NodeWeights = std::array<std::pair<int, double>, std::size_t(1) << kMaxFactorAxes>;

// The grid: the product of its axes, the first axis fastest. A table holds
// G at the cells' centres (its nodes) and is multilinear between them, so
// that a smooth factor tabulated on it is off by the square of the cell
// size rather than by its first power; G is constant from the last centre
// to the grid's edge, and 1 outside the grid.
struct FactorGrid {
  std::vector<FactorAxis> axes;
  int cells() const;
  // The cell of a point, or -1 outside the grid.
  int cell(const FactorInputs& in) const;
  // The nodes whose multilinear interpolation is G at a point, with their
  // weights (positive, summing to 1), into *out; their count, 0 outside
  // the grid.
  int nodes(const FactorInputs& in, NodeWeights* out) const;
  // The centre of a cell, degrees, per axis.
  std::vector<double> centre(int cell) const;
};

// A factor table: G per cell of the grid, in [0, inf) (a fitted G may
// exceed 1 where raw bump is too dark).
struct FactorTable {
  FactorGrid grid;
  std::vector<double> values;  // grid.cells() of them, at the cells' centres
  // Multilinear between the centres; 1 outside the grid.
  double at(const FactorInputs& in) const;
};

// Raw bump's light in each pixel of a render, split by the grid's nodes
// with each sample's interpolation weights: what a factor table G would
// make of the pixel is rest + sum light * G
// (W m^-2 sr^-1, already divided by the samples per pixel). Pixel p's
// entries are [offsets[p], offsets[p + 1]) of cells and light.
struct PixelTally {
  int width = 0, height = 0;
  std::vector<double> rest;  // per pixel: light no cell's G scales
  std::vector<std::uint32_t> offsets;
  std::vector<int> cells;
  std::vector<double> light;
};

}  // namespace penumbra
