#include "analysis/measure.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

#include "analysis/flip.h"
#include "util/strict_json.h"

namespace penumbra {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// `image` with its A channel set to alpha(x, y), appended when it has none.
template <class Alpha>
Image with_alpha(const Image& image, Alpha alpha) {
  Image out = image;
  int a = image.channel_index("A");
  if (a < 0) {
    const std::size_t nc = image.channels.size(), n = std::size_t(image.width) * image.height;
    out.channels.push_back("A");
    out.pixels.assign(n * (nc + 1), 0.0f);
    for (std::size_t p = 0; p < n; ++p)
      std::copy_n(&image.pixels[p * nc], nc, &out.pixels[p * (nc + 1)]);
    a = static_cast<int>(nc);
  }
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) out.at(x, y, a) = alpha(x, y);
  return out;
}

// R, G, B and A of `image` on a copy of `geometry` (same size): the analysis
// channels of one render lent to an image that has none.
Image with_channels_of(const Image& image, const Image& geometry) {
  Image out = geometry;
  const std::size_t nc = out.channels.size();
  const char* names[4] = {"R", "G", "B", "A"};
  for (int c = 0; c < 4; ++c) {
    const int from = image.channel_index(names[c]), to = out.channel_index(names[c]);
    for (int y = 0; y < out.height; ++y)
      for (int x = 0; x < out.width; ++x)
        out.pixels[(std::size_t(y) * out.width + x) * nc + to] = image.at(x, y, from);
  }
  return out;
}

// `image` with the coverage `options` gives it: itself where it needs no
// copy (it has an A channel, or gets none), else the copy in `storage`.
const Image& covered(const Image& image, const MeasureOptions& options,
                     std::optional<Image>& storage) {
  switch (coverage_source(image, options)) {
    case CoverageSource::kAlpha:
    case CoverageSource::kEveryPixel:
      return image;
    case CoverageSource::kMask: {
      const Image& mask = *options.mask;
      if (mask.width != image.width || mask.height != image.height || mask.channels.empty())
        throw std::invalid_argument("measure: the mask's size differs from the image's");
      const int c = std::max(0, mask.channel_index("A"));
      return storage.emplace(with_alpha(image, [&](int x, int y) { return mask.at(x, y, c); }));
    }
    case CoverageSource::kThreshold: {
      const double level = threshold_level(options);
      const int rgb[3] = {image.channel_index("R"), image.channel_index("G"),
                          image.channel_index("B")};
      return storage.emplace(with_alpha(image, [&](int x, int y) {
        const double v =
            (image.at(x, y, rgb[0]) + image.at(x, y, rgb[1]) + image.at(x, y, rgb[2])) / 3.0;
        return v >= level ? 1.0f : 0.0f;
      }));
    }
    case CoverageSource::kMissing:
    case CoverageSource::kNoScale:
      break;
  }
  throw std::invalid_argument("measure: an image has no coverage and none can be made");
}

ProfileMissing why_no_profile(const Image& test, const Image& reference, double scale) {
  if (reference.channel_index("A") < 0 || test.channel_index("A") < 0)
    return ProfileMissing::kNoCoverage;
  if (reference.channel_index("analysis.theta") < 0 && test.channel_index("analysis.theta") < 0)
    return ProfileMissing::kNoTheta;
  if (!std::isfinite(scale)) return ProfileMissing::kNoScale;
  return ProfileMissing::kNo;
}

ComparisonIntervals nan_intervals() {
  ComparisonIntervals ci;
  for (Interval* i : {&ci.rmse_terminator, &ci.image_rmse, &ci.view_rmse_grazing,
                      &ci.view_bias_grazing, &ci.max_error, &ci.position_error, &ci.lit_bias})
    *i = {kNaN, kNaN};
  ci.rmse_terminator_bias = kNaN;
  return ci;
}

ProfileMetrics nan_profile_metrics() {
  ProfileMetrics m;
  for (double* v : {&m.rmse_terminator, &m.rmse_overall, &m.max_error, &m.max_step,
                    &m.reference_max_step, &m.position, &m.reference_position, &m.position_error,
                    &m.width, &m.reference_width, &m.lit_bias})
    *v = kNaN;
  return m;
}

// Image metrics over the covered pixels or, every_pixel, over every pixel
// with the usual SSIM (analysis/metrics.h, ssim_unmasked).
ImageMetrics image_metrics(const Image& test, const Image& reference, bool every_pixel) {
  if (!every_pixel) return compare_images(test, reference);
  const auto full = [](const Image& image) {
    return with_alpha(image, [](int, int) { return 1.0f; });
  };
  ImageMetrics m = compare_images(full(test), full(reference));
  m.mask_iou = kNaN;
  m.ssim = m.pixels ? ssim_unmasked(test, reference, m.peak) : kNaN;
  return m;
}

// The profile, view, shadow metrics and intervals of two covered images,
// each with the analysis channels (`test` and `reference` as measure()
// gives them the other's where they lack them).
void measure_profiles(const Image& test, const Image& reference, const MeasureOptions& options,
                      Measurement& m) {
  const double scale = options.scale;
  const ProfileOptions po;
  m.profile = compare_profiles(terminator_profile(test, scale, po),
                               terminator_profile(reference, scale, po), po);
  if (options.intervals) {
    m.intervals = comparison_intervals(test, reference, scale, po);
    // Its bands count covered pixels only.
    if (options.every_pixel) m.intervals.image_rmse = {kNaN, kNaN};
  }
  if (options.view) m.view = view_metrics(view_error_profile(test, reference, scale));
  if (options.shadows) m.shadow = compare_shadows(test, reference, scale);
}

}  // namespace

CoverageSource coverage_source(const Image& image, const MeasureOptions& options) {
  if (image.channel_index("A") >= 0) return CoverageSource::kAlpha;
  if (options.mask) return CoverageSource::kMask;
  if (options.threshold)
    return std::isfinite(options.scale) ? CoverageSource::kThreshold : CoverageSource::kNoScale;
  return options.every_pixel ? CoverageSource::kEveryPixel : CoverageSource::kMissing;
}

double threshold_level(const MeasureOptions& options) {
  return options.threshold.value_or(kNaN) * options.scale;
}

namespace {

// Mean HDR-FLIP of the two images as rendered (linear radiance, every
// pixel: the background is black in both) and its interval; NaN where the
// reference gives no exposure (an all-black reference).
void measure_flip(const Image& test, const Image& reference, Measurement& m, FlipImage* out) {
  try {
    FlipOptions options;
    options.range = FlipRange::kHdr;
    FlipImage map = flip_map(test, reference, options);
    m.image.flip = mean_flip(map);
    m.intervals.flip = mean_flip_interval(map);
    if (out) *out = std::move(map);
  } catch (const std::invalid_argument&) {
    m.image.flip = kNaN;
    m.intervals.flip = {kNaN, kNaN};
  }
}

Measurement measure_covered(const Image& test_image, const Image& reference_image,
                            const MeasureOptions& options);

}  // namespace

Measurement measure(const Image& test_image, const Image& reference_image,
                    const MeasureOptions& options, FlipImage* flip_map) {
  Measurement m = measure_covered(test_image, reference_image, options);
  if (options.image && options.flip) measure_flip(test_image, reference_image, m, flip_map);
  return m;
}

namespace {

Measurement measure_covered(const Image& test_image, const Image& reference_image,
                            const MeasureOptions& options) {
  if (test_image.width != reference_image.width || test_image.height != reference_image.height)
    throw std::invalid_argument(fmt::format("measure: a {}x{} image against a {}x{} one",
                                            test_image.width, test_image.height,
                                            reference_image.width, reference_image.height));
  Measurement m;
  m.test_coverage = coverage_source(test_image, options);
  m.reference_coverage = coverage_source(reference_image, options);
  std::optional<Image> test_storage, reference_storage;
  const Image& test = covered(test_image, options, test_storage);
  const Image& reference = covered(reference_image, options, reference_storage);
  if (options.image) m.image = image_metrics(test, reference, options.every_pixel);
  m.profile_missing = why_no_profile(test, reference, options.scale);
  if (m.profile_missing != ProfileMissing::kNo) {
    m.profile = nan_profile_metrics();
    if (options.view) m.view = {kNaN, kNaN, 0};
    if (options.intervals) m.intervals = nan_intervals();
    return m;
  }
  // A side without analysis.theta borrows the other's analysis channels.
  const bool test_has_theta = test.channel_index("analysis.theta") >= 0;
  const bool reference_has_theta = reference.channel_index("analysis.theta") >= 0;
  if (test_has_theta && reference_has_theta) {
    measure_profiles(test, reference, options, m);
  } else if (reference_has_theta) {
    measure_profiles(with_channels_of(test, reference), reference, options, m);
  } else {
    measure_profiles(test, with_channels_of(reference, test), options, m);
  }
  return m;
}

}  // namespace

Image difference_image(const Image& test_image, const Image& reference_image,
                       const MeasureOptions& options) {
  std::optional<Image> test_storage, reference_storage;
  const Image& test = covered(test_image, options, test_storage);
  const Image& reference = covered(reference_image, options, reference_storage);
  Image out;
  out.width = test.width, out.height = test.height;
  out.channels = {"R", "G", "B", "A"};
  out.pixels.resize(std::size_t(out.width) * out.height * 4);
  int t[4], r[4];
  const char* names[4] = {"R", "G", "B", "A"};
  for (int c = 0; c < 4; ++c)
    t[c] = test.channel_index(names[c]), r[c] = reference.channel_index(names[c]);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) {
      float* p = &out.pixels[(std::size_t(y) * out.width + x) * 4];
      for (int c = 0; c < 3; ++c) p[c] = test.at(x, y, t[c]) - reference.at(x, y, r[c]);
      p[3] = std::min(t[3] < 0 ? 1.0f : test.at(x, y, t[3]),
                      r[3] < 0 ? 1.0f : reference.at(x, y, r[3]));
    }
  return out;
}

std::vector<std::string> scene_differences(const nlohmann::json& reference,
                                           const nlohmann::json& test) {
  using nlohmann::json;
  auto comparable = [](const json& scene) {
    json out = json::object();
    for (const char* key : {"camera", "light", "shape", "height"})
      if (scene.is_object() && scene.contains(key)) out[key] = scene[key];
    if (out.contains("shape") && out["shape"].is_object()) out["shape"].erase("tessellation");
    // A filter changes how the bumps are shaded, not which surface it is.
    if (out.contains("height") && out["height"].is_object()) out["height"].erase("filter");
    if (out.contains("camera") && out["camera"].is_object())
      for (const char* key : {"spp", "seed"}) out["camera"].erase(key);
    return out;
  };
  const json diff = json::diff(comparable(reference), comparable(test));
  // Named two levels deep (/camera/right, not /camera/right/0), the shape first.
  std::vector<std::string> where;
  for (const char* key : {"/shape", "/camera", "/light", "/height"})
    for (const json& op : diff) {
      const std::string path = op.at("path").get<std::string>();
      if (path.rfind(key, 0) != 0 ||
          (path.size() > std::strlen(key) && path[std::strlen(key)] != '/'))
        continue;
      const std::string named = printable(path.substr(0, path.find('/', std::strlen(key) + 1)), 60);
      if (std::find(where.begin(), where.end(), named) == where.end()) where.push_back(named);
    }
  return where;
}

}  // namespace penumbra
