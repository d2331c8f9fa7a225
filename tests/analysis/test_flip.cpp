// FLIP (analysis/flip.h): values computed by hand from the papers' equations,
// the values the reference implementation prints for the pairs under
// tests/analysis/data/flip/ (README.md there says how each was made), and
// the properties the papers' construction implies.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "analysis/flip.h"
#include "analysis/magma.h"
#include "image/image_io.h"

namespace penumbra {
namespace {

const std::string kData = std::string(PENUMBRA_SOURCE_DIR) + "/tests/analysis/data/flip/";

Image uniform(int width, int height, double r, double g, double b) {
  Image image{width, height, {"R", "G", "B"}, {}};
  for (int i = 0; i < width * height; ++i)
    image.pixels.insert(image.pixels.end(), {float(r), float(g), float(b)});
  return image;
}

// Deterministic pseudo-random values in [0, 1) (a 64-bit LCG's top bits).
struct Lcg {
  std::uint64_t state;
  double next() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return double(state >> 11) * 0x1.0p-53;
  }
};

Image random_image(int width, int height, double scale, std::uint64_t seed) {
  Lcg rng{seed};
  Image image{width, height, {"R", "G", "B"}, {}};
  for (int i = 0; i < width * height * 3; ++i) image.pixels.push_back(float(scale * rng.next()));
  return image;
}

FlipOptions hdr() {
  FlipOptions o;
  o.range = FlipRange::kHdr;
  return o;
}

// ---- The equations, by hand ----------------------------------------------------------

// The sRGB primaries with CIE's D65 (0.31271, 0.32902) put the white at
// X = 0.31271 / 0.32902 = 0.950428545..., Z = (1 - 0.31271 - 0.32902) /
// 0.32902 = 1.088900370...; the reference implementation's
// DEFAULT_ILLUMINANT is the same to its 9 digits.
TEST(Flip, WhiteIsD65FromItsChromaticity) {
  const Xyz w = d65_white();
  EXPECT_NEAR(w.x, 0.31271 / 0.32902, 1e-12);
  EXPECT_NEAR(w.y, 1.0, 1e-12);
  EXPECT_NEAR(w.z, (1.0 - 0.31271 - 0.32902) / 0.32902, 1e-12);
  const Lab white = lab_from_xyz(w), black = lab_from_xyz({0, 0, 0});
  EXPECT_NEAR(white.l, 100.0, 1e-12);
  EXPECT_NEAR(white.a, 0.0, 1e-12);
  EXPECT_NEAR(black.l, 0.0, 1e-12);  // 116 * 4/29 - 16 on the linear segment
}

// cmax: green (0, 1, 0) is L*a*b* (87.736, -86.179, 83.183) and blue
// (32.298, 79.194, -107.859); Hunt-adjusted (a, b times L/100) their HyAB
// distance is 55.438 + 147.864 = 203.30165, and 203.30165^0.7 = 41.276098.
TEST(Flip, MaximumColourDistanceIsGreenAgainstBlue) {
  const Lab green = lab_from_xyz(xyz_from_linear_rgb({0, 1, 0}));
  EXPECT_NEAR(green.l, 87.73621066, 1e-7);
  EXPECT_NEAR(green.a, -86.17870509, 1e-7);
  EXPECT_NEAR(green.b, 83.18256604, 1e-7);
  EXPECT_NEAR(
      hyab(hunt_adjusted(green), hunt_adjusted(lab_from_xyz(xyz_from_linear_rgb({0, 0, 1})))),
      203.3016546, 1e-6);
  EXPECT_NEAR(flip_max_colour_distance(), 41.27609841, 1e-7);
}

// The remapping, on both sides of its knee pc cmax = 16.5104:
//   black against white: HyAB 100, 100^0.7 = 25.1189 above the knee, so
//   0.95 + (25.1189 - 16.5104) / (41.2761 - 16.5104) * 0.05 = 0.967380;
//   grey 0.5 against 0.25: L* 76.0693 and 57.0755, HyAB 18.99384,
//   18.99384^0.7 = 7.85247 below the knee, so 7.85247 * 0.95 / 16.5104 =
//   0.451850.
TEST(Flip, ColourErrorMapsBelowAndAboveTheKnee) {
  EXPECT_NEAR(flip_colour_error(100.0), 0.9673797615, 1e-9);
  EXPECT_NEAR(flip_colour_error(18.993840120), 0.4518496178, 1e-9);
  EXPECT_EQ(flip_colour_error(0.0), 0.0);
  EXPECT_NEAR(flip_colour_error(203.3016546), 1.0, 1e-8);
}

// Uniform images have no edges or points, and the normalised spatial
// filters leave them unchanged, so FLIP is the colour error of the two
// colours alone at every pixel. The feature error is not exactly 0: summed
// in float, a derivative filter leaves a uniform image a response of a few
// ulps (~1e-7), which the square root of qf = 0.5 lifts to a feature error
// f up to ~3e-4, and c^(1 - f) moves c by c |ln c| f <= 0.37 f ~ 1.1e-4:
// hence 2e-4 (the reference implementation sums the same way).
constexpr double kUniformTolerance = 2e-4;
TEST(Flip, UniformImagesGiveTheColourErrorOfTheirColours) {
  struct Case {
    double ref[3], test[3], expected;
  };
  // The expected values: HyAB of the Hunt-adjusted L*a*b* colours, then
  // the remapping above (grey 0.2 against 0.21: L* 51.8372 against 52.9495,
  // HyAB 1.11228, 1.11228^0.7 * 0.95 / 16.5104 = 0.0619892; red against
  // blue: HyAB 93.5825, above the knee, 0.965079; grey 0.5 against
  // (0.5, 0.4, 0.5): HyAB 13.0723, 0.347866).
  const Case cases[] = {{{0, 0, 0}, {1, 1, 1}, 0.9673797615},
                        {{0.5, 0.5, 0.5}, {0.25, 0.25, 0.25}, 0.4518496178},
                        {{0.2, 0.2, 0.2}, {0.21, 0.21, 0.21}, 0.0619891553},
                        {{1, 0, 0}, {0, 0, 1}, 0.9650790225},
                        {{0.5, 0.5, 0.5}, {0.5, 0.4, 0.5}, 0.3478659142}};
  for (const Case& c : cases) {
    const FlipImage map = flip_map(uniform(24, 20, c.test[0], c.test[1], c.test[2]),
                                   uniform(24, 20, c.ref[0], c.ref[1], c.ref[2]));
    for (float e : map.error) ASSERT_NEAR(e, c.expected, kUniformTolerance) << c.expected;
    EXPECT_NEAR(mean_flip(map), c.expected, kUniformTolerance);
  }
}

// HDR-FLIP of uniform grey images: the reference's largest and median
// luminance are both its grey g, so start = stop = log2(x_max / g) with
// x_max = 2.1188723 (ACES(x_max) = 0.85), two equal exposures, and the
// reference exposes to grey 0.85 exactly. A test at 2 g exposes to
// ACES(2 x_max) = 0.939674, HyAB |L*(0.85) - L*(0.939674)| = 3.73572,
// colour error 0.144753; at g / 2 to ACES(x_max / 2) = 0.690267, HyAB
// 7.36584, 0.232820. The same for any g: the exposures follow the reference.
TEST(Flip, HdrOfUniformGreyIsLdrAfterExposingTheReferenceTo085) {
  for (const float g : {0.01f, 1.0f, 300.0f}) {
    const ExposureRange e = hdr_exposures(uniform(16, 16, g, g, g));
    EXPECT_NEAR(e.start, std::log2(2.118872324 / g), 1e-6);
    EXPECT_EQ(e.start, e.stop);
    EXPECT_EQ(e.count, 2);
    EXPECT_NEAR(aces_tone_map(std::exp2(e.start) * g), 0.85, 1e-9);
    for (auto [k, expected] : {std::pair{2.0, 0.1447527575}, std::pair{0.5, 0.2328200726}}) {
      const FlipImage map =
          flip_map(uniform(16, 16, k * g, k * g, k * g), uniform(16, 16, g, g, g), hdr());
      for (float v : map.error) ASSERT_NEAR(v, expected, kUniformTolerance) << g << " " << k;
    }
  }
}

// ---- Against the reference implementation ----------------------------------------------

// The values NVlabs/flip's C++ tool (commit 1eb247cabcf2862c2c8207ab15314304394132b9,
// v1.6, default options: 67 ppd, ACES) prints for the pairs under data/flip
// (README.md there), and its error maps in grey (-nm: byte round(255 e)).
// The means it prints are rounded to 6 decimals (5e-7) and summed in float:
// over 4032 to 16384 values near 0.1 to 0.2 each addition rounds to half an
// ulp of the running sum, ~3e-5 at worst, and the mean's error, a random
// walk of those over n additions divided by n, ~3e-7; with the per-pixel
// differences of float against double colour arithmetic (~1e-7 after
// averaging) that makes 2e-6. Each pixel: within the half step of 1/255 of
// the tool's byte, plus 1e-5 for a value on a rounding boundary.
struct ReferenceCase {
  const char *reference, *test, *tool_map;
  FlipRange range;
  double mean;
  std::optional<ExposureRange> exposures;  // given to both (the tool's -cstart -cstop -n)
};

FlipImage flip_of_files(const ReferenceCase& c) {
  auto load = [&](const char* name) {
    const Image image = read_image(kData + name);
    return c.range == FlipRange::kLdr ? srgb_decoded(image) : image;  // PNG or EXR
  };
  FlipOptions o;
  o.range = c.range;
  o.exposures = c.exposures;
  return flip_map(load(c.test), load(c.reference), o);
}

TEST(Flip, AgreesWithTheReferenceImplementation) {
  const ReferenceCase cases[] = {
      {"colour-reference.png", "colour-test.png", "reference-tool-colour-ldr.png", FlipRange::kLdr,
       0.094977, std::nullopt},
      {"colour-reference.exr", "colour-test.exr", "reference-tool-colour-hdr.png", FlipRange::kHdr,
       0.195041, std::nullopt},
      {"sphere-truth.png", "sphere-none.png", "reference-tool-sphere-ldr.png", FlipRange::kLdr,
       0.059663, std::nullopt},
      // The tool's own exposures for this render are broken (its median
      // luminance is 0: stop = inf, -2147483648 exposures, mean 0), so both
      // get Penumbra's, which the next test checks.
      {"sphere-truth.exr", "sphere-none.exr", "reference-tool-sphere-hdr.png", FlipRange::kHdr,
       0.068132, ExposureRange{1.4072850495924476, 2.2529749826197567, 2}}};
  for (const ReferenceCase& c : cases) {
    const FlipImage map = flip_of_files(c);
    EXPECT_NEAR(mean_flip(map), c.mean, 2e-6) << c.test;
    const Image tool = read_image(kData + c.tool_map);
    ASSERT_EQ(tool.width, map.width);
    ASSERT_EQ(tool.height, map.height);
    for (int y = 0; y < map.height; ++y)
      for (int x = 0; x < map.width; ++x)
        ASSERT_NEAR(map.at(x, y), tool.at(x, y, 0), 0.5 / 255.0 + 1e-5)
            << c.test << " at " << x << "," << y;
  }
}

// The tool printed start -3.2582, stop 1.5808 and 5 exposures for the
// colour pair, and start 1.4073 for the sphere (its stop being the infinite
// one above; Penumbra's comes from the lit pixels). Tolerance: the 4
// printed decimals (5e-5) plus the luminance weights, which the tool rounds
// to BT.709's 0.2126, 0.7152, 0.0722 where Penumbra takes the Y row of its
// sRGB matrix (0.212637, 0.715183, 0.072180): at most 2.8e-4 of a
// luminance (the blue weight), log2(1 + 2.8e-4) = 4e-4 stops.
TEST(Flip, ExposuresAgreeWithTheReferenceImplementation) {
  constexpr double kStops = 5e-5 + 4e-4;
  const ExposureRange colour = hdr_exposures(read_image(kData + "colour-reference.exr"));
  EXPECT_NEAR(colour.start, -3.2582, kStops);
  EXPECT_NEAR(colour.stop, 1.5808, kStops);
  EXPECT_EQ(colour.count, 5);
  const ExposureRange sphere = hdr_exposures(read_image(kData + "sphere-truth.exr"));
  EXPECT_NEAR(sphere.start, 1.4073, kStops);
  EXPECT_DOUBLE_EQ(sphere.start, 1.4072850495924476);
  EXPECT_DOUBLE_EQ(sphere.stop, 2.2529749826197567);
  EXPECT_EQ(sphere.count, 2);
}

// ---- Filters ---------------------------------------------------------------------------

// At 67.02 ppd: the widest CSF Gaussian (b = 0.04 deg^2) has a standard
// deviation of sqrt(0.04 / (2 pi^2)) = 0.045016 degrees = 3.017 pixels, so
// the spatial radius is ceil(9.051) = 10; the features' sigma is
// 0.5 * 0.082 * 67.02 = 2.748 pixels, radius ceil(8.243) = 9.
TEST(Flip, FiltersHaveThePapersRadiiAndNormalisation) {
  EXPECT_NEAR(kFlipDefaultPixelsPerDegree, 67.02064328, 1e-8);
  EXPECT_NEAR(pixels_per_degree(0.7, 3840, 0.7), kFlipDefaultPixelsPerDegree, 1e-12);
  const SpatialFilters s = spatial_filters(kFlipDefaultPixelsPerDegree);
  const FeatureFilters f = feature_filters(kFlipDefaultPixelsPerDegree);
  EXPECT_EQ(s.radius, 10);
  EXPECT_EQ(f.radius, 9);
  EXPECT_EQ(flip_support_radius(kFlipDefaultPixelsPerDegree), 10);
  auto sum = [](const std::vector<float>& v) {
    double t = 0;
    for (float x : v) t += x;
    return t;
  };
  auto part = [](const std::vector<float>& v, bool positive) {
    double t = 0;
    for (float x : v)
      if ((x > 0) == positive && x != 0) t += x;
    return t;
  };
  EXPECT_NEAR(sum(s.achromatic), 1.0, 1e-6);
  EXPECT_NEAR(sum(s.red_green), 1.0, 1e-6);
  // The 2D blue-yellow filter is the sum of two separable pairs.
  const double by =
      sum(s.blue_yellow[0]) * sum(s.blue_yellow[0]) + sum(s.blue_yellow[1]) * sum(s.blue_yellow[1]);
  EXPECT_NEAR(by, 1.0, 1e-6);
  EXPECT_NEAR(sum(f.gaussian), 1.0, 1e-6);
  for (const auto* d : {&f.first_derivative, &f.second_derivative}) {
    EXPECT_NEAR(part(*d, true), 1.0, 1e-6);
    EXPECT_NEAR(part(*d, false), -1.0, 1e-6);
    ASSERT_EQ(d->size(), 2u * 9u + 1u);
  }
  EXPECT_THROW(spatial_filters(0.0), std::invalid_argument);
}

// ---- Properties ------------------------------------------------------------------------

TEST(Flip, IdenticalImagesGiveZeroEverywhere) {
  const Image image = random_image(40, 30, 1.0, 7);
  for (const FlipOptions& o : {FlipOptions{}, hdr()}) {
    const FlipImage map = flip_map(image, image, o);
    for (float e : map.error) ASSERT_EQ(e, 0.0f);
    EXPECT_EQ(mean_flip(map), 0.0);
    const Interval i = mean_flip_interval(map);
    EXPECT_EQ(i.low, 0.0);
    EXPECT_EQ(i.high, 0.0);
  }
}

TEST(Flip, MapStaysInZeroOne) {
  // Noise against noise (the largest colour and feature differences) and
  // HDR values up to 1000, NaN, Inf and negative values among them.
  Image a = random_image(48, 40, 1.0, 1), b = random_image(48, 40, 1.0, 2);
  Image c = random_image(48, 40, 1000.0, 3), d = random_image(48, 40, 1000.0, 4);
  d.pixels[5] = std::nanf(""), d.pixels[9] = INFINITY, d.pixels[13] = -3.0f;
  for (const auto& [t, r, o] : {std::tuple{a, b, FlipOptions{}}, std::tuple{c, d, hdr()},
                                std::tuple{d, c, FlipOptions{}}}) {
    const FlipImage map = flip_map(t, r, o);
    for (float e : map.error) {
      ASSERT_GE(e, 0.0f);
      ASSERT_LE(e, 1.0f);
    }
  }
}

// A change to one pixel of the test reaches at most flip_support_radius
// pixels (Chebyshev) in the map: outside that square the map is the same to
// the bit. HDR too, as the exposures come from the reference alone. Near a
// corner too, where the clamped edge repeats the changed pixel.
TEST(Flip, OnePixelChangeStaysWithinTheFiltersSupport) {
  const Image reference = random_image(64, 56, 1.0, 11);
  const Image test = random_image(64, 56, 1.0, 12);
  for (const double ppd : {kFlipDefaultPixelsPerDegree, 30.0}) {
    const int r = flip_support_radius(ppd);
    for (const auto& [x0, y0] : {std::pair{30, 25}, std::pair{2, 1}})
      for (FlipOptions o : {FlipOptions{}, hdr()}) {
        o.pixels_per_degree = ppd;
        const FlipImage before = flip_map(test, reference, o);
        Image changed = test;
        changed.at(x0, y0, 1) = 1.0f - changed.at(x0, y0, 1);
        const FlipImage after = flip_map(changed, reference, o);
        int moved_at_edge = 0;
        for (int y = 0; y < 56; ++y)
          for (int x = 0; x < 64; ++x) {
            const int d = std::max(std::abs(x - x0), std::abs(y - y0));
            if (d > r)
              ASSERT_EQ(before.at(x, y), after.at(x, y)) << x << "," << y << " ppd " << ppd;
            else if (d == r && before.at(x, y) != after.at(x, y))
              ++moved_at_edge;
          }
        EXPECT_NE(before.at(x0, y0), after.at(x0, y0));
        // The radius is tight: the blue-yellow filter reaches its last ring.
        EXPECT_GT(moved_at_edge, 0) << ppd;
      }
  }
}

// A larger colour difference at a pixel gives a larger FLIP there: a grey
// pixel brightened step by step against a grey reference (both the colour
// and the feature error grow, and colour^(1 - feature) grows with both).
TEST(Flip, LargerDifferenceGivesLargerFlip) {
  const Image reference = uniform(32, 32, 0.3, 0.3, 0.3);
  for (const FlipOptions& o : {FlipOptions{}, hdr()}) {
    double last = 0.0;
    for (double v = 0.32; v <= 1.0; v += 0.04) {
      Image test = reference;
      for (int c = 0; c < 3; ++c) test.at(16, 16, c) = float(v);
      const double e = flip_map(test, reference, o).at(16, 16);
      EXPECT_GT(e, last) << v;
      last = e;
    }
  }
  // And in colour alone: the red channel raised at one pixel.
  double last = 0.0;
  for (double v = 0.35; v <= 1.0; v += 0.05) {
    Image test = reference;
    test.at(16, 16, 0) = float(v);
    const double e = flip_map(test, reference).at(16, 16);
    EXPECT_GT(e, last) << v;
    last = e;
  }
}

// HDR-FLIP is, per pixel, the largest LDR-FLIP over its exposures of the
// images exposed by 2^c, ACES tone mapped and clamped (the HDR-FLIP paper,
// section 3). For images within the LDR range the reference exposes its
// largest luminance to 0.85 first, so HDR-FLIP is not LDR-FLIP of the
// images as given, but never below LDR-FLIP at any of its exposures.
TEST(Flip, HdrIsTheLargestLdrOverTheExposures) {
  const Image reference = random_image(40, 32, 1.0, 21), test = random_image(40, 32, 1.0, 22);
  const FlipImage h = flip_map(test, reference, hdr());
  ASSERT_GE(h.exposures.count, 2);
  EXPECT_EQ(h.exposures.count, std::max(2, int(std::ceil(h.exposures.stop - h.exposures.start))));
  std::vector<float> largest(h.error.size(), 0.0f);
  auto exposed = [](Image image, double c) {
    for (float& v : image.pixels) v = float(std::clamp(aces_tone_map(std::exp2(c) * v), 0.0, 1.0));
    return image;
  };
  for (int i = 0; i < h.exposures.count; ++i) {
    const double c = h.exposures.exposure(i);
    const FlipImage l = flip_map(exposed(test, c), exposed(reference, c));
    for (std::size_t k = 0; k < l.error.size(); ++k) largest[k] = std::max(largest[k], l.error[k]);
  }
  for (std::size_t k = 0; k < largest.size(); ++k) ASSERT_NEAR(h.error[k], largest[k], 1e-6);
  // Scaling both images leaves HDR-FLIP alone (the exposures follow):
  // exactly so for a power of 2.
  Image r4 = reference, t4 = test;
  for (float& v : r4.pixels) v *= 4.0f;
  for (float& v : t4.pixels) v *= 4.0f;
  const FlipImage h4 = flip_map(t4, r4, hdr());
  EXPECT_NEAR(h4.exposures.start, h.exposures.start - 2.0, 1e-12);
  for (std::size_t k = 0; k < h.error.size(); ++k) ASSERT_NEAR(h4.error[k], h.error[k], 1e-6);
}

// A reference that is mostly black (a render's background) has median
// luminance 0; the stop exposure then comes from the median of its lit
// pixels, where the reference implementation's would be infinite.
TEST(Flip, MostlyBlackReferenceTakesItsStopFromTheLitPixels) {
  Image reference = uniform(10, 10, 0.0, 0.0, 0.0);
  for (int x = 0; x < 10; ++x)
    for (int y = 0; y < 3; ++y)
      for (int c = 0; c < 3; ++c) reference.at(x, y, c) = float(1 + y);  // 10 each of 1, 2, 3
  const ExposureRange e = hdr_exposures(reference);
  const double x_max = 2.118872324;
  EXPECT_NEAR(e.start, std::log2(x_max / 3.0), 1e-6);
  EXPECT_NEAR(e.stop, std::log2(x_max / 2.0), 1e-6);  // element 15 of 30 sorted
  EXPECT_EQ(e.count, 2);
  const ExposureRange black = hdr_exposures(uniform(4, 4, 0, 0, 0));
  EXPECT_EQ(black.start, 0.0);
  EXPECT_EQ(black.count, 2);
}

TEST(Flip, MismatchedImagesAreRefused) {
  EXPECT_THROW(flip_map(uniform(4, 4, 0, 0, 0), uniform(4, 5, 0, 0, 0)), ImageMismatch);
  Image grey{4, 4, {"Y"}, std::vector<float>(16, 0.5f)};
  EXPECT_THROW(flip_map(grey, grey), ImageMismatch);
}

// ---- The interval ---------------------------------------------------------------------

// The band bootstrap: an interval around the mean, drawn from the same
// bands as comparison_intervals (16 bands of 8 rows at 128 px), wider for
// an error that lives in a few rows than for one spread evenly.
TEST(Flip, IntervalComesFromBandsOfRows) {
  FlipImage even;
  even.width = even.height = 128;
  even.error.assign(128 * 128, 0.1f);
  const Interval flat = mean_flip_interval(even);
  EXPECT_NEAR(flat.low, double(0.1f), 1e-12);
  EXPECT_NEAR(flat.high, double(0.1f), 1e-12);
  FlipImage banded = even;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 128; ++x) banded.error[std::size_t(y) * 128 + x] = 0.9f;
  const double mean = mean_flip(banded);
  EXPECT_NEAR(mean, 0.2, 1e-6);
  const Interval i = mean_flip_interval(banded);
  EXPECT_LT(i.low, mean);
  EXPECT_GT(i.high, mean);
  // Two of 16 bands hold the error: a resample holds k of them, k ~
  // Binomial(16, 1/8), mean 0.1 + 0.05 k; P(k = 0) = 0.12 and P(k <= 4) =
  // 0.96, so the 2.5 % and 97.5 % points are k = 0 and k = 5: [0.1, 0.35].
  EXPECT_NEAR(i.low, 0.1, 0.011);
  EXPECT_NEAR(i.high, 0.35, 0.051);
}

// ---- The colour map --------------------------------------------------------------------

TEST(Flip, MagmaRunsFromBlackToPaleYellow) {
  EXPECT_EQ(magma_rgb8(0.0), (std::array<unsigned char, 3>{0, 0, 4}));
  EXPECT_EQ(magma_rgb8(1.0), (std::array<unsigned char, 3>{252, 253, 191}));
  EXPECT_EQ(magma_rgb8(-1.0), magma_rgb8(0.0));
  EXPECT_EQ(magma_rgb8(std::nan("")), magma_rgb8(0.0));
  EXPECT_EQ(magma_rgb8(std::vector<float>{0.0f, 1.0f}).size(), 6u);
}

}  // namespace
}  // namespace penumbra
