// `penumbra calibrate`: the smooth, bump and displacement versions of a
// cylinder and a sphere rendered by the evaluator, POV-Ray and Blender
// Cycles, compared pairwise, with the bounds of the renderer issue.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/metrics.h"
#include "renderers/renderers.h"
#include "util/parallel.h"

namespace penumbra {

struct CalibrationOptions {
  std::string output_dir;  // renders/, calibration.{json,csv,md} go here
  std::string scenes_dir;  // holds cylinder.json and sphere.json
  // Renders at once and threads per render (util/parallel.h).
  Parallelism parallelism = resolve_parallelism(1);
  double timeout_s = 600.0;                     // per external render
  int blender_spp = 64;                         // Cycles samples per pixel (its noise, not ours)
  std::vector<std::string> sets;                // overrides applied to both base scenes
  std::function<void(const std::string&)> log;  // one line per finished render
};

// A single bound: `value` must be <= `bound` (or >= for a minimum).
struct CalibrationCheck {
  std::string name;  // what is measured, with its unit
  double value = 0.0;
  double bound = 0.0;
  bool minimum = false;  // true: value >= bound passes
  bool pass = false;
};

struct CalibrationRow {
  std::string shape, representation, test, reference;  // test/reference: "renderer:method"
  ImageMetrics image;
  ProfileMetrics profile;
  std::vector<CalibrationCheck> checks;  // empty: measured and reported only
  std::string note;                      // why there is no bound, or what explains a residual
  std::string missing;                   // a render this row needs failed: why
};

struct CalibrationRender {
  std::string label, renderer, file;
  double seconds = 0.0;  // wall time of that renderer
  // The evaluator on the same scene and sample count (for external renderers
  // its geometry pass is exactly that render).
  double evaluator_seconds = 0.0;
  std::string error;  // empty on success
};

struct CalibrationResult {
  std::vector<CalibrationRender> renders;
  std::vector<CalibrationRow> rows;
  bool all_rendered() const;
  bool all_pass() const;  // every check of every row passes (rows with missing renders fail)
  nlohmann::json to_json() const;
};

CalibrationResult run_calibration(const CalibrationOptions& options);

// Writes calibration.json, calibration.csv and calibration.md into `dir`.
void write_calibration_reports(const CalibrationResult& result, const std::string& dir);
// The agreement table as plain text (for the terminal).
std::string calibration_table(const CalibrationResult& result);

}  // namespace penumbra
