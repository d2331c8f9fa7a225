// FLIP: the perceptual difference of a test image against a reference, as a
// viewer flipping between the two at a given distance would see it.
//
// LDR-FLIP: Andersson, Nilsson, Akenine-Möller, Oskarsson, Åström and
// Fairchild, "FLIP: A Difference Evaluator for Alternating Images", Proc. ACM
// Comput. Graph. Interact. Tech. (HPG) 3(2), 2020. HDR-FLIP: Andersson,
// Nilsson, Shirley and Akenine-Möller, "Visualizing Errors in Rendered High
// Dynamic Range Images", Eurographics 2021 short papers.
//
// Written from the papers' equations. The conventions the papers leave open
// were read in the reference implementation, NVlabs/flip (BSD-3-Clause),
// src/cpp/FLIP.h at commit 1eb247cabcf2862c2c8207ab15314304394132b9 (v1.6),
// none of its code copied: the default pixels per degree (calculatePPD), the
// D65 white of the sRGB matrix (CIE's (0.31271, 0.32902), which its
// LinearRGBToXYZ implies), the filters' radii, sampling and normalisation
// (setSpatialFilters, setFeatureFilter), clamp-to-edge filtering, the ACES
// fit with its 0.6 pre-exposure cancellation and the exposure range
// (computeExposures, the median taken as the element n/2). docs/reading-numbers.md ("FLIP") says
// what the number means; tests/analysis/test_flip.cpp checks it against the
// values the reference implementation prints.
//
// Where Penumbra departs from the reference implementation, for inputs that
// break it: NaN and Inf count as 0 (compare already fails such an image);
// HDR inputs below 0 count as 0 (radiance); and an HDR reference whose median
// luminance is 0 (more than half of it black background, as in most renders
// here) takes its stop exposure from the median of its non-zero pixels,
// where the reference implementation's stop exposure would be infinite.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "analysis/intervals.h"
#include "analysis/statistics.h"
#include "core/vec.h"
#include "image/image.h"

namespace penumbra {

// ---- Viewing conditions ----------------------------------------------------

// Pixels per degree of visual angle of a display `width_px` pixels and
// `width_m` metres wide seen from `distance_m` metres: d (N / w) pi / 180,
// the small-angle size of one degree on the screen.
double pixels_per_degree(double distance_m, double width_px, double width_m);

// FLIP's default observer: a 0.7 m wide 3840-pixel (4K) monitor seen from
// 0.7 m, 3840 pi / 180 = 67.02 pixels per degree.
inline constexpr double kFlipDefaultPixelsPerDegree = 3840.0 * kPi / 180.0;

// ---- Colour spaces (per pixel, double precision) -----------------------------

struct LinearRgb {
  double r = 0, g = 0, b = 0;
};
struct Xyz {  // CIE 1931, Y = 1 for the sRGB white
  double x = 0, y = 0, z = 0;
};
struct YCxCz {  // the opponent space FLIP filters in (Y 0..100 like L*)
  double y = 0, cx = 0, cz = 0;
};
struct Lab {  // CIELAB; after hunt_adjusted(), a and b scaled by L/100
  double l = 0, a = 0, b = 0;
};

// The sRGB (IEC 61966-2-1) decoding of an encoded value in [0, 1].
double srgb_to_linear(double encoded);

// sRGB primaries, D65 white (derived from their chromaticities).
Xyz xyz_from_linear_rgb(const LinearRgb& c);
LinearRgb linear_rgb_from_xyz(const Xyz& c);
// The sRGB white, linear (1, 1, 1): the reference white of both spaces.
Xyz d65_white();

// Y = 116 y/yn - 16, Cx = 500 (x/xn - y/yn), Cz = 200 (y/yn - z/zn): CIELAB
// without its cube root, so linear and filterable (Zhang and Wandell 1997).
YCxCz ycxcz_from_xyz(const Xyz& c);
Xyz xyz_from_ycxcz(const YCxCz& c);
Lab lab_from_xyz(const Xyz& c);

// The Hunt effect (colourfulness grows with luminance): a, b times L/100.
Lab hunt_adjusted(const Lab& c);
// HyAB distance: |dL| + sqrt(da^2 + db^2).
double hyab(const Lab& p, const Lab& q);

// ---- The FLIP error from its two parts ----------------------------------------

// The paper's constants: colour exponent qc, the knee pc and the value pt it
// maps to, the feature width w (degrees) and the feature exponent qf.
inline constexpr double kFlipQc = 0.7, kFlipPc = 0.4, kFlipPt = 0.95;
inline constexpr double kFlipFeatureWidthDeg = 0.082, kFlipQf = 0.5;

// The largest colour distance, HyAB^qc between Hunt-adjusted green and blue.
double flip_max_colour_distance();
// The colour error in [0, 1]: HyAB^qc mapped linearly to [0, pt] below
// pc * cmax and to [pt, 1] above it.
double flip_colour_error(double hyab_distance);
// The feature error in [0, 1] from the edge and point magnitudes of both
// images: (max(|de|, |dp|) / sqrt(2))^qf.
double flip_feature_error(double edge_reference, double edge_test, double point_reference,
                          double point_test);
// The FLIP error: colour^(1 - feature).
double flip_error(double colour_error, double feature_error);

// ---- Filters ---------------------------------------------------------------------

// The contrast sensitivity functions as separable sampled filters over
// [-radius, radius] pixels: achromatic and red-green one Gaussian each,
// blue-yellow the sum of two, each kept as its own separable pair
// (blue_yellow[0] (x) blue_yellow[0] + blue_yellow[1] (x) blue_yellow[1]).
// Each channel's 2D filter sums to 1. Radius: 3 standard deviations of the
// widest Gaussian, ceil(3 sqrt(b_max / (2 pi^2)) ppd).
struct SpatialFilters {
  int radius = 0;
  std::vector<float> achromatic, red_green, blue_yellow[2];
};
SpatialFilters spatial_filters(double pixels_per_degree);

// The edge and point detectors: a Gaussian of sigma = w/2 degrees in pixels
// and its first and second derivatives over [-ceil(3 sigma), ceil(3 sigma)];
// the Gaussian sums to 1, each derivative's positive weights to 1 and its
// negative weights to -1.
struct FeatureFilters {
  int radius = 0;
  std::vector<float> gaussian, first_derivative, second_derivative;
};
FeatureFilters feature_filters(double pixels_per_degree);

// How far a change to one pixel reaches in the map (Chebyshev distance,
// pixels): the larger of the two filters' radii.
int flip_support_radius(double pixels_per_degree);

// ---- HDR-FLIP's exposures ----------------------------------------------------------

// The ACES filmic fit FLIP tone maps with (Narkowicz 2015, input scaled by
// 0.6), per channel: (k0 x^2 + k1 x) / (k3 x^2 + k4 x + k5).
double aces_tone_map(double x);

// `count` exposures 2^c, c evenly spaced over [start, stop] (stops).
struct ExposureRange {
  double start = 0.0, stop = 0.0;
  int count = 0;
  double exposure(int i) const;
};

// HDR-FLIP's range from the reference's luminance: start maps its largest
// luminance, stop its median, to 0.85 after tone mapping; one exposure per
// stop between them, at least 2. An all-black reference: [0, 0].
ExposureRange hdr_exposures(const Image& reference);

// ---- The map and its mean -------------------------------------------------------

enum class FlipRange {
  kLdr,  // R, G, B: linear display values, clamped to [0, 1]
  kHdr,  // R, G, B: linear radiance, any unit (the exposures follow the reference)
};

struct FlipOptions {
  FlipRange range = FlipRange::kLdr;
  double pixels_per_degree = kFlipDefaultPixelsPerDegree;
  // HDR only: the exposures; by default hdr_exposures(reference).
  std::optional<ExposureRange> exposures;
};

// The per-pixel FLIP error, row-major from the top, each in [0, 1].
struct FlipImage {
  int width = 0, height = 0;
  std::vector<float> error;
  FlipRange range = FlipRange::kLdr;
  double pixels_per_degree = 0.0;
  ExposureRange exposures;  // HDR: those the map is the maximum over
  float at(int x, int y) const { return error[std::size_t(y) * width + x]; }
};

// FLIP of `test` against `reference` (same size, channels R, G and B, other
// channels ignored). Throws ImageMismatch when they do not fit and
// std::invalid_argument for a pixels per degree not above 0 or HDR
// exposures fewer than 1.
FlipImage flip_map(const Image& test, const Image& reference, const FlipOptions& options = {});

// The images' R, G and B decoded from sRGB (8-bit PNGs and the like hold
// encoded values; FLIP wants linear ones). Other channels are kept.
Image srgb_decoded(const Image& encoded);

// The mean over every pixel, as FLIP's authors pool it (double sums).
double mean_flip(const FlipImage& map);

// The 95 % interval of mean_flip from the same paired block bootstrap as
// every comparison metric (analysis/intervals.h): the same bands of rows,
// resamples and seed, so the same bands are drawn. The mean is linear in
// the bands' sums, so its replicates centre on the estimate (to within the
// resampling noise) and their plain percentile interval is the centred
// interval the other metrics get; NaN for an empty map.
Interval mean_flip_interval(const FlipImage& map, int bands = kIntervalBands,
                            int resamples = kIntervalResamples, std::uint64_t seed = 1);

}  // namespace penumbra
