// `penumbra compare`: reads two images (and a mask), checks that they can be
// compared, and prints what measure() (analysis/measure.h) measures, as text
// or JSON, with units and intervals; with --flip also mean FLIP
// (analysis/flip.h) and its map.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "analysis/flip.h"
#include "analysis/magma.h"
#include "analysis/measure.h"
#include "analysis/metrics_json.h"
#include "cli/command.h"
#include "image/image_io.h"
#include "util/strict_json.h"

namespace penumbra {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct CompareArgs {
  std::string reference, test;
  std::string difference;  // -o: the difference image
  bool json = false;
  double scale = 0.0;
  double max_rmse = -1.0;
  // The coverage of an image without an A channel (another renderer's PNG):
  // a mask image, or the lit region, radiance >= threshold * albedo*E/pi.
  std::string mask;
  std::optional<double> threshold;
  bool no_mask = false;     // image metrics over every pixel, the usual SSIM
  bool same_scene = false;  // different penumbra:scene geometry: exit 2, not a warning
  // FLIP: ldr, hdr, auto or off; not given: off, or auto with --flip-map.
  std::optional<std::string> flip;
  std::optional<double> ppd;  // FLIP's pixels per degree
  std::string flip_map;       // .png (magma) or .exr (float)
};

// The images and how measure() is to treat them.
struct Inputs {
  Image reference, test;
  std::optional<Image> mask;
  MeasureOptions options;
};

Image read_image_checked(const std::string& path) {
  return read_image(path);  // InputError naming the file: missing, not a file, unreadable
}

void require_rgb(const Image& image, const std::string& path) {
  for (const char* name : {"R", "G", "B"})
    if (image.channel_index(name) < 0)
      throw UsageError(fmt::format("{}: no {} channel (compare needs R, G and B; it has {})", path,
                                   name, fmt::join(image.channels, ", ")));
}

// albedo * E / pi of the first of `paths` whose penumbra:scene gives one; NaN
// when none carries the metadata (an image from another renderer).
double radiance_scale_of(const std::vector<std::string>& paths) {
  for (const std::string& path : paths) {
    const std::string text = read_image_attribute(path, "penumbra:scene");
    if (text.empty()) continue;
    const std::string origin = path + " (penumbra:scene metadata)";
    return radiance_scale(scene_from_json(parse_json_text(text, origin), origin));
  }
  return kNaN;
}

// Says why a side cannot get its coverage (the reference first, as measure()
// would find it), or what is wrong with the mask it gets.
void check_coverage(const Image& image, const std::string& path, const CompareArgs& a,
                    const Inputs& in) {
  switch (coverage_source(image, in.options)) {
    case CoverageSource::kMask:
      if (in.mask->width != image.width || in.mask->height != image.height)
        throw UsageError(fmt::format("--mask {} is {}x{} but {} is {}x{}", a.mask, in.mask->width,
                                     in.mask->height, path, image.width, image.height));
      if (in.mask->channels.empty())
        throw UsageError(fmt::format("--mask {}: no channels", a.mask));
      return;
    case CoverageSource::kNoScale:
      throw UsageError(fmt::format(
          "--threshold is a fraction of albedo*E/pi, which neither image's penumbra:scene "
          "gives ({} has none): add --scale",
          path));
    case CoverageSource::kMissing:
      throw UsageError(fmt::format(
          "{}: no A (coverage) channel and no --mask FILE or --threshold given (or --no-mask for "
          "image metrics over every pixel)",
          path));
    default:
      return;
  }
}

// Reads both images (and --mask) and checks that they fit.
Inputs read_inputs(const CompareArgs& a) {
  Inputs in{read_image_checked(a.reference), read_image_checked(a.test), std::nullopt, {}};
  require_rgb(in.reference, a.reference);
  require_rgb(in.test, a.test);
  if (in.reference.width != in.test.width || in.reference.height != in.test.height)
    throw UsageError(fmt::format("{} is {}x{} but {} is {}x{}", a.reference, in.reference.width,
                                 in.reference.height, a.test, in.test.width, in.test.height));
  in.options.scale = a.scale > 0.0 ? a.scale : radiance_scale_of({a.reference, a.test});
  if (!a.mask.empty()) in.mask = read_image_checked(a.mask);
  in.options.mask = in.mask ? &*in.mask : nullptr;
  in.options.threshold = a.threshold;
  in.options.every_pixel = a.no_mask;
  check_coverage(in.reference, a.reference, a, in);
  check_coverage(in.test, a.test, a, in);
  return in;
}

// Warns (or, with --same-scene, refuses) when the two images show different
// scenes: their metrics would compare unrelated images.
void check_same_scene(const CompareArgs& a, std::ostream& err) {
  const std::string reference = read_image_attribute(a.reference, "penumbra:scene");
  const std::string test = read_image_attribute(a.test, "penumbra:scene");
  if (reference.empty() || test.empty()) return;
  const std::vector<std::string> where =
      scene_differences(parse_json_text(reference, a.reference + " (penumbra:scene)"),
                        parse_json_text(test, a.test + " (penumbra:scene)"));
  if (where.empty()) return;
  const std::size_t shown = std::min<std::size_t>(where.size(), 8);
  const std::string list =
      fmt::format("{}{}", fmt::join(where.begin(), where.begin() + long(shown), ", "),
                  where.size() > shown ? fmt::format(" and {} more", where.size() - shown) : "");
  const std::string message = fmt::format(
      "{} and {} show different scenes (penumbra:scene differs at {})", a.reference, a.test, list);
  if (a.same_scene) throw UsageError(message + "; --same-scene");
  err << "penumbra: warning: " << printable(message, 2000)
      << "; the metrics compare unrelated images\n";
}

// -o: OpenEXR, writable, and not one of the images compared.
void check_difference_output(const CompareArgs& a) {
  if (a.difference.empty()) return;
  check_extension(a.difference, ".exr", "-o", ": the difference is signed float radiance");
  for (const std::string& input : {a.reference, a.test, a.mask}) {
    std::error_code ec;
    if (!input.empty() && fs::equivalent(a.difference, input, ec))
      throw UsageError(fmt::format("-o {}: is {}, an input of the comparison", a.difference,
                                   input == a.mask ? "the --mask image" : input));
  }
  check_writable(a.difference);
}

bool is_exr(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext == ".exr";
}

// The FLIP that --flip asks for, none when off. auto: HDR-FLIP when both
// images are OpenEXR (linear radiance), LDR-FLIP otherwise.
std::optional<FlipRange> flip_range(const CompareArgs& a) {
  const std::string mode = a.flip.value_or(a.flip_map.empty() ? "off" : "auto");
  if (mode == "off") return std::nullopt;
  if (mode == "ldr") return FlipRange::kLdr;
  if (mode == "hdr") return FlipRange::kHdr;
  return is_exr(a.reference) && is_exr(a.test) ? FlipRange::kHdr : FlipRange::kLdr;
}

// --flip-map and --ppd need FLIP; the map is .png or .exr, writable and not
// an input. Checked before anything is read.
void check_flip_args(const CompareArgs& a) {
  if (!flip_range(a)) {
    if (!a.flip_map.empty()) throw UsageError("--flip-map needs FLIP, and --flip is off");
    if (a.ppd) throw UsageError("--ppd is FLIP's viewing distance: add --flip");
    return;
  }
  if (a.flip_map.empty()) return;
  if (!is_exr(a.flip_map))
    check_extension(a.flip_map, ".png", "--flip-map", " (magma colours) or .exr (float values)");
  for (const std::string& input : {a.reference, a.test, a.mask, a.difference}) {
    std::error_code ec;
    if (!input.empty() && fs::equivalent(a.flip_map, input, ec))
      throw UsageError(
          fmt::format("--flip-map {}: is {}, already a file of the comparison", a.flip_map, input));
  }
  check_writable(a.flip_map);
}

// FLIP of the comparison: its map, mean and interval, and how each image
// was made linear (EXR holds linear values, other formats sRGB-encoded ones).
struct FlipResult {
  FlipImage map;
  double mean = 0.0;
  Interval interval;
  std::string encoding[2];  // reference, test
};

FlipResult compare_flip(const CompareArgs& a, const Inputs& in, FlipRange range) {
  auto linear = [](const Image& image, const std::string& path) {
    return is_exr(path) ? image : srgb_decoded(image);
  };
  FlipOptions options;
  options.range = range;
  options.pixels_per_degree = a.ppd.value_or(kFlipDefaultPixelsPerDegree);
  FlipResult r{flip_map(linear(in.test, a.test), linear(in.reference, a.reference), options),
               0.0,
               {},
               {is_exr(a.reference) ? "linear" : "srgb", is_exr(a.test) ? "linear" : "srgb"}};
  r.mean = mean_flip(r.map);
  r.interval = mean_flip_interval(r.map);
  return r;
}

void write_flip_map(const CompareArgs& a, const FlipResult& f) {
  if (a.flip_map.empty()) return;
  if (!is_exr(a.flip_map)) {
    write_png_rgb8(a.flip_map, f.map.width, f.map.height, magma_rgb8(f.map.error));
    return;
  }
  write_exr(Image{f.map.width, f.map.height, {"Y"}, f.map.error}, a.flip_map,
            {{"penumbra:flip", fmt::format("{} of {} against {}, {:.6g} pixels per degree",
                                           f.map.range == FlipRange::kHdr ? "HDR-FLIP" : "LDR-FLIP",
                                           a.test, a.reference, f.map.pixels_per_degree)}});
}

std::string coverage_text(CoverageSource source, const CompareArgs& a, const MeasureOptions& o) {
  switch (source) {
    case CoverageSource::kMask:
      return "--mask " + a.mask;
    case CoverageSource::kThreshold:
      return fmt::format("--threshold {}: lit where radiance >= {:.6g} W m^-2 sr^-1",
                         o.threshold.value_or(kNaN), threshold_level(o));
    case CoverageSource::kEveryPixel:
      return "none (--no-mask)";
    default:
      return "A channel";
  }
}

// Why the profile and viewer metrics are missing, "" when they are not.
std::string skipped_text(ProfileMissing missing) {
  switch (missing) {
    case ProfileMissing::kNoCoverage:
      return "an image has no coverage (--no-mask without --mask or --threshold)";
    case ProfileMissing::kNoTheta:
      return "neither image has the analysis.theta channel of a Penumbra render";
    case ProfileMissing::kNoScale:
      return "no albedo*E/pi: neither image carries penumbra:scene metadata (give --scale)";
    case ProfileMissing::kNo:
      break;
  }
  return "";
}

// What the printers show: the measurement with its descriptions.
struct Report {
  const CompareArgs& a;
  const Measurement& m;
  double scale;
  std::string coverage[2];  // reference, test
  std::string skipped;
  bool over, pass;
  const FlipResult* flip;  // null without --flip
};

json with_interval(json metrics, const char* key, const Interval& i) {
  auto bound = [](double v) { return std::isfinite(v) ? json(v) : json(); };
  metrics[key] = {bound(i.low), bound(i.high)};
  return metrics;
}

json profile_json_with_intervals(const ProfileMetrics& pm, const ComparisonIntervals& ci) {
  json j = with_interval(profile_metrics_json(pm), "rmse_terminator_ci", ci.rmse_terminator);
  j = with_interval(std::move(j), "max_error_terminator_ci", ci.max_error);
  j = with_interval(std::move(j), "position_error_deg_ci", ci.position_error);
  j = with_interval(std::move(j), "lit_bias_ci", ci.lit_bias);
  j["rmse_terminator_bootstrap_bias"] =
      std::isfinite(ci.rmse_terminator_bias) ? json(ci.rmse_terminator_bias) : json();
  return j;
}

std::string interval_note(const ComparisonIntervals& ci) {
  return fmt::format(
      "intervals: 95 %, paired block bootstrap over {} bands of rows, {} resamples (seed 1), "
      "centred on the estimate: the spread over image regions, not a bias both images share",
      ci.bands, ci.resamples);
}

const char* flip_name(const FlipImage& map) {
  return map.range == FlipRange::kHdr ? "HDR-FLIP" : "LDR-FLIP";
}

json flip_json(const FlipResult& f, const CompareArgs& a) {
  const ExposureRange& e = f.map.exposures;
  json doc = {{"range", f.map.range == FlipRange::kHdr ? "hdr" : "ldr"},
              {"pixels_per_degree", f.map.pixels_per_degree},
              {"pixels", f.map.error.size()},
              {"mean", f.mean},
              {"exposures", f.map.range == FlipRange::kHdr
                                ? json{{"start", e.start}, {"stop", e.stop}, {"count", e.count}}
                                : json()},
              {"encoding", {{"reference", f.encoding[0]}, {"test", f.encoding[1]}}},
              {"map", a.flip_map.empty() ? json() : json(a.flip_map)}};
  return with_interval(std::move(doc), "mean_ci", f.interval);
}

void print_flip(const FlipResult& f, const CompareArgs& a, std::ostream& out) {
  out << fmt::format("FLIP ({}, {:.2f} pixels per degree; mean over every pixel: {}):\n",
                     flip_name(f.map), f.map.pixels_per_degree, f.map.error.size());
  out << fmt::format(
      "  mean FLIP                     {:.6f} [{:.6f}, {:.6f}] (95 % CI; {} bands of rows, {} "
      "resamples)\n",
      f.mean, f.interval.low, f.interval.high, kIntervalBands, kIntervalResamples);
  const ExposureRange& e = f.map.exposures;
  if (f.map.range == FlipRange::kHdr)
    out << fmt::format(
        "  exposures                     {:+.4f} to {:+.4f} stops, {} (from the "
        "reference)\n",
        e.start, e.stop, e.count);
  else
    out << "  exposures                     none (LDR-FLIP: values clamped to [0, 1])\n";
  out << fmt::format("  inputs                        reference {}, test {} (made linear)\n",
                     f.encoding[0], f.encoding[1]);
  if (!a.flip_map.empty())
    out << fmt::format("  map                           {}{}\n", a.flip_map,
                       is_exr(a.flip_map) ? " (float, channel Y)" : " (magma)");
}

const char* ssim_kind(bool no_mask) {
  return no_mask ? "usual SSIM over every pixel (--no-mask): Gaussian 11x11, sigma 1.5, mean "
                   "over windows inside the image, L = reference peak"
                 : "masked SSIM: Gaussian 11x11, sigma 1.5, windows renormalised over pixels "
                   "fully covered in both, L = reference peak";
}

json comparison_json(const Report& r) {
  const bool profiled = r.skipped.empty();
  const ComparisonIntervals& ci = r.m.intervals;
  json image = with_interval(image_metrics_json(r.m.image), "rmse_ci", ci.image_rmse);
  image["ssim_kind"] = ssim_kind(r.a.no_mask);
  json doc = {
      {"reference", r.a.reference},
      {"test", r.a.test},
      {"coverage", {{"reference", r.coverage[0]}, {"test", r.coverage[1]}}},
      {"radiance_scale", std::isfinite(r.scale) ? json(r.scale) : json()},
      {"radiance_scale_unit", "W m^-2 sr^-1 (albedo * E / pi)"},
      {"profile", profiled ? profile_json_with_intervals(r.m.profile, ci) : json()},
      {"image", image},
      {"view", profiled ? with_interval(with_interval(view_metrics_json(r.m.view),
                                                      "rmse_grazing_ci", ci.view_rmse_grazing),
                                        "bias_grazing_ci", ci.view_bias_grazing)
                        : json()},
      {"intervals", profiled ? json(interval_note(ci)) : json()},
      {"pass", r.pass}};
  if (!profiled) doc["profile_skipped"] = r.skipped;
  if (r.flip) doc["flip"] = flip_json(*r.flip, r.a);
  return doc;
}

void print_profile(const ProfileMetrics& pm, const ComparisonIntervals& ci, double scale,
                   std::ostream& out) {
  out << fmt::format(
      "profile (1-degree theta bins, fraction of albedo*E/pi = {:.6g} W m^-2 "
      "sr^-1; {} common bins):\n",
      scale, pm.common_bins);
  out << fmt::format("  RMSE terminator [60,100) deg  {:.6f} [{:.6f}, {:.6f}] (95 % CI)\n",
                     pm.rmse_terminator, ci.rmse_terminator.low, ci.rmse_terminator.high);
  out << fmt::format("  (bootstrap bias of that RMSE  {:+.6f})\n", ci.rmse_terminator_bias);
  out << fmt::format("  RMSE overall                  {:.6f}\n", pm.rmse_overall);
  out << fmt::format("  max error terminator          {:.6f} [{:.6f}, {:.6f}]\n", pm.max_error,
                     ci.max_error.low, ci.max_error.high);
  out << fmt::format("  largest bin step              {:.6f} (reference {:.6f})\n", pm.max_step,
                     pm.reference_max_step);
  out << fmt::format(
      "  terminator position (L<{})  {:.3f} deg (reference {:.3f}, error {:+.3f} [{:+.3f}, "
      "{:+.3f}])\n",
      kDarkLevel, pm.position, pm.reference_position, pm.position_error, ci.position_error.low,
      ci.position_error.high);
  out << fmt::format("  transition width 90%->10%     {:.3f} deg (reference {:.3f})\n", pm.width,
                     pm.reference_width);
  out << fmt::format("  lit-region bias (<60 deg)     {:+.6f} [{:+.6f}, {:+.6f}]\n", pm.lit_bias,
                     ci.lit_bias.low, ci.lit_bias.high);
}

void print_image(const ImageMetrics& im, const ComparisonIntervals& ci, bool no_mask,
                 std::ostream& out) {
  out << fmt::format("image ({}: {}):\n",
                     no_mask ? "every pixel, --no-mask" : "pixels fully covered in both",
                     im.pixels);
  out << fmt::format("  mask IoU (alpha>=0.5)         {:.6f}\n", im.mask_iou);
  out << fmt::format(
      "  RMSE                          {:.6g} [{:.6g}, {:.6g}] W m^-2 sr^-1 (95 % CI)\n", im.rmse,
      ci.image_rmse.low, ci.image_rmse.high);
  out << fmt::format("  max error                     {:.6g} W m^-2 sr^-1\n", im.max_error);
  out << fmt::format("  mean error (test-reference)   {:+.6g} W m^-2 sr^-1\n", im.mean_error);
  out << fmt::format("  reference mean                {:.6g} W m^-2 sr^-1\n", im.reference_mean);
  out << fmt::format("  reference peak (SSIM's L)     {:.6g} W m^-2 sr^-1\n", im.peak);
  out << fmt::format("  SSIM                          {:.6f} ({})\n", im.ssim, ssim_kind(no_mask));
  out << fmt::format("  NaN/Inf values                {}\n", im.nonfinite);
}

void print_view(const ViewMetrics& vm, const ComparisonIntervals& ci, std::ostream& out) {
  out << fmt::format(
      "viewer (lit pixels, theta < {} deg, binned by view angle; {} pixels at [{}, {}) deg):\n",
      kLitEnd, vm.pixels, kGrazingBegin, kGrazingEnd);
  out << fmt::format("  RMSE grazing views            {:.6f} [{:.6f}, {:.6f}] (95 % CI)\n",
                     vm.rmse_grazing, ci.view_rmse_grazing.low, ci.view_rmse_grazing.high);
  out << fmt::format(
      "  bias grazing views            {:+.6f} [{:+.6f}, {:+.6f}] (negative: test darker)\n",
      vm.bias_grazing, ci.view_bias_grazing.low, ci.view_bias_grazing.high);
}

// The text form: every metric of --json, with units and intervals.
void print_comparison(const Report& r, std::ostream& out) {
  out << fmt::format("reference {} (coverage: {})\ntest      {} (coverage: {})\n",
                     printable(r.a.reference, 240), r.coverage[0], printable(r.a.test, 240),
                     r.coverage[1]);
  if (r.skipped.empty())
    print_profile(r.m.profile, r.m.intervals, r.scale, out);
  else
    out << fmt::format("profile and viewer metrics: not computed: {}\n", r.skipped);
  print_image(r.m.image, r.m.intervals, r.a.no_mask, out);
  if (r.skipped.empty()) print_view(r.m.view, r.m.intervals, out);
  if (r.flip) print_flip(*r.flip, r.a, out);
  if (r.skipped.empty()) out << interval_note(r.m.intervals) << "\n";
  if (r.over)
    out << fmt::format("FAIL: profile RMSE {:.6f} above --max-profile-rmse {}\n",
                       r.m.profile.rmse_overall, r.a.max_rmse);
  out << (r.pass ? "pass\n" : "FAIL\n");
}

int compare(const CompareArgs& a, const CommandContext& c) {
  check_difference_output(a);
  check_flip_args(a);
  const Inputs in = read_inputs(a);
  check_same_scene(a, c.err);
  const Measurement m = measure(in.test, in.reference, in.options);
  const std::string skipped = skipped_text(m.profile_missing);
  if (a.max_rmse >= 0.0 && !skipped.empty())
    throw UsageError(fmt::format("--max-profile-rmse: no profile to check: {}", skipped));
  const bool over = a.max_rmse >= 0.0 && !(m.profile.rmse_overall <= a.max_rmse);
  const bool pass = m.image.nonfinite == 0 && !over;
  // No output holds NaN or Inf (image_io.h); the exit status says why.
  if (!a.difference.empty() && m.image.nonfinite > 0)
    c.err << "penumbra: warning: -o " << printable(a.difference, 240)
          << " not written: the images hold NaN or Inf values\n";
  else if (!a.difference.empty())
    write_exr(difference_image(in.test, in.reference, in.options), a.difference,
              {{"penumbra:difference", a.test + " - " + a.reference},
               {"penumbra:radiance_unit", "W m^-2 sr^-1"}});
  std::optional<FlipResult> flip;
  if (const auto range = flip_range(a)) {
    flip = compare_flip(a, in, *range);
    write_flip_map(a, *flip);
  }
  const Report report{a,
                      m,
                      in.options.scale,
                      {coverage_text(m.reference_coverage, a, in.options),
                       coverage_text(m.test_coverage, a, in.options)},
                      skipped,
                      over,
                      pass,
                      flip ? &*flip : nullptr};
  if (a.json)
    c.out << comparison_json(report).dump(2) << "\n";
  else
    print_comparison(report, c.out);
  return pass ? kExitOk : kExitThreshold;
}

void add_coverage_options(CLI::App* cmd, CompareArgs& a) {
  cmd->add_option("--mask", a.mask,
                  "coverage of an image without an A channel: an image of the same size "
                  "(its A channel, else its first; 1 object, 0 background); before --threshold");
  cmd->add_option("--threshold", a.threshold,
                  "coverage of an image without an A channel: its lit region, radiance >= "
                  "FRACTION * albedo*E/pi; alone: 0.05, the profile's dark level (write "
                  "--threshold=F before the images)")
      ->expected(0, 1)
      ->default_str("0.05")
      ->type_name("FRACTION")
      ->check(CLI::Range(0.0, 1e6));
  cmd->add_flag("--no-mask", a.no_mask,
                "image metrics over every pixel, with the usual (unmasked) SSIM");
}

void add_flip_options(CLI::App* cmd, CompareArgs& a) {
  cmd->add_option("--flip", a.flip,
                  "mean FLIP (Andersson et al. 2020, 2021) with its interval: ldr, hdr, off, or "
                  "auto (HDR-FLIP when both images are EXR, else LDR-FLIP); alone: auto; not "
                  "given: off (write --flip=MODE before the images)")
      ->expected(0, 1)
      ->default_str("auto")
      ->type_name("MODE")
      ->check(CLI::IsMember({"ldr", "hdr", "auto", "off"}));
  cmd->add_option("--ppd", a.ppd,
                  "FLIP's viewer: pixels per degree of visual angle (default 67.02: a 0.7 m wide "
                  "3840-pixel monitor seen from 0.7 m)")
      ->type_name("PIXELS")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--flip-map", a.flip_map,
                  "write the FLIP error map: .png in the magma colours, .exr as float (channel "
                  "Y); implies --flip");
}

}  // namespace

Command add_compare_command(CLI::App& app, SharedOptions&) {
  auto a = std::make_shared<CompareArgs>();
  CLI::App* cmd = app.add_subcommand(
      "compare", "terminator-profile and image metrics of TEST against REFERENCE");
  cmd->add_option("reference", a->reference,
                  "reference image (a Penumbra EXR, e.g. displacement, or another renderer's)")
      ->required();
  cmd->add_option("test", a->test, "image to compare (EXR, PNG, TIFF, ...)")->required();
  cmd->add_flag("--json", a->json, "print JSON");
  cmd->add_option("-o,--output", a->difference,
                  "write the difference image (test - reference, R G B; A the smaller "
                  "coverage) as OpenEXR");
  cmd->add_option("--scale", a->scale,
                  "albedo*E/pi in W m^-2 sr^-1 (default: from the penumbra:scene metadata of the "
                  "reference, else of the test)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--max-profile-rmse", a->max_rmse,
                  "exit 3 when the overall profile RMSE exceeds this")
      ->check(CLI::NonNegativeNumber);
  add_coverage_options(cmd, *a);
  add_flip_options(cmd, *a);
  cmd->add_flag("--same-scene", a->same_scene,
                "exit 2 when the images' penumbra:scene show different geometry, camera "
                "or light (default: a warning)");
  return {cmd, [a](const CommandContext& c) { return compare(*a, c); }};
}

}  // namespace penumbra
