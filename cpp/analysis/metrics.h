// The terminator gradient and the metrics that compare renders (reference
// sheet, section 7). Images are those every renderer produces: R G B A plus
// the evaluator's analysis channels (analysis.theta in degrees).
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "image/image.h"
#include "scene/scene.h"

namespace penumbra {

// Mean radiance per theta bin over fully covered pixels, divided by
// albedo * E / pi, so that a smooth Lambertian surface gives cos(theta).
// Bins are [k w, (k+1) w) degrees over [0, 180).
struct Profile {
  double bin_degrees = 1.0;
  std::vector<double> value;         // dimensionless; 0 where count is 0
  std::vector<std::uint64_t> count;  // pixels in the bin
  double centre(std::size_t bin) const { return (double(bin) + 0.5) * bin_degrees; }
};

struct ProfileOptions {
  double bin_degrees = 1.0;
  double min_coverage = 0.999;  // alpha at or above this: the pixel is all object
  // Bins with fewer pixels than this in either profile are left out of
  // comparisons: a handful of pixels is pixel noise, not a gradient.
  std::uint64_t min_count = 4;
};

// The irradiance (W/m^2) the light gives at `at` on a plane facing it
// (light_axis), shadows aside: exact for the delta lights and for an area
// light wholly in front of that plane (a quad by Lambert's polygon formula);
// an environment's on a plane facing its mean direction, summed over its
// texels' centres.
double light_irradiance(const Light& light, const Vec3& at);

// albedo * E / pi in W m^-2 sr^-1: the radiance of a Lambertian surface facing
// the light. Point and area lights: E at the shape's centre.
double radiance_scale(const Scene& scene);

// `radiance_scale` = albedo * E / pi of the scene (W m^-2 sr^-1).
Profile terminator_profile(const Image& image, double radiance_scale,
                           const ProfileOptions& options = {});

// Degrees: the terminator region of the reference sheet, and the lit region.
inline constexpr double kTerminatorBegin = 60.0, kTerminatorEnd = 100.0;
inline constexpr double kLitEnd = 60.0;
// Level, as a fraction of albedo * E / pi, below which the profile counts as
// dark: where it first crosses it is the terminator position.
inline constexpr double kDarkLevel = 0.05;

// Profile metrics of `test` against `reference`, over bins both populate.
// Values are fractions of albedo * E / pi; angles in degrees. NaN where a
// quantity is undefined (no common bins, or the profile never gets dark).
struct ProfileMetrics {
  double rmse_terminator = 0.0;  // RMS difference over [60, 100) degrees
  double rmse_overall = 0.0;     // RMS difference over all common bins
  double max_error = 0.0;        // largest |difference| in the terminator region
  double max_step = 0.0;         // test: largest |L(k+1) - L(k)| in the terminator region
  double reference_max_step = 0.0;
  double position = 0.0;  // test: theta of the last fall below kDarkLevel
  double reference_position = 0.0;
  double position_error = 0.0;  // position - reference_position
  double width = 0.0;           // test: theta(L = 0.1 L60) - theta(L = 0.9 L60)
  double reference_width = 0.0;
  double lit_bias = 0.0;  // mean(test - reference) over theta < 60 degrees
  std::size_t common_bins = 0;
};

ProfileMetrics compare_profiles(const Profile& test, const Profile& reference,
                                const ProfileOptions& options = {});

// Theta (degrees) of the profile's last fall below `level` at or after
// `from_deg`, linear between bin centres; NaN if it never falls below it.
double crossing(const Profile& p, double level, std::uint64_t min_count, double from_deg = 0.0);

// The viewer's side: the signed error binned by the view angle theta_o (the
// reference's analysis.view), over pixels fully covered in both that the
// light reaches head-on (reference theta < kLitEnd), so that it counts none
// of the terminator region the profile metrics cover. Binned means cancel
// the bump's phase as the profile does; what is left is a method's darkening
// or brightening as a function of where the viewer stands, the flaw of a
// factor applied on the view side (estevez2019-reciprocal, reference sheet
// section 3). Bins: [k w, (k+1) w) degrees over [0, 180).
struct ViewErrorProfile {
  double bin_degrees = 5.0;
  std::vector<double> error_sum;     // per bin: sum of (test - reference) / scale
  std::vector<std::uint64_t> count;  // pixels in the bin
  double centre(std::size_t bin) const { return (double(bin) + 0.5) * bin_degrees; }
  double mean(std::size_t bin) const;  // NaN where the bin is empty
  ViewErrorProfile& operator+=(const ViewErrorProfile& other);
};

// Over rows [row_begin, row_end) (row_end < 0: to the last row); `scale` =
// albedo * E / pi. The bootstrap of intervals adds bands of rows. A reference
// without analysis.view (rendered before Penumbra 0.5) gives empty bins, so
// the metrics below are NaN: unknown, never zero.
ViewErrorProfile view_error_profile(const Image& test, const Image& reference, double scale,
                                    double min_coverage = 0.999, int row_begin = 0,
                                    int row_end = -1);

// Degrees: the grazing views the viewer metric scores. It stops at 75, 1.7
// pixels inside a 51-pixel silhouette at 128 px, so that partly covered
// silhouette pixels, whose number halves when the resolution doubles, are
// never near it.
inline constexpr double kGrazingBegin = 60.0, kGrazingEnd = 75.0;

// Pixel-weighted over the bins in [kGrazingBegin, kGrazingEnd): weights are
// projected areas, the same at every resolution. Fractions of albedo*E/pi.
struct ViewMetrics {
  double rmse_grazing = 0.0;  // sqrt(sum n_k mean_k^2 / sum n_k); NaN if no pixel
  double bias_grazing = 0.0;  // sum n_k mean_k / sum n_k: negative, the test is darker
  std::uint64_t pixels = 0;
};

ViewMetrics view_metrics(const ViewErrorProfile& profile);

// Image-space comparison inside the object.
struct ImageMetrics {
  double mask_iou = 0.0;        // |A>=0.5 in both| / |A>=0.5 in either|
  double rmse = 0.0;            // W m^-2 sr^-1, pixels fully covered in both
  double max_error = 0.0;       // W m^-2 sr^-1, same pixels
  double mean_error = 0.0;      // mean(test - reference), same pixels
  double reference_mean = 0.0;  // mean reference radiance over those pixels
  double peak = 0.0;            // largest reference radiance over those pixels
  // Mean SSIM over the same pixels (Wang et al. 2004: 11x11 Gaussian window,
  // sigma 1.5, K1 = 0.01, K2 = 0.03, dynamic range = reference peak; window
  // weights renormalised over covered pixels so the background does not count).
  double ssim = 0.0;
  std::size_t pixels = 0;     // pixels fully covered in both
  std::size_t nonfinite = 0;  // NaN or Inf values in either image (a failure)
  // Mean HDR-FLIP over every pixel of the frame (analysis/flip.h, 67.02
  // pixels per degree), in [0, 1], 0 = identical; NaN unless measured
  // (MeasureOptions::flip).
  double flip = std::numeric_limits<double>::quiet_NaN();
};

ImageMetrics compare_images(const Image& test, const Image& reference, double min_coverage = 0.999);

// The usual SSIM, for images without a coverage mask (`compare --no-mask`):
// the same window, constants and luminance (R+G+B)/3 as ImageMetrics::ssim,
// with dynamic range L = `data_range`, but every pixel counts and the mean
// runs over the pixels whose whole 11x11 window lies inside the image, as
// scikit-image's structural_similarity(gaussian_weights=True, sigma=1.5,
// use_sample_covariance=False) does. NaN when the image is under 11x11.
double ssim_unmasked(const Image& test, const Image& reference, double data_range);

// Shadow changes of a low-poly render against a smooth (unbumped) ground
// truth, over pixels fully covered in both. Radiances are in units of
// scale = albedo * E / pi, so the truth's unshadowed value is cos(theta),
// theta from the reference's analysis.theta channel.
struct ShadowMetrics {
  std::size_t lit_pixels = 0;       // reference >= kDarkLevel (lit in the truth)
  std::size_t darkened_pixels = 0;  // of those, test < half the reference
  double darkened_fraction = 0.0;   // darkened / lit: the shadow-line pixels
  double max_darkening = 0.0;       // max(reference - test), fraction of albedo*E/pi
  // Cast shadows: facing the light (theta < kShadowMaxTheta) yet below half
  // the unshadowed value cos(theta).
  std::size_t shadowed_pixels = 0;       // in the reference
  std::size_t test_shadowed_pixels = 0;  // in the test
  // Reference-shadowed pixels that the test lights: a shadow the offset lost.
  double lost_shadow_fraction = 0.0;  // NaN when the reference has no cast shadow
  // Distance between the centroids of the two shadowed sets, pixels; NaN
  // when either is empty.
  double shadow_shift_px = 0.0;
};
inline constexpr double kShadowMaxTheta = 85.0;  // degrees

ShadowMetrics compare_shadows(const Image& test, const Image& reference, double scale,
                              double min_coverage = 0.999);

}  // namespace penumbra
