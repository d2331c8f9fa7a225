#include "analysis/intervals.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace penumbra {

namespace {

// One band's contribution: per theta bin the radiance sum and pixel count
// of each image, and the squared image difference over pixels covered in both.
struct BandSums {
  std::vector<double> test_sum, ref_sum, test_weight, ref_weight;
  std::vector<std::uint64_t> test_count, ref_count;
  double sq = 0.0;
  std::size_t pixels = 0;
  ViewErrorProfile view;
};

struct Channels {
  int rgb[3], alpha, theta;
  explicit Channels(const Image& im)
      : rgb{im.channel_index("R"), im.channel_index("G"), im.channel_index("B")},
        alpha(im.channel_index("A")),
        theta(im.channel_index("analysis.theta")) {}
  double radiance(const Image& im, int x, int y) const {
    return (im.at(x, y, rgb[0]) + im.at(x, y, rgb[1]) + im.at(x, y, rgb[2])) / 3.0f;
  }
};

// The same pixel selection and binning as terminator_profile and compare_images.
void add_to_profile(const Image& im, const Channels& c, int x, int y, const ProfileOptions& o,
                    std::vector<double>& weight, std::vector<double>& sum,
                    std::vector<std::uint64_t>& count) {
  if (im.at(x, y, c.alpha) < o.min_coverage) return;
  const double t = im.at(x, y, c.theta), v = c.radiance(im, x, y);
  if (!std::isfinite(t) || !std::isfinite(v)) return;
  const auto k =
      std::min(sum.size() - 1, static_cast<std::size_t>(std::max(0.0, t) / o.bin_degrees));
  weight[k] += 1.0;
  sum[k] += v;
  ++count[k];
}

std::vector<BandSums> band_sums(const Image& test, const Image& ref, double scale,
                                const ProfileOptions& o, int band_rows) {
  const Channels ct(test), cr(ref);
  const std::size_t bins = static_cast<std::size_t>(std::ceil(180.0 / o.bin_degrees));
  std::vector<BandSums> bands((test.height + band_rows - 1) / band_rows);
  for (BandSums& b : bands) {
    b.test_sum.assign(bins, 0.0), b.ref_sum.assign(bins, 0.0);
    b.test_weight.assign(bins, 0.0), b.ref_weight.assign(bins, 0.0);
    b.test_count.assign(bins, 0), b.ref_count.assign(bins, 0);
  }
  for (int y = 0; y < test.height; ++y) {
    BandSums& b = bands[y / band_rows];
    for (int x = 0; x < test.width; ++x) {
      add_to_profile(test, ct, x, y, o, b.test_weight, b.test_sum, b.test_count);
      add_to_profile(ref, cr, x, y, o, b.ref_weight, b.ref_sum, b.ref_count);
      if (test.at(x, y, ct.alpha) < o.min_coverage || ref.at(x, y, cr.alpha) < o.min_coverage)
        continue;
      const double d = ct.radiance(test, x, y) - cr.radiance(ref, x, y);
      if (!std::isfinite(d)) continue;
      b.sq += d * d;
      ++b.pixels;
    }
  }
  for (std::size_t n = 0; n < bands.size(); ++n)
    bands[n].view = view_error_profile(test, ref, scale, o.min_coverage, int(n) * band_rows,
                                       int(n + 1) * band_rows);
  return bands;
}

// The spread of the replicates (their percentile interval minus their mean)
// placed around the estimate. A plain percentile interval of an RMSE sits
// above the estimate: resampling bands adds noise to every bin, which the
// RMSE turns into upward bias; centring keeps the spread and drops the bias.
// `nonnegative`: an RMSE's interval stops at 0; a signed metric's does not.
Interval centred_interval(std::vector<double> v, double estimate, double confidence,
                          bool nonnegative = true) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (v.empty() || !std::isfinite(estimate)) return {nan, nan};
  std::sort(v.begin(), v.end());
  double mean = 0.0;
  for (double x : v) mean += x / double(v.size());
  const double tail = 0.5 * (1.0 - confidence);
  const double low = estimate + quantile(v, tail) - mean;
  return {nonnegative ? std::max(0.0, low) : low, estimate + quantile(v, 1.0 - tail) - mean};
}

// The two metrics over the bands `pick` selects (all bands: the estimate).
struct Metrics {
  ProfileMetrics profile;
  double image;
  ViewMetrics view;
};

// The sums of a resample, kept between resamples so that each one allocates
// nothing. Only `active` bins (those with pixels in some band) are ever
// touched; the others stay 0, as a fresh sum would leave them.
struct Resample {
  std::vector<std::size_t> active;
  std::vector<double> ts, rs, tw, rw;
  std::vector<std::uint64_t> tc, rc;
  ViewErrorProfile view;
  Profile test, reference;

  explicit Resample(const std::vector<BandSums>& bands) {
    const std::size_t bins = bands[0].test_sum.size();
    for (std::size_t k = 0; k < bins; ++k)
      for (const BandSums& b : bands)
        if (b.test_count[k] > 0 || b.ref_count[k] > 0) {
          active.push_back(k);
          break;
        }
    ts.assign(bins, 0.0), rs.assign(bins, 0.0), tw.assign(bins, 0.0), rw.assign(bins, 0.0);
    tc.assign(bins, 0), rc.assign(bins, 0);
    view = bands[0].view;
  }
};

void fill_profile(const std::vector<std::size_t>& active, const std::vector<double>& weight,
                  const std::vector<double>& sum, const std::vector<std::uint64_t>& count,
                  double scale, const ProfileOptions& o, Profile* p) {
  p->bin_degrees = o.bin_degrees;
  p->count = count;
  p->value.assign(sum.size(), 0.0);
  for (std::size_t k : active)
    if (weight[k] > 0.0) p->value[k] = sum[k] / weight[k] / scale;
}

template <typename Pick>
Metrics metrics_of(const std::vector<BandSums>& bands, Pick pick, double scale,
                   const ProfileOptions& o, Resample& r) {
  for (std::size_t k : r.active) r.ts[k] = r.rs[k] = r.tw[k] = r.rw[k] = 0.0, r.tc[k] = r.rc[k] = 0;
  std::fill(r.view.error_sum.begin(), r.view.error_sum.end(), 0.0);
  std::fill(r.view.count.begin(), r.view.count.end(), 0);
  double sq = 0.0;
  std::size_t pixels = 0;
  for (std::size_t n = 0; n < bands.size(); ++n) {
    const BandSums& b = bands[pick(n)];
    r.view += b.view;
    for (std::size_t k : r.active) {
      r.ts[k] += b.test_sum[k], r.rs[k] += b.ref_sum[k];
      r.tw[k] += b.test_weight[k], r.rw[k] += b.ref_weight[k];
      r.tc[k] += b.test_count[k], r.rc[k] += b.ref_count[k];
    }
    sq += b.sq, pixels += b.pixels;
  }
  fill_profile(r.active, r.tw, r.ts, r.tc, scale, o, &r.test);
  fill_profile(r.active, r.rw, r.rs, r.rc, scale, o, &r.reference);
  return {compare_profiles(r.test, r.reference, o),
          pixels ? std::sqrt(sq / double(pixels)) : std::numeric_limits<double>::quiet_NaN(),
          view_metrics(r.view)};
}

}  // namespace

ComparisonIntervals comparison_intervals(const Image& test, const Image& reference,
                                         double radiance_scale, const ProfileOptions& options,
                                         int band_count, int resamples, std::uint64_t seed) {
  ComparisonIntervals out;
  const int band_rows = std::max(1, (test.height + band_count - 1) / band_count);
  const std::vector<BandSums> bands =
      band_sums(test, reference, radiance_scale, options, band_rows);
  out.bands = static_cast<int>(bands.size());
  out.resamples = resamples;
  if (bands.empty()) return out;
  Resample scratch(bands);
  const Metrics estimate = metrics_of(
      bands, [](std::size_t n) { return n; }, radiance_scale, options, scratch);
  std::mt19937_64 rng(seed);
  auto draw = [&](std::size_t) { return uniform_index(rng, bands.size()); };

  std::vector<double> terminator, image, view, view_bias, max_error, position, lit_bias;
  for (std::vector<double>* v :
       {&terminator, &image, &view, &view_bias, &max_error, &position, &lit_bias})
    v->reserve(std::size_t(std::max(0, resamples)));
  for (int r = 0; r < resamples; ++r) {
    const Metrics m = metrics_of(bands, draw, radiance_scale, options, scratch);
    terminator.push_back(m.profile.rmse_terminator);
    max_error.push_back(m.profile.max_error);
    position.push_back(m.profile.position_error);
    lit_bias.push_back(m.profile.lit_bias);
    image.push_back(m.image);
    view.push_back(m.view.rmse_grazing);
    view_bias.push_back(m.view.bias_grazing);
  }
  out.rmse_terminator = centred_interval(terminator, estimate.profile.rmse_terminator, 0.95);
  out.max_error = centred_interval(max_error, estimate.profile.max_error, 0.95);
  out.position_error = centred_interval(position, estimate.profile.position_error, 0.95, false);
  out.lit_bias = centred_interval(lit_bias, estimate.profile.lit_bias, 0.95, false);
  double sum = 0.0;
  std::size_t n = 0;
  for (double t : terminator)
    if (std::isfinite(t)) sum += t, ++n;
  out.rmse_terminator_bias = n ? sum / double(n) - estimate.profile.rmse_terminator : 0.0;
  out.image_rmse = centred_interval(image, estimate.image, 0.95);
  out.view_rmse_grazing = centred_interval(view, estimate.view.rmse_grazing, 0.95);
  out.view_bias_grazing = centred_interval(view_bias, estimate.view.bias_grazing, 0.95, false);
  return out;
}

}  // namespace penumbra
