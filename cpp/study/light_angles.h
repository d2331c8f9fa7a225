// Light directions as angles a reader can picture, in the scene's axes
// (POV-Ray's: y up, the default camera at -z looking towards +z, +x to its
// right). Used by the CSV columns light_elevation_deg/light_azimuth_deg,
// the variant labels and report.json's axis value labels, so that all three
// agree.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <fmt/format.h>

#include "core/vec.h"

namespace penumbra {

// Elevation of direction d above the x-z plane, degrees in [-90, 90]; NaN
// for a zero vector.
inline double elevation_deg(const Vec3& d) {
  const double n = length(d);
  return n > 0 ? std::asin(std::clamp(d.y / n, -1.0, 1.0)) * 180.0 / kPi
               : std::numeric_limits<double>::quiet_NaN();
}

// Azimuth of d in the x-z plane from -z (the side the default camera is on:
// 0 is front light) towards +x (90: from the image's right; -90: from its
// left; 180: back light), degrees in (-180, 180]; NaN for a vertical d.
// x + 0.0 turns -0 into 0, so that a light straight behind is 180, never -180.
inline double azimuth_deg(const Vec3& d) {
  return d.x == 0.0 && d.z == 0.0 ? std::numeric_limits<double>::quiet_NaN()
                                  : std::atan2(d.x + 0.0, -d.z) * 180.0 / kPi;
}

// "azimuth -79°, elevation 0°" (whole degrees; one decimal below 10°
// where it matters).
inline std::string direction_text(const Vec3& d) {
  auto deg = [](double a) {
    if (!std::isfinite(a)) return std::string("n/a");
    const double r = std::round(a);
    return std::abs(a - r) < 0.05 || std::abs(a) >= 10 ? fmt::format("{:.0f}°", r + 0.0)
                                                       : fmt::format("{:.1f}°", a);
  };
  return fmt::format("azimuth {}, elevation {}", deg(azimuth_deg(d)), deg(elevation_deg(d)));
}

}  // namespace penumbra
