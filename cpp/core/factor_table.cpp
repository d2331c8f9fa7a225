#include "core/factor_table.h"

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
