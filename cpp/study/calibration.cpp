#include "study/calibration.h"

#include <cmath>
#include <filesystem>
#include <map>

#include <fmt/format.h>

#include "analysis/measure.h"
#include "analysis/metrics_json.h"
#include "image/image_io.h"
#include "scene/scene_json.h"
#include "study/execute.h"
#include "util/files.h"

namespace penumbra {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

struct Spec {
  std::string shape;
  Representation representation;
  std::string method;
  RendererKind renderer;
  std::string label;  // file stem: shape-representation-method-renderer
  Scene scene;
};

std::string key(const std::string& shape, Representation r, const std::string& method,
                RendererKind renderer, int scale = 1) {
  return fmt::format("{}-{}-{}-{}{}", shape, to_string(r), method, to_string(renderer),
                     scale == 1 ? "" : fmt::format("-x{}", scale));
}

CalibrationCheck at_most(std::string name, double value, double bound) {
  return {std::move(name), value, bound, false, std::isfinite(value) && value <= bound};
}
CalibrationCheck at_least(std::string name, double value, double bound) {
  return {std::move(name), value, bound, true, std::isfinite(value) && value >= bound};
}

// What a one-pixel forward difference does to the steepest sine term: a
// difference over a step of d radians of phase scales the slope by
// sin(d/2)/(d/2) and shifts it by d/2.
std::string footprint_explanation(const Scene& scene) {
  const Camera& c = scene.camera;
  if (c.projection != Projection::kOrthographic) return "";
  const double footprint = length(c.right) / c.width;
  double k = 0.0;
  for (const SineTerm& t : scene.height.function.terms) k = std::max(k, length(t.k));
  const double d = 2.0 * kPi * k * footprint;
  if (!(d > 0.0)) return "";
  return fmt::format(
      "Pixel footprint {:.4g} scene units = {:.3g} rad of phase of the steepest term ({:.3g} "
      "cycles/unit): a one-pixel forward difference scales its slope by {:.3f} and shifts it "
      "by half a pixel.",
      footprint, d, k, std::sin(0.5 * d) / (0.5 * d));
}

}  // namespace

bool CalibrationResult::all_rendered() const {
  for (const CalibrationRender& r : renders)
    if (!r.error.empty()) return false;
  return true;
}

bool CalibrationResult::all_pass() const {
  for (const CalibrationRow& row : rows) {
    if (!row.missing.empty()) return false;
    for (const CalibrationCheck& c : row.checks)
      if (!c.pass) return false;
  }
  return true;
}

json CalibrationResult::to_json() const {
  json renders_json = json::array(), rows_json = json::array();
  for (const CalibrationRender& r : renders)
    renders_json.push_back({{"label", r.label},
                            {"renderer", r.renderer},
                            {"file", r.file},
                            {"seconds", r.seconds},
                            {"evaluator_seconds", r.evaluator_seconds},
                            {"error", r.error.empty() ? json() : json(r.error)}});
  for (const CalibrationRow& row : rows) {
    json checks = json::array();
    for (const CalibrationCheck& c : row.checks)
      checks.push_back({{"name", c.name},
                        {"value", std::isfinite(c.value) ? json(c.value) : json()},
                        {"bound", c.bound},
                        {"kind", c.minimum ? "minimum" : "maximum"},
                        {"pass", c.pass}});
    rows_json.push_back({{"shape", row.shape},
                         {"representation", row.representation},
                         {"test", row.test},
                         {"reference", row.reference},
                         {"image", image_metrics_json(row.image)},
                         {"profile", profile_metrics_json(row.profile)},
                         {"checks", checks},
                         {"note", row.note},
                         {"missing", row.missing.empty() ? json() : json(row.missing)}});
  }
  return {{"format", "penumbra-calibration"},
          {"version", 1},
          {"penumbra", kPenumbraVersion},
          {"all_rendered", all_rendered()},
          {"all_pass", all_pass()},
          {"renders", renders_json},
          {"rows", rows_json}};
}

namespace {

// The fixed plan: every case on both shapes. Parses everything before the
// first render, so bad input fails fast.
std::vector<Spec> calibration_specs(const CalibrationOptions& options) {
  std::vector<Override> overrides;
  for (const std::string& s : options.sets) overrides.push_back(parse_override(s));
  std::vector<Spec> specs;
  const struct {
    Representation representation;
    const char* method;
    RendererKind renderer;
    int scale = 1;  // image size multiplier, same camera extents
  } plan[] = {
      {Representation::kSmooth, "none", RendererKind::kEvaluator},
      {Representation::kSmooth, "none", RendererKind::kPovray},
      {Representation::kSmooth, "none", RendererKind::kBlender},
      {Representation::kBump, "none", RendererKind::kEvaluator},
      {Representation::kBump, "chiang2019", RendererKind::kEvaluator},
      {Representation::kBump, "none", RendererKind::kPovray},
      {Representation::kBump, "none", RendererKind::kBlender},
      {Representation::kBump, "chiang2019", RendererKind::kBlender},
      {Representation::kDisplacement, "none", RendererKind::kEvaluator},
      {Representation::kDisplacement, "none", RendererKind::kPovray},
      {Representation::kDisplacement, "none", RendererKind::kBlender},
      // Cycles' bump differentiates over the pixel footprint: the same view
      // at 2x and 4x the pixels shows how its residual follows the footprint.
      {Representation::kBump, "none", RendererKind::kEvaluator, 2},
      {Representation::kBump, "none", RendererKind::kBlender, 2},
      {Representation::kBump, "none", RendererKind::kEvaluator, 4},
      {Representation::kBump, "none", RendererKind::kBlender, 4},
  };
  for (const char* shape : {"cylinder", "sphere"}) {
    const std::string file =
        (fs::path(options.scenes_dir) / (std::string(shape) + ".json")).string();
    json base = read_json_file(file);
    resolve_map_files(base, file);
    for (const auto& p : plan) {
      json document = base;
      std::vector<Override> all = overrides;
      all.push_back({"/representation", to_string(p.representation)});
      all.push_back({"/terminator/method", p.method});
      if (p.renderer == RendererKind::kBlender) all.push_back({"/camera/spp", options.blender_spp});
      if (p.scale != 1) {
        const json& camera = base.at("camera");
        all.push_back({"/camera/width", camera.value("width", 256) * p.scale});
        all.push_back({"/camera/height", camera.value("height", 256) * p.scale});
      }
      const std::string origin = file + " (calibration case)";
      apply_overrides(document, all, origin);
      resolve_map_files(document, file);
      specs.push_back({shape, p.representation, p.method, p.renderer,
                       key(shape, p.representation, p.method, p.renderer, p.scale),
                       scene_from_json(document, origin)});
    }
  }

  return specs;
}

// Renders every case in parallel into `renders_dir` (failures are kept as
// rows' "missing", not thrown).
std::vector<Image> render_specs(const std::vector<Spec>& specs, const CalibrationOptions& options,
                                const fs::path& renders_dir, CalibrationResult& result) {
  result.renders.resize(specs.size());
  std::vector<Image> images(specs.size());
  ExecuteOptions eo;
  eo.jobs = options.parallelism.renders;
  eo.log = options.log;
  const ExecuteResult executed = execute_tasks(
      specs.size(), eo,
      [&](std::size_t i) {
        const Spec& spec = specs[i];
        CalibrationRender& r = result.renders[i];
        RenderSettings settings;
        settings.timeout_s = options.timeout_s;
        settings.threads = options.parallelism.threads_per_render;
        settings.log_path = (renders_dir / (spec.label + ".log")).string();
        std::error_code ignored;
        fs::remove(settings.log_path, ignored);  // a log per attempt, not appended forever
        RendererRun run = render_with(spec.renderer, spec.scene, settings);
        r.seconds = run.seconds;
        r.evaluator_seconds =
            spec.renderer == RendererKind::kEvaluator ? run.seconds : run.geometry_seconds;
        r.file = (renders_dir / (spec.label + ".exr")).string();
        write_exr(run.image, r.file,
                  {{"penumbra:version", kPenumbraVersion},
                   {"penumbra:renderer", to_string(spec.renderer)},
                   {"penumbra:method", spec.method},
                   {"penumbra:representation", to_string(spec.representation)},
                   {"penumbra:radiance_unit", "W m^-2 sr^-1"}});
        images[i] = std::move(run.image);
      },
      [&](std::size_t i) {
        return fmt::format("{} with {}", specs[i].label, to_string(specs[i].renderer));
      });
  for (std::size_t i = 0; i < specs.size(); ++i) {
    CalibrationRender& r = result.renders[i];
    r.label = specs[i].label;
    r.renderer = to_string(specs[i].renderer);
    if (!executed.done[i]) {
      r.error = executed.errors[i].empty() ? "not rendered (interrupted)" : executed.errors[i];
      r.file.clear();
    }
  }
  return images;
}

// Compares two cases of one shape and appends the row to the result.
struct RowMaker {
  const std::vector<Spec>& specs;
  const std::vector<Image>& images;
  CalibrationResult& result;
  std::map<std::string, std::size_t> index;

  CalibrationRow& operator()(const std::string& shape, Representation rep,
                             const std::string& test_method, RendererKind test,
                             const std::string& ref_method, RendererKind ref,
                             const std::string& note, int scale = 1) {
    CalibrationRow row;
    row.shape = shape;
    row.representation = to_string(rep);
    row.test = fmt::format("{}:{}", to_string(test), test_method);
    row.reference = fmt::format("{}:{}", to_string(ref), ref_method);
    row.note = note;
    const std::size_t ti = index.at(key(shape, rep, test_method, test, scale));
    const std::size_t ri = index.at(key(shape, rep, ref_method, ref, scale));
    if (scale != 1) row.representation += fmt::format(" x{}", scale);
    for (std::size_t i : {ti, ri})
      if (!result.renders[i].error.empty())
        row.missing +=
            fmt::format("{} failed: {}; ", specs[i].label, result.renders[i].error.substr(0, 200));
    if (row.missing.empty()) {
      MeasureOptions options;
      options.scale = radiance_scale(specs[ri].scene);
      options.intervals = options.view = false;
      const Measurement m = measure(images[ti], images[ri], options);
      row.profile = m.profile;
      row.image = m.image;
    }
    result.rows.push_back(std::move(row));
    return result.rows.back();
  }
};

// The rows of one shape, each with its bound (or none, said in the note).
void shape_rows(RowMaker& compare, const char* shape) {
  const RendererKind E = RendererKind::kEvaluator, P = RendererKind::kPovray,
                     B = RendererKind::kBlender;
  {
    CalibrationRow& row = compare(shape, Representation::kSmooth, "none", P, "none", E,
                                  "deterministic both; same sample positions (stratum "
                                  "centres), POV-Ray output is half float");
    if (row.missing.empty()) {
      row.checks.push_back(
          at_most("image RMSE / peak radiance", row.image.rmse / row.image.peak, 0.001));
      row.checks.push_back(at_least("mask IoU (silhouettes)", row.image.mask_iou, 0.99));
    }
  }
  {
    CalibrationRow& row =
        compare(shape, Representation::kSmooth, "none", B, "none", E,
                "Monte Carlo: the test is |mean(Cycles - evaluator)| / mean(evaluator) over fully "
                "covered pixels <= 0.5 %");
    if (row.missing.empty()) {
      row.checks.push_back(at_most("|mean error| / mean radiance",
                                   std::abs(row.image.mean_error) / row.image.reference_mean,
                                   0.005));
      row.checks.push_back(at_least("mask IoU (silhouettes)", row.image.mask_iou, 0.99));
    }
  }
  {
    CalibrationRow& row = compare(shape, Representation::kBump, "none", P, "none", E,
                                  "POV-Ray bump: pattern h(projected point), bump_size "
                                  "7.5 A / C, one-sided differences of step 1e-4");
    if (row.missing.empty())
      row.checks.push_back(
          at_most("profile RMSE (fraction of albedo*E/pi)", row.profile.rmse_overall, 0.01));
  }
  const std::string footprint_note = footprint_explanation(
      compare.specs[compare.index.at(key(shape, Representation::kBump, "none", B))].scene);
  compare(shape, Representation::kBump, "none", B, "none", E,
          "no bound: Cycles 3.4 differentiates h over the pixel footprint (ray "
          "differentials), not analytically. " +
              footprint_note);
  compare(shape, Representation::kBump, "chiang2019", B, "chiang2019", E,
          "no bound: Cycles' own chiang2019 (Bump node, Ng := Ni) on the same "
          "footprint-differenced normal");
  for (int scale : {2, 4})
    compare(shape, Representation::kBump, "none", B, "none", E,
            fmt::format("no bound: the same view at {}x the pixels, so 1/{} of the footprint; "
                        "the residual should shrink with it",
                        scale, scale),
            scale);
  for (const auto& [t, r] : {std::pair{P, E}, std::pair{B, E}, std::pair{B, P}}) {
    CalibrationRow& row = compare(shape, Representation::kDisplacement, "none", t, "none", r,
                                  "true displacement in both");
    if (row.missing.empty())
      row.checks.push_back(
          at_most("profile RMSE (fraction of albedo*E/pi)", row.profile.rmse_overall, 0.01));
  }
}

// Compares the cases and checks each against its bound.
void calibration_rows(const std::vector<Spec>& specs, const std::vector<Image>& images,
                      CalibrationResult& result) {
  RowMaker compare{specs, images, result, {}};
  for (std::size_t i = 0; i < specs.size(); ++i) compare.index[specs[i].label] = i;
  for (const char* shape : {"cylinder", "sphere"}) shape_rows(compare, shape);
}

}  // namespace

CalibrationResult run_calibration(const CalibrationOptions& options) {
  const fs::path out(options.output_dir), renders_dir = out / "renders";
  const std::vector<Spec> specs = calibration_specs(options);
  std::error_code ec;
  fs::create_directories(renders_dir, ec);
  if (ec || !fs::is_directory(renders_dir))
    throw OutputError(
        fmt::format("{}: cannot create the folder: {}", renders_dir.string(), ec.message()));
  remove_stale_temporaries(renders_dir.string());  // left by a killed earlier calibration
  CalibrationResult result;
  const std::vector<Image> images = render_specs(specs, options, renders_dir, result);
  calibration_rows(specs, images, result);
  return result;
}

std::string calibration_table(const CalibrationResult& result) {
  std::string s = fmt::format("{:<9} {:<13} {:<22} {:<22} {:>8} {:>9} {:>9} {:>9} {:>9}  {}\n",
                              "shape", "repr.", "test", "reference", "IoU", "RMSE/pk", "maxerr/pk",
                              "prof.RMSE", "term.RMSE", "checks");
  for (const CalibrationRow& r : result.rows) {
    std::string checks;
    for (const CalibrationCheck& c : r.checks)
      checks += fmt::format("{}{} {:.3g} {} {:.3g}; ", c.pass ? "pass " : "FAIL ", c.name, c.value,
                            c.minimum ? ">=" : "<=", c.bound);
    if (!r.missing.empty()) checks = "MISSING: " + r.missing;
    if (checks.empty()) checks = "(reported, no bound)";
    const double pk = r.image.peak > 0 ? r.image.peak : 1.0;
    s += fmt::format(
        "{:<9} {:<13} {:<22} {:<22} {:>8.5f} {:>9.5f} {:>9.5f} {:>9.5f} {:>9.5f}  {}\n", r.shape,
        r.representation, r.test, r.reference, r.image.mask_iou, r.image.rmse / pk,
        r.image.max_error / pk, r.profile.rmse_overall, r.profile.rmse_terminator, checks);
  }
  s += "\nRMSE/pk, maxerr/pk: image errors over pixels fully covered in both, divided by the "
       "reference's peak radiance.\nprof.RMSE, term.RMSE: terminator-profile RMSE overall and "
       "over 60-100 degrees, as a fraction of albedo*E/pi.\n";
  s += fmt::format("\n{:<44} {:>10} {:>12} {:>9}\n", "wall time per render", "seconds",
                   "evaluator s", "speed-up");
  for (const CalibrationRender& r : result.renders)
    s += !r.error.empty() ? fmt::format("  {:<42} FAILED\n", r.label)
         : r.renderer == "evaluator"
             ? fmt::format("  {:<42} {:>10.3f}\n", r.label, r.seconds)
             : fmt::format("  {:<42} {:>10.3f} {:>12.3f} {:>8.0f}x\n", r.label, r.seconds,
                           r.evaluator_seconds, r.seconds / r.evaluator_seconds);
  s += "(speed-up: the external renderer's wall time over the evaluator's on the same scene and "
       "sample count)\n";
  return s;
}

void write_calibration_reports(const CalibrationResult& result, const std::string& dir) {
  const fs::path d(dir);
  write_text_file((d / "calibration.json").string(), result.to_json().dump(2) + "\n");
  std::string csv =
      "shape,representation,test,reference,mask_iou,image_rmse,image_max_error,image_mean_error,"
      "reference_mean,reference_peak,profile_rmse_overall,profile_rmse_terminator,"
      "profile_max_error,position_error_deg,lit_bias,checks_pass,missing\n";
  for (const CalibrationRow& r : result.rows) {
    bool pass = r.missing.empty();
    for (const CalibrationCheck& c : r.checks) pass = pass && c.pass;
    csv += fmt::format(
        "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", r.shape, r.representation, r.test,
        r.reference, r.image.mask_iou, r.image.rmse, r.image.max_error, r.image.mean_error,
        r.image.reference_mean, r.image.peak, r.profile.rmse_overall, r.profile.rmse_terminator,
        r.profile.max_error, r.profile.position_error, r.profile.lit_bias,
        r.checks.empty() ? "" : (pass ? "true" : "false"), r.missing.empty() ? "" : "true");
  }
  write_text_file((d / "calibration.csv").string(), csv);
  std::string md = "# Penumbra calibration: evaluator, POV-Ray, Blender Cycles\n\n";
  md += fmt::format("Result: {}.\n\n", result.all_pass() ? "every bound met" : "BOUNDS MISSED");
  md +=
      "Image errors in W m^-2 sr^-1 (pixels fully covered in both images); profile errors "
      "as a fraction of albedo*E/pi (1-degree bins of theta, the angle between the light and "
      "the base normal).\n\n";
  md +=
      "| shape | repr. | test | reference | IoU | image RMSE | profile RMSE | terminator "
      "RMSE | checks | note |\n|---|---|---|---|---|---|---|---|---|---|\n";
  for (const CalibrationRow& r : result.rows) {
    std::string checks;
    for (const CalibrationCheck& c : r.checks)
      checks += fmt::format("{}: {} {:.4g} {} {:.4g}<br>", c.pass ? "pass" : "**FAIL**", c.name,
                            c.value, c.minimum ? ">=" : "<=", c.bound);
    if (!r.missing.empty()) checks = "**missing**: " + r.missing;
    md += fmt::format("| {} | {} | {} | {} | {:.5f} | {:.3g} | {:.5f} | {:.5f} | {} | {} |\n",
                      r.shape, r.representation, r.test, r.reference, r.image.mask_iou,
                      r.image.rmse, r.profile.rmse_overall, r.profile.rmse_terminator,
                      checks.empty() ? "reported" : checks, r.note);
  }
  md +=
      "\n## Wall time per render\n\nSpeed-up: the renderer's wall time (process start to "
      "exit) over the evaluator's on the same scene and sample count.\n\n"
      "| render | renderer | seconds | evaluator seconds | speed-up |\n|---|---|---|---|---|\n";
  for (const CalibrationRender& r : result.renders) {
    if (!r.error.empty())
      md += fmt::format("| {} | {} | failed | | |\n", r.label, r.renderer);
    else if (r.renderer == "evaluator")
      md += fmt::format("| {} | {} | {:.3f} | | |\n", r.label, r.renderer, r.seconds);
    else
      md += fmt::format("| {} | {} | {:.3f} | {:.3f} | {:.0f}x |\n", r.label, r.renderer, r.seconds,
                        r.evaluator_seconds, r.seconds / r.evaluator_seconds);
  }
  md +=
      "\nPOV-Ray offers only the `none` row (it has no shadow-terminator method); Cycles 3.4 "
      "offers `none`, `chiang2019` (its Bump node) and `shading-offset`.\n";
  write_text_file((d / "calibration.md").string(), md);
}

}  // namespace penumbra
