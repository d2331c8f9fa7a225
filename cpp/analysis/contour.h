// Chiang et al. 2019, Fig. 5: a method's factor G over (light angle from Ng,
// shading-normal deviation towards the light), both in degrees. Geometry:
// Ng = z, wi = (sin t, 0, cos t), Ns = (sin d, 0, cos d), wo = Ng (viewer
// along the base normal, which matters to estevez2019-reciprocal and the
// view-dependent adjustments). Methods that are not a plain factor get an
// effective factor: their radiance over raw bump's on a white Lambertian
// base, NaN where raw bump receives no light (light behind Ns); it may
// exceed 1 (schuessler2017 lights what raw bump leaves dark).
#pragma once

#include <string>
#include <vector>

#include "core/terminator.h"

namespace penumbra {

struct ContourGrid {
  std::vector<double> light_deg;      // columns
  std::vector<double> deviation_deg;  // rows
  // One per method: g[row][column].
  std::vector<std::vector<std::vector<double>>> g;
};

// Angles 0, step, 2 step, ... up to max_deg (light) and max_deviation_deg.
ContourGrid make_contour_grid(const std::vector<MethodSettings>& methods, double step_deg,
                              double max_light_deg = 90.0, double max_deviation_deg = 89.0);

}  // namespace penumbra
