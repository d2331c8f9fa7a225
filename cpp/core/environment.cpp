#include "core/environment.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace penumbra {

namespace {

// Scene (y up) <-> Blender (z up): the y <-> z swap, its own inverse.
Vec3 swap_yz(const Vec3& v) {
  return {v.x, v.z, v.y};
}

Vec3 rotate_z(const Vec3& v, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c * v.x - s * v.y, s * v.x + c * v.y, v.z};
}

// Index of the first entry of cdf[0..n] (cdf[0] = 0, cdf[n] = 1) above u,
// minus one: the cell u falls in, skipping cells of zero weight.
int find_cell(const double* cdf, int n, double u) {
  const double* it = std::upper_bound(cdf, cdf + n + 1, u);
  return std::clamp(int(it - cdf) - 1, 0, n - 1);
}

}  // namespace

MapCoordinates environment_coordinates(const Vec3& direction, double rotation_rad) {
  const Vec3 b = rotate_z(swap_yz(direction), rotation_rad);
  const double z = std::clamp(b.z / length(b), -1.0, 1.0);
  double s = 0.5 - std::atan2(b.y, b.x) / (2.0 * kPi);
  if (s >= 1.0) s -= 1.0;  // atan2 = -pi exactly
  return {s, 1.0 - std::acos(z) / kPi};
}

Vec3 environment_direction(const MapCoordinates& c, double rotation_rad) {
  const double phi = (0.5 - c.s) * 2.0 * kPi;
  const double theta = (1.0 - c.t) * kPi;
  const Vec3 b{std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
  return swap_yz(rotate_z(b, -rotation_rad));
}

EnvironmentMap::EnvironmentMap(std::vector<float> radiance, int width, int height,
                               double rotation_rad)
    : radiance_(std::move(radiance)), width_(width), height_(height), rotation_(rotation_rad) {
  if (width < 2 || height < 2 || radiance_.size() != std::size_t(width) * height)
    throw std::invalid_argument("EnvironmentMap: needs at least 2 x 2 texels, width * height");
  row_cdf_.assign(std::size_t(height) + 1, 0.0);
  column_cdf_.assign(std::size_t(height) * (width + 1), 0.0);
  texel_weight_.assign(radiance_.size(), 0.0);
  // Weight of a texel: its radiance times its solid angle, so that the
  // density per steradian is proportional to the radiance itself.
  for (int y = 0; y < height; ++y) {
    double* cdf = &column_cdf_[std::size_t(y) * (width + 1)];
    const double omega = texel_solid_angle(y);
    for (int x = 0; x < width; ++x) {
      const double w = double(texel(x, y)) * omega;
      texel_weight_[std::size_t(y) * width + x] = w;
      cdf[x + 1] = cdf[x] + w;
    }
    row_cdf_[std::size_t(y) + 1] = row_cdf_[std::size_t(y)] + cdf[width];
  }
  const double total = row_cdf_[std::size_t(height)];
  if (!(total > 0.0)) return;  // black: sample() gives pdf 0
  Vec3 mean;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      mean += texel_centre(x, y) * texel_weight_[std::size_t(y) * width + x];
  light_vector_ = mean;
  if (length(mean) > 0.0) mean_direction_ = normalize(mean);
  for (double& w : texel_weight_) w /= total;
  for (double& c : row_cdf_) c /= total;
  for (int y = 0; y < height; ++y) {
    double* cdf = &column_cdf_[std::size_t(y) * (width + 1)];
    const double row = cdf[width];
    if (row > 0.0)
      for (int x = 0; x <= width; ++x) cdf[x] /= row;
  }
}

Vec3 EnvironmentMap::texel_centre(int x, int y) const {
  return environment_direction({(x + 0.5) / width_, 1.0 - (y + 0.5) / height_}, rotation_);
}

double EnvironmentMap::irradiance(const Vec3& n) const {
  double sum = 0.0;
  for (int y = 0; y < height_; ++y) {
    const double omega = texel_solid_angle(y);
    for (int x = 0; x < width_; ++x)
      sum += texel(x, y) * std::max(0.0, dot(n, texel_centre(x, y))) * omega;
  }
  return sum;
}

double EnvironmentMap::texel_solid_angle(int y) const {
  // Row y spans polar angles [y pi / height, (y + 1) pi / height].
  const double upper = std::cos(kPi * y / height_), lower = std::cos(kPi * (y + 1) / height_);
  return 2.0 * kPi / width_ * (upper - lower);
}

int EnvironmentMap::texel_x(double s) const {
  return std::clamp(int(s * width_), 0, width_ - 1);
}
int EnvironmentMap::texel_y(double t) const {
  return std::clamp(int((1.0 - t) * height_), 0, height_ - 1);
}

double EnvironmentMap::radiance(const Vec3& direction) const {
  const MapCoordinates c = environment_coordinates(direction, rotation_);
  return texel(texel_x(c.s), texel_y(c.t));
}

double EnvironmentMap::pdf(const Vec3& direction) const {
  const MapCoordinates c = environment_coordinates(direction, rotation_);
  const int x = texel_x(c.s), y = texel_y(c.t);
  return texel_weight_[std::size_t(y) * width_ + x] / texel_solid_angle(y);
}

LightDirectionSample EnvironmentMap::sample(double u1, double u2, double* radiance) const {
  *radiance = 0.0;
  if (!(row_cdf_.back() > 0.0)) return {};
  const int y = find_cell(row_cdf_.data(), height_, u1);
  const double* cdf = &column_cdf_[std::size_t(y) * (width_ + 1)];
  const int x = find_cell(cdf, width_, u2);
  // Reuse what is left of each uniform within its cell: uniform in
  // azimuth and in cos(polar angle) over the texel, i.e. in solid angle.
  const double row_width = row_cdf_[std::size_t(y) + 1] - row_cdf_[std::size_t(y)];
  const double column_width = cdf[x + 1] - cdf[x];
  const double a = std::clamp((u1 - row_cdf_[std::size_t(y)]) / row_width, 0.0, 1.0);
  const double b = std::clamp((u2 - cdf[x]) / column_width, 0.0, 1.0);
  const double upper = std::cos(kPi * y / height_), lower = std::cos(kPi * (y + 1) / height_);
  const double cos_polar = upper + (lower - upper) * a;
  const double s = (x + b) / width_;
  const MapCoordinates c{std::min(s, std::nextafter(1.0, 0.0)),
                         1.0 - std::acos(std::clamp(cos_polar, -1.0, 1.0)) / kPi};
  const Vec3 wi = normalize(environment_direction(c, rotation_));
  const double weight = texel_weight_[std::size_t(y) * width_ + x];
  *radiance = texel(x, y);
  return {wi, weight / texel_solid_angle(y), std::numeric_limits<double>::infinity()};
}

}  // namespace penumbra
