#include "core/factor_table.h"

#include <algorithm>
#include <cmath>

#include <cmath>

namespace penumbra {

int FactorAxis::cells() const {
  return static_cast<int>(std::lround((max_deg - min_deg) / step_deg));
}

FactorInputs factor_inputs(const Vec3& ng, const Vec3& ns, const Vec3& wi, const Vec3& wo) {
  const auto angle = [](const Vec3& a, const Vec3& b) {
    return degrees(std::acos(std::clamp(dot(a, b), -1.0, 1.0)));
  };
  FactorInputs in;
  in.deg[static_cast<int>(FactorInput::kLight)] = angle(ng, wi);
  in.deg[static_cast<int>(FactorInput::kDeviation)] = angle(ng, ns);
  in.deg[static_cast<int>(FactorInput::kShading)] = angle(ns, wi);
  in.deg[static_cast<int>(FactorInput::kView)] = angle(ng, wo);
  return in;
}

int FactorGrid::cells() const {
  int n = 1;
  for (const FactorAxis& a : axes) n *= a.cells();
  return axes.empty() ? 0 : n;
}

int FactorGrid::cell(const FactorInputs& in) const {
  int index = 0, stride = 1;
  for (const FactorAxis& a : axes) {
    const double x = in.deg[static_cast<int>(a.input)];
    const int n = a.cells();
    const double k = std::floor((x - a.min_deg) / a.step_deg);
    if (!(k >= 0.0) || k >= double(n)) return -1;
    index += static_cast<int>(k) * stride;
    stride *= n;
  }
  return axes.empty() ? -1 : index;
}

int FactorGrid::nodes(const FactorInputs& in, NodeWeights* out) const {
  if (axes.empty() || axes.size() > kMaxFactorAxes) return 0;
  // Per axis: the two neighbouring centres and the weight of the upper one.
  std::array<int, kMaxFactorAxes> lower{}, upper{};
  std::array<double, kMaxFactorAxes> t{};
  for (std::size_t a = 0; a < axes.size(); ++a) {
    const FactorAxis& axis = axes[a];
    const double x = in.deg[static_cast<int>(axis.input)];
    const int n = axis.cells();
    const double u = (x - axis.min_deg) / axis.step_deg;
    if (!(u >= 0.0) || u >= double(n)) return 0;
    // Between the grid's edge and the first (last) centre: that centre alone.
    const double c = std::clamp(u - 0.5, 0.0, double(n - 1));
    lower[a] = std::min(static_cast<int>(std::floor(c)), n - 1);
    upper[a] = std::min(lower[a] + 1, n - 1);
    t[a] = c - double(lower[a]);
  }
  int count = 0;
  for (int corner = 0; corner < (1 << axes.size()); ++corner) {
    int index = 0, stride = 1;
    double w = 1.0;
    for (std::size_t a = 0; a < axes.size(); ++a) {
      const bool up = (corner >> a) & 1;
      w *= up ? t[a] : 1.0 - t[a];
      index += (up ? upper[a] : lower[a]) * stride;
      stride *= axes[a].cells();
    }
    if (w > 0.0) (*out)[static_cast<std::size_t>(count++)] = {index, w};
  }
  return count;
}

double FactorTable::at(const FactorInputs& in) const {
  NodeWeights w;
  const int n = grid.nodes(in, &w);
  if (n == 0) return 1.0;
  double g = 0.0;
  for (int k = 0; k < n; ++k)
    g += w[static_cast<std::size_t>(k)].second *
         values[static_cast<std::size_t>(w[static_cast<std::size_t>(k)].first)];
  return g;
}

std::vector<double> FactorGrid::centre(int cell) const {
  std::vector<double> out;
  for (const FactorAxis& a : axes) {
    const int n = a.cells();
    out.push_back(a.min_deg + (double(cell % n) + 0.5) * a.step_deg);
    cell /= n;
  }
  return out;
}

}  // namespace penumbra
