#include "analysis/contour.h"

#include <cmath>
#include <limits>

#include "core/shading.h"

namespace penumbra {

namespace {

// The factor a method applies at one grid point: its own for a plain
// factor; for the others the radiance over raw bump's on a white Lambertian
// base (NaN where raw bump receives no light).
double effective_factor(const MethodSettings& m, const Vec3& ng, const Vec3& ns, const Vec3& wi) {
  if (method_info(m.method).kind == MethodKind::kFactor)
    return terminator_factor(m, {ng, ns, wi, ng});
  TerminatorSettings t;
  t.method = m;
  Material white;
  white.albedo = 1.0;
  const Shaded s = shade(t, white, {ng, ng, ns, wi, ng}, nullptr);
  return s.factor_defined ? s.factor : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

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
        row.push_back(effective_factor(m, ng, ns, wi));
      }
      rows.push_back(std::move(row));
    }
    grid.g.push_back(std::move(rows));
  }
  return grid;
}

}  // namespace penumbra
