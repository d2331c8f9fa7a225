// Measuring a test image against a reference: the one function behind
// `penumbra compare`, a study's comparison rows and agreement rows, the
// calibration table, the ground truths' convergence checks and the interplay
// section. Each asks for the metrics it reports (MeasureOptions); the
// numbers do not depend on what else is asked for.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/flip.h"
#include "analysis/intervals.h"
#include "analysis/metrics.h"
#include "image/image.h"

namespace penumbra {

// Where an image's coverage (A: 1 object, 0 background) comes from. Every
// Penumbra render has an A channel; another renderer's PNG may not.
enum class CoverageSource {
  kAlpha,       // its own A channel
  kMask,        // MeasureOptions::mask: its A channel, else its first
  kThreshold,   // the lit region: mean of R, G, B >= threshold * scale
  kEveryPixel,  // none (MeasureOptions::every_pixel): no profile
  kMissing,     // none and nothing to make it from
  kNoScale,     // a threshold, but no scale to multiply it by
};

struct MeasureOptions {
  // albedo * E / pi of the scene, W m^-2 sr^-1: the unit of the profile and
  // view metrics and of a threshold. NaN: unknown (no profile).
  double scale = std::numeric_limits<double>::quiet_NaN();
  // The coverage of an image without an A channel, in this order of
  // preference: the mask (same size as the images), then the threshold.
  const Image* mask = nullptr;
  std::optional<double> threshold;
  // Image metrics over every pixel with the usual (unmasked) SSIM, and no
  // coverage needed: a side without one gets no profile.
  bool every_pixel = false;
  // What to compute besides the profile metrics: the paired bootstrap
  // (most of the cost), the image metrics, the viewer's side, and the
  // shadow metrics of a low-poly render.
  bool intervals = true;
  bool image = true;
  bool view = true;
  bool shadows = false;
  // With `image`: mean HDR-FLIP of the linear radiance over every pixel at
  // FLIP's default 67.02 pixels per degree, and its interval.
  bool flip = false;
};

// Why there is no profile (nor view metrics or intervals).
enum class ProfileMissing {
  kNo,          // there is one
  kNoCoverage,  // an image has no coverage (every_pixel without mask or threshold)
  kNoTheta,     // neither image has the analysis.theta channel of a Penumbra render
  kNoScale,     // no albedo*E/pi
};

// What was measured. Metrics not asked for keep their zero defaults; those
// asked for but impossible (profile_missing) are NaN.
struct Measurement {
  ProfileMetrics profile;
  ImageMetrics image;
  ViewMetrics view;
  std::optional<ShadowMetrics> shadow;
  ComparisonIntervals intervals;
  ProfileMissing profile_missing = ProfileMissing::kNo;
  CoverageSource test_coverage = CoverageSource::kAlpha;
  CoverageSource reference_coverage = CoverageSource::kAlpha;
};

// How `image` gets its coverage under `options` (kMissing and kNoScale when
// it cannot: measure() refuses those).
CoverageSource coverage_source(const Image& image, const MeasureOptions& options);

// The level a threshold coverage compares radiance with (W m^-2 sr^-1).
double threshold_level(const MeasureOptions& options);

// `test` against `reference`, both with R, G and B and of one size. The
// analysis channels (analysis.theta, analysis.view) come from whichever
// image has them, the reference first: both show the same base points.
// Throws std::invalid_argument when the sizes differ or a side's coverage
// is kMissing or kNoScale. `flip_map`, where given, receives the HDR-FLIP
// map behind the mean FLIP (left empty where none was computed), so that a
// caller that also draws it need not compute it again.
Measurement measure(const Image& test, const Image& reference, const MeasureOptions& options,
                    FlipImage* flip_map = nullptr);

// R, G, B: test - reference (W m^-2 sr^-1); A: the smaller coverage of the
// two as `options` gives it (1 for a side without one).
Image difference_image(const Image& test, const Image& reference, const MeasureOptions& options);

// What differs between two renders' scenes (their penumbra:scene JSON) that
// makes them incomparable: camera, light, shape or height function (not the
// representation, method, tessellation, bump filter or sampling). JSON
// pointers two levels deep (/camera/right), the shape first; none when
// they match.
std::vector<std::string> scene_differences(const nlohmann::json& reference,
                                           const nlohmann::json& test);

}  // namespace penumbra
