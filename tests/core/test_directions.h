// Unit directions for the core tests: uniform random ones and the fixed
// geometries the papers draw (angles in radians, z = the macro normal).
#pragma once

#include <algorithm>
#include <cmath>

#include "core/random.h"
#include "core/vec.h"

namespace penumbra::test {

inline const Vec3 kZ{0, 0, 1};

// Uniform on the sphere.
inline Vec3 random_unit(Pcg32& rng) {
  const double z = 1.0 - 2.0 * rng.next_double();
  const double phi = 2.0 * kPi * rng.next_double();
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  return {r * std::cos(phi), r * std::sin(phi), z};
}

// In the x-z plane at `angle` from +z towards +x.
inline Vec3 in_plane(double angle) {
  return {std::sin(angle), 0.0, std::cos(angle)};
}

inline Vec3 spherical(double theta, double phi) {
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

}  // namespace penumbra::test
