// A captured environment as a light: a latitude-longitude radiance map at
// infinity, looked up per texel (piecewise constant, as its sampling
// density is) and sampled by a piecewise-constant 2-D distribution over
// its texels weighted by luminance times sin(theta) (pbrt-v4, section
// 12.5.2's image infinite light; Pharr, Jakob and Humphreys 2023). Pure
// math: the scene layer reads the file.
#pragma once

#include <cstdint>
#include <vector>

#include "core/light_sampling.h"
#include "core/vec.h"

namespace penumbra {

// Directions and map coordinates, Cycles' equirectangular convention
// (direction_to_equirectangular, src/kernel/camera/projection.h of
// blender/cycles) in Blender's frame (z up), which is the scene's (POV-Ray's,
// y up) with y and z swapped:
//   b = (x, z, y) for the scene's (x, y, z);  b' = Rz(rotation) b, the
//   rotation a Mapping node of that Z rotation applies to the world's
//   direction before the Environment Texture node reads it;
//   s = 1/2 - atan2(b'.y, b'.x) / 2 pi,   t = 1 - acos(b'.z) / pi,
// s across the map (texel x = s width), t up it (texel row y = (1 - t) height,
// row 0 at the zenith).
struct MapCoordinates {
  double s = 0.0, t = 0.0;
};
MapCoordinates environment_coordinates(const Vec3& direction, double rotation_rad);
Vec3 environment_direction(const MapCoordinates& c, double rotation_rad);

// One channel of radiance per texel, W/(m^2 sr), row-major from the top
// row (y = 0 at t = 1), with the sampling tables built from it.
class EnvironmentMap {
 public:
  // `radiance`: width * height finite values >= 0; width >= 2, height >= 2.
  EnvironmentMap(std::vector<float> radiance, int width, int height, double rotation_rad);

  int width() const { return width_; }
  int height() const { return height_; }
  double rotation() const { return rotation_; }
  // The radiance seen along `direction` (unit): its texel's value.
  double radiance(const Vec3& direction) const;
  double texel(int x, int y) const { return radiance_[std::size_t(y) * width_ + x]; }
  // A direction by the 2-D distribution, (u1, u2) in [0,1)^2: pdf per
  // steradian, distance infinite, and the radiance of the texel drawn (the
  // one radiance() reads there but for rounding at a texel's edge). pdf 0
  // where the map is black everywhere.
  LightDirectionSample sample(double u1, double u2, double* radiance) const;
  // The density sample() draws `direction` with, per steradian.
  double pdf(const Vec3& direction) const;
  // The radiance-weighted mean of the directions (sum of L d dOmega over
  // the texels), normalised; +y (up) for a map without one.
  Vec3 mean_direction() const { return mean_direction_; }
  // The sum of L d dOmega over the texels (W/m^2): the map's vector
  // irradiance, the same at every point (a map at infinity).
  Vec3 light_vector() const { return light_vector_; }
  // The irradiance on a plane of unit normal n, shadows aside: the sum over
  // texels of L max(0, n . d) dOmega at the texels' centres.
  double irradiance(const Vec3& n) const;
  // The solid angle of row y's texels, each: (2 pi / width)(cos of its
  // upper edge's polar angle - cos of its lower edge's).
  double texel_solid_angle(int y) const;

 private:
  Vec3 texel_centre(int x, int y) const;  // direction through the texel's centre
  int texel_x(double s) const;
  int texel_y(double t) const;

  std::vector<float> radiance_;
  int width_ = 0, height_ = 0;
  double rotation_ = 0.0;
  // Sampling by rows then columns: each row's weight (luminance times the
  // texels' solid angle) and cumulative sums, normalised to 1 at the end.
  std::vector<double> row_cdf_;       // height + 1
  std::vector<double> column_cdf_;    // height * (width + 1)
  std::vector<double> texel_weight_;  // width * height, sums to 1 over all texels
  Vec3 mean_direction_{0, 1, 0};
  Vec3 light_vector_;
};

}  // namespace penumbra
