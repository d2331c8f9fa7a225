#include "analysis/metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "core/light_sampling.h"

namespace penumbra {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

int require_channel(const Image& image, const char* name) {
  const int c = image.channel_index(name);
  if (c < 0) throw std::invalid_argument(fmt::format("the image has no {} channel", name));
  return c;
}

float radiance(const Image& image, int x, int y, const int rgb[3]) {
  return (image.at(x, y, rgb[0]) + image.at(x, y, rgb[1]) + image.at(x, y, rgb[2])) / 3.0f;
}

bool usable(const Profile& a, std::size_t k, std::uint64_t min_count) {
  return k < a.count.size() && a.count[k] >= min_count;
}

// SSIM as Wang et al. (2004) define it: an 11x11 Gaussian window (sigma 1.5)
// and K1 = 0.01, K2 = 0.03 of the dynamic range; shared by the masked and the
// unmasked variants, which differ only in the pixels a window takes.
struct SsimWindow {
  static constexpr int kRadius = 5;
  double kernel[2 * kRadius + 1];  // unnormalised 1-D weights
  double c1, c2;
  explicit SsimWindow(double range) : c1(std::pow(0.01 * range, 2)), c2(std::pow(0.03 * range, 2)) {
    for (int i = -kRadius; i <= kRadius; ++i)
      kernel[i + kRadius] = std::exp(-0.5 * i * i / (1.5 * 1.5));
  }
  // The index from a window's weighted means, variances and covariance.
  double index(double mx, double my, double vx, double vy, double cxy) const {
    return ((2 * mx * my + c1) * (2 * cxy + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2));
  }
};

// OpenImageIO's ImageBufAlgo has no SSIM, hence this one.
double ssim_in_mask(const Image& test, const Image& reference, const int trgb[3], const int rrgb[3],
                    int ta, int ra, double min_coverage, double peak) {
  const int w = test.width, h = test.height, radius = SsimWindow::kRadius;
  const SsimWindow window(peak);
  const double* kernel = window.kernel;
  // Radiance and mask once per pixel, not once per window that takes it
  // (121 times); the sums below run in the same order, so the bits agree.
  std::vector<float> a(std::size_t(w) * h), b(a.size());
  std::vector<char> inside(a.size());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = std::size_t(y) * w + x;
      a[i] = radiance(test, x, y, trgb), b[i] = radiance(reference, x, y, rrgb);
      inside[i] = test.at(x, y, ta) >= min_coverage && reference.at(x, y, ra) >= min_coverage;
    }
  double sum = 0.0;
  std::size_t n = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (!inside[std::size_t(y) * w + x]) continue;
      double sw = 0, mx = 0, my = 0, sxx = 0, syy = 0, sxy = 0;
      for (int dy = -radius; dy <= radius; ++dy)
        for (int dx = -radius; dx <= radius; ++dx) {
          const int u = x + dx, v = y + dy;
          if (u < 0 || v < 0 || u >= w || v >= h) continue;
          const std::size_t i = std::size_t(v) * w + u;
          if (!inside[i]) continue;
          const double k = kernel[dx + radius] * kernel[dy + radius];
          const double ai = a[i], bi = b[i];
          sw += k, mx += k * ai, my += k * bi, sxx += k * ai * ai, syy += k * bi * bi,
              sxy += k * ai * bi;
        }
      mx /= sw, my /= sw;
      const double vx = std::max(0.0, sxx / sw - mx * mx), vy = std::max(0.0, syy / sw - my * my);
      sum += window.index(mx, my, vx, vy, sxy / sw - mx * my);
      ++n;
    }
  return n ? sum / double(n) : kNaN;
}

}  // namespace

double light_irradiance(const Light& light, const Vec3& at) {
  switch (light.type) {
    case LightType::kDistant:
      return light.irradiance;
    case LightType::kPoint:
      return light.intensity / length_squared(light.position - at);
    case LightType::kSphere:
      // pi L sin^2 theta_max: the cap's projected solid angle, facing it.
      return light.radiance * kPi *
             std::min(1.0, light.radius * light.radius / length_squared(light.position - at));
    case LightType::kQuad: {
      const Vec3 centre = light.corner + (light.edge_u + light.edge_v) * 0.5;
      if (!(dot(cross(light.edge_u, light.edge_v), at - centre) > 0.0)) return 0.0;  // behind
      const Vec3 v[4] = {light.corner, light.corner + light.edge_u,
                         light.corner + light.edge_u + light.edge_v, light.corner + light.edge_v};
      return polygon_irradiance(v, 4, at, normalize(light_axis(light, at)), light.radiance);
    }
    case LightType::kEnvironment:
      return light.environment
                 ? light.scale * light.environment->irradiance(light.environment->mean_direction())
                 : 0.0;
    case LightType::kGroup: {
      double sum = 0.0;
      for (const Light& m : light.members) sum += light_irradiance(m, at);
      return sum;
    }
  }
  return light.irradiance;
}

double radiance_scale(const Scene& scene) {
  return scene.material.albedo * light_irradiance(scene.light, scene.shape.center) / kPi;
}

Profile terminator_profile(const Image& image, double radiance_scale,
                           const ProfileOptions& options) {
  const int rgb[3] = {require_channel(image, "R"), require_channel(image, "G"),
                      require_channel(image, "B")};
  const int alpha = require_channel(image, "A");
  const int theta = require_channel(image, "analysis.theta");
  Profile p;
  p.bin_degrees = options.bin_degrees;
  const std::size_t bins = static_cast<std::size_t>(std::ceil(180.0 / options.bin_degrees));
  std::vector<double> sum(bins, 0.0);
  p.count.assign(bins, 0);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      if (image.at(x, y, alpha) < options.min_coverage) continue;
      const double t = image.at(x, y, theta);
      const double v = radiance(image, x, y, rgb);
      if (!std::isfinite(t) || !std::isfinite(v)) continue;
      const auto k =
          std::min(bins - 1, static_cast<std::size_t>(std::max(0.0, t) / options.bin_degrees));
      sum[k] += v;
      ++p.count[k];
    }
  p.value.assign(bins, 0.0);
  for (std::size_t k = 0; k < bins; ++k)
    if (p.count[k]) p.value[k] = sum[k] / double(p.count[k]) / radiance_scale;
  return p;
}

double crossing(const Profile& p, double level, std::uint64_t min_count, double from_deg) {
  // The last downward crossing: bump and displacement profiles oscillate in
  // the lit region (a grating's dark flanks), so the first dip below the
  // level is not the terminator; the last bin still above it is.
  double result = kNaN, last_theta = 0.0, last_value = 0.0;
  bool have_last = false;
  for (std::size_t k = 0; k < p.value.size(); ++k) {
    if (!usable(p, k, min_count) || p.centre(k) < from_deg) continue;
    const double v = p.value[k], t = p.centre(k);
    if (have_last && last_value >= level && v < level)
      result = last_theta + (t - last_theta) * (last_value - level) / (last_value - v);
    last_theta = t, last_value = v, have_last = true;
  }
  return result;
}

namespace {

// Theta of the 90 % and 10 % points of the fall from the value at 60 degrees.
double transition_width(const Profile& p, std::uint64_t min_count) {
  double l60 = kNaN;
  for (std::size_t k = 0; k < p.value.size(); ++k)
    if (usable(p, k, min_count) && p.centre(k) >= kLitEnd) {
      l60 = p.value[k];
      break;
    }
  if (!(l60 > 0.0)) return kNaN;
  return crossing(p, 0.1 * l60, min_count, kLitEnd) - crossing(p, 0.9 * l60, min_count, kLitEnd);
}

}  // namespace

ProfileMetrics compare_profiles(const Profile& test, const Profile& reference,
                                const ProfileOptions& options) {
  if (test.bin_degrees != reference.bin_degrees)
    throw std::invalid_argument("profiles with different bin widths");
  ProfileMetrics m;
  double sum_all = 0.0, sum_term = 0.0, sum_lit = 0.0;
  std::size_t n_all = 0, n_term = 0, n_lit = 0;
  const std::size_t bins = std::min(test.value.size(), reference.value.size());
  for (std::size_t k = 0; k < bins; ++k) {
    if (!usable(test, k, options.min_count) || !usable(reference, k, options.min_count)) continue;
    const double d = test.value[k] - reference.value[k], t = test.centre(k);
    sum_all += d * d, ++n_all;
    if (t >= kTerminatorBegin && t < kTerminatorEnd) {
      sum_term += d * d, ++n_term;
      m.max_error = std::max(m.max_error, std::abs(d));
    }
    if (t < kLitEnd) sum_lit += d, ++n_lit;
  }
  m.common_bins = n_all;
  m.rmse_overall = n_all ? std::sqrt(sum_all / double(n_all)) : kNaN;
  m.rmse_terminator = n_term ? std::sqrt(sum_term / double(n_term)) : kNaN;
  if (!n_term) m.max_error = kNaN;
  m.lit_bias = n_lit ? sum_lit / double(n_lit) : kNaN;
  auto max_step = [&](const Profile& p) {
    double step = 0.0;
    for (std::size_t k = 0; k + 1 < p.value.size(); ++k) {
      if (!usable(p, k, options.min_count) || !usable(p, k + 1, options.min_count)) continue;
      const double t = p.centre(k);
      if (t >= kTerminatorBegin && t + p.bin_degrees < kTerminatorEnd)
        step = std::max(step, std::abs(p.value[k + 1] - p.value[k]));
    }
    return step;
  };
  m.max_step = max_step(test);
  m.reference_max_step = max_step(reference);
  m.position = crossing(test, kDarkLevel, options.min_count);
  m.reference_position = crossing(reference, kDarkLevel, options.min_count);
  m.position_error = m.position - m.reference_position;
  m.width = transition_width(test, options.min_count);
  m.reference_width = transition_width(reference, options.min_count);
  return m;
}

namespace {

// Channel indices of two images of the same size that are compared.
struct PairChannels {
  int trgb[3], rrgb[3];
  int ta, ra;
};

PairChannels pair_channels(const Image& test, const Image& reference) {
  if (test.width != reference.width || test.height != reference.height)
    throw std::invalid_argument(fmt::format("image sizes differ: {}x{} and {}x{}", test.width,
                                            test.height, reference.width, reference.height));
  return {{require_channel(test, "R"), require_channel(test, "G"), require_channel(test, "B")},
          {require_channel(reference, "R"), require_channel(reference, "G"),
           require_channel(reference, "B")},
          require_channel(test, "A"),
          require_channel(reference, "A")};
}

}  // namespace

double ssim_unmasked(const Image& test, const Image& reference, double data_range) {
  if (test.width != reference.width || test.height != reference.height)
    throw std::invalid_argument("image sizes differ");
  const int trgb[3] = {require_channel(test, "R"), require_channel(test, "G"),
                       require_channel(test, "B")};
  const int rrgb[3] = {require_channel(reference, "R"), require_channel(reference, "G"),
                       require_channel(reference, "B")};
  const int w = test.width, h = test.height, radius = SsimWindow::kRadius;
  if (w < 2 * radius + 1 || h < 2 * radius + 1) return kNaN;
  std::vector<double> a(std::size_t(w) * h), b(a.size());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      a[std::size_t(y) * w + x] = radiance(test, x, y, trgb);
      b[std::size_t(y) * w + x] = radiance(reference, x, y, rrgb);
    }
  const SsimWindow window(data_range);
  const double* kernel = window.kernel;
  double total = 0.0;
  for (double k : window.kernel) total += k;
  double sum = 0.0;
  for (int y = radius; y < h - radius; ++y)
    for (int x = radius; x < w - radius; ++x) {
      double mx = 0, my = 0, sxx = 0, syy = 0, sxy = 0;
      for (int dy = -radius; dy <= radius; ++dy)
        for (int dx = -radius; dx <= radius; ++dx) {
          const double k = kernel[dx + radius] * kernel[dy + radius] / (total * total);
          const std::size_t i = std::size_t(y + dy) * w + (x + dx);
          mx += k * a[i], my += k * b[i], sxx += k * a[i] * a[i], syy += k * b[i] * b[i],
              sxy += k * a[i] * b[i];
        }
      sum += window.index(mx, my, sxx - mx * mx, syy - my * my, sxy - mx * my);
    }
  return sum / (double(w - 2 * radius) * double(h - 2 * radius));
}

ImageMetrics compare_images(const Image& test, const Image& reference, double min_coverage) {
  const PairChannels ch = pair_channels(test, reference);
  const int(&trgb)[3] = ch.trgb;
  const int(&rrgb)[3] = ch.rrgb;
  const int ta = ch.ta, ra = ch.ra;
  ImageMetrics m;
  std::size_t both = 0, either = 0;
  double sum_sq = 0.0, sum = 0.0, sum_ref = 0.0;
  for (int y = 0; y < test.height; ++y)
    for (int x = 0; x < test.width; ++x) {
      for (int c = 0; c < 3; ++c) {
        if (!std::isfinite(test.at(x, y, trgb[c]))) ++m.nonfinite;
        if (!std::isfinite(reference.at(x, y, rrgb[c]))) ++m.nonfinite;
      }
      const float at = test.at(x, y, ta), ar = reference.at(x, y, ra);
      if (!std::isfinite(at) || !std::isfinite(ar)) {
        ++m.nonfinite;
        continue;
      }
      both += (at >= 0.5f && ar >= 0.5f);
      either += (at >= 0.5f || ar >= 0.5f);
      if (at < min_coverage || ar < min_coverage) continue;
      const double vt = radiance(test, x, y, trgb), vr = radiance(reference, x, y, rrgb);
      if (!std::isfinite(vt) || !std::isfinite(vr)) continue;
      const double d = vt - vr;
      sum_sq += d * d, sum += d, sum_ref += vr;
      m.max_error = std::max(m.max_error, std::abs(d));
      m.peak = std::max(m.peak, vr);
      ++m.pixels;
    }
  m.mask_iou = either ? double(both) / double(either) : 1.0;
  m.ssim =
      m.pixels ? ssim_in_mask(test, reference, trgb, rrgb, ta, ra, min_coverage, m.peak) : kNaN;
  if (m.pixels) {
    m.rmse = std::sqrt(sum_sq / double(m.pixels));
    m.mean_error = sum / double(m.pixels);
    m.reference_mean = sum_ref / double(m.pixels);
  } else {
    m.rmse = m.max_error = m.mean_error = kNaN;
  }
  return m;
}

double ViewErrorProfile::mean(std::size_t bin) const {
  return bin < count.size() && count[bin] ? error_sum[bin] / double(count[bin]) : kNaN;
}

ViewErrorProfile& ViewErrorProfile::operator+=(const ViewErrorProfile& other) {
  if (other.bin_degrees != bin_degrees || other.count.size() != count.size())
    throw std::invalid_argument("view error profiles with different bins");
  for (std::size_t k = 0; k < count.size(); ++k)
    error_sum[k] += other.error_sum[k], count[k] += other.count[k];
  return *this;
}

ViewErrorProfile view_error_profile(const Image& test, const Image& reference, double scale,
                                    double min_coverage, int row_begin, int row_end) {
  const PairChannels ch = pair_channels(test, reference);
  const int theta = require_channel(reference, "analysis.theta");
  const int view = reference.channel_index("analysis.view");
  ViewErrorProfile p;
  const auto bins = static_cast<std::size_t>(std::ceil(180.0 / p.bin_degrees));
  p.error_sum.assign(bins, 0.0);
  p.count.assign(bins, 0);
  if (view < 0) return p;
  if (row_end < 0 || row_end > test.height) row_end = test.height;
  for (int y = std::max(0, row_begin); y < row_end; ++y)
    for (int x = 0; x < test.width; ++x) {
      if (!(test.at(x, y, ch.ta) >= min_coverage && reference.at(x, y, ch.ra) >= min_coverage))
        continue;
      const double t = reference.at(x, y, theta), v = reference.at(x, y, view);
      if (!(t < kLitEnd) || !std::isfinite(v)) continue;
      const double d = (radiance(test, x, y, ch.trgb) - radiance(reference, x, y, ch.rrgb)) / scale;
      if (!std::isfinite(d)) continue;
      const auto k = std::min(bins - 1, static_cast<std::size_t>(std::max(0.0, v) / p.bin_degrees));
      p.error_sum[k] += d;
      ++p.count[k];
    }
  return p;
}

ViewMetrics view_metrics(const ViewErrorProfile& p) {
  ViewMetrics m;
  double sum_sq = 0.0, sum = 0.0;
  for (std::size_t k = 0; k < p.count.size(); ++k) {
    const double lo = double(k) * p.bin_degrees;
    if (lo < kGrazingBegin || lo + p.bin_degrees > kGrazingEnd || !p.count[k]) continue;
    const double mean = p.mean(k), n = double(p.count[k]);
    sum_sq += n * mean * mean, sum += n * mean;
    m.pixels += p.count[k];
  }
  m.rmse_grazing = m.pixels ? std::sqrt(sum_sq / double(m.pixels)) : kNaN;
  m.bias_grazing = m.pixels ? sum / double(m.pixels) : kNaN;
  return m;
}

ShadowMetrics compare_shadows(const Image& test, const Image& reference, double scale,
                              double min_coverage) {
  const PairChannels ch = pair_channels(test, reference);
  const int(&trgb)[3] = ch.trgb;
  const int(&rrgb)[3] = ch.rrgb;
  const int ta = ch.ta, ra = ch.ra;
  const int theta_channel = require_channel(reference, "analysis.theta");
  ShadowMetrics m;
  double cx[2] = {0, 0}, cy[2] = {0, 0};
  std::size_t lost = 0;
  for (int y = 0; y < test.height; ++y)
    for (int x = 0; x < test.width; ++x) {
      if (!(test.at(x, y, ta) >= min_coverage && reference.at(x, y, ra) >= min_coverage)) continue;
      const double vt = radiance(test, x, y, trgb) / scale;
      const double vr = radiance(reference, x, y, rrgb) / scale;
      if (!std::isfinite(vt) || !std::isfinite(vr)) continue;
      m.max_darkening = std::max(m.max_darkening, vr - vt);
      if (vr >= kDarkLevel) {
        ++m.lit_pixels;
        m.darkened_pixels += vt < 0.5 * vr;
      }
      const double theta = reference.at(x, y, theta_channel);
      if (!(theta < kShadowMaxTheta)) continue;
      const double unshadowed = std::cos(radians(theta));
      const bool shadowed[2] = {vr < 0.5 * unshadowed, vt < 0.5 * unshadowed};
      for (int k = 0; k < 2; ++k)
        if (shadowed[k]) cx[k] += x, cy[k] += y;
      m.shadowed_pixels += shadowed[0];
      m.test_shadowed_pixels += shadowed[1];
      lost += shadowed[0] && !shadowed[1];
    }
  m.darkened_fraction = m.lit_pixels ? double(m.darkened_pixels) / double(m.lit_pixels) : kNaN;
  m.lost_shadow_fraction = m.shadowed_pixels ? double(lost) / double(m.shadowed_pixels) : kNaN;
  if (m.shadowed_pixels && m.test_shadowed_pixels) {
    const double n0 = double(m.shadowed_pixels), n1 = double(m.test_shadowed_pixels);
    m.shadow_shift_px = std::hypot(cx[1] / n1 - cx[0] / n0, cy[1] / n1 - cy[0] / n0);
  } else {
    m.shadow_shift_px = kNaN;
  }
  return m;
}

}  // namespace penumbra
