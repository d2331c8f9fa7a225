#include "analysis/contour.h"

#include <cmath>

namespace penumbra {

ContourGrid make_contour_grid(const std::vector<MethodSettings>& methods, double step_deg,
                              double max_light_deg, double max_deviation_deg) {
  ContourGrid grid;
  for (int i = 0; i * step_deg <= max_light_deg + 1e-9; ++i) grid.light_deg.push_back(i * step_deg);
  for (int i = 0; i * step_deg <= max_deviation_deg + 1e-9; ++i)
    grid.deviation_deg.push_back(i * step_deg);
  const Vec3 ng{0, 0, 1};
  for (const MethodSettings& m : methods) {
    std::vector<std::vector<double>> rows;
    for (double d : grid.deviation_deg) {
      std::vector<double> row;
      const double dr = radians(d);
      const Vec3 ns{std::sin(dr), 0, std::cos(dr)};
      for (double t : grid.light_deg) {
        const double tr = radians(t);
        const Vec3 wi{std::sin(tr), 0, std::cos(tr)};
        row.push_back(terminator_factor(m, {ng, ns, wi, ng}));
      }
      rows.push_back(std::move(row));
    }
    grid.g.push_back(std::move(rows));
  }
  return grid;
}

}  // namespace penumbra
