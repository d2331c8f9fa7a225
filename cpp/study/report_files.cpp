#include "study/report_files.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <set>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "analysis/metrics_json.h"
#include "core/tessellation.h"
#include "core/vec.h"
#include "image/image_io.h"
#include "scene/scene_json.h"
#include "study/cache.h"
#include "study/light_angles.h"
#include "study/names.h"
#include "study/provenance.h"
#include "study/ranking.h"
#include "util/strict_json.h"

namespace penumbra {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// ---- CSV ----------------------------------------------------------------------
// metrics.csv and lowpoly.csv are documented column by column in
// harness/csv-columns.json (a test compares that file with what is written
// here). Names carry their unit as a suffix so that a loaded table cannot be
// misread: _rel a fraction of albedo*E/pi, _w_m2_sr radiance, _deg degrees,
// _px pixels, _count a count, _fraction a share of pixels; bare names are
// identifiers, paths or unitless indices (SSIM, IoU).

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

// An undefined quantity (NaN) is an empty field; + 0.0 writes -0 as 0.
std::string number(double v) {
  return std::isfinite(v) ? fmt::format("{}", v + 0.0) : std::string();
}
std::string count(std::uint64_t n) {
  return fmt::format("{}", n);
}

// What one CSV row is made of: a comparison, its two renders and its variant.
struct CsvRow {
  const std::string& study;
  const Variant& variant;
  const ComparisonRow& c;
  const Job& test;
  const Job& reference;
  const StudyMethod* method;  // as the study names it; null if the label is unknown
  // The ranking metric C (study/ranking.h) for an evaluator row against the
  // evaluator's truth; NaN elsewhere.
  double combined = kNaN;
};

struct Column {
  std::string name;
  std::function<std::string(const CsvRow&)> value;  // unquoted
};
using Columns = std::vector<Column>;

using Metric = double (*)(const ComparisonRow&);
using Count = std::uint64_t (*)(const ComparisonRow&);

Column metric_column(std::string name, Metric f) {
  return {std::move(name), [f](const CsvRow& r) { return number(f(r.c)); }};
}
Column count_column(std::string name, Count f) {
  return {std::move(name), [f](const CsvRow& r) { return count(f(r.c)); }};
}

// A metric with its 95 % interval beside it: NAME, NAME_ci_low, NAME_ci_high.
void add_with_ci(Columns& out, const std::string& name, Metric f,
                 Interval ComparisonIntervals::*ci) {
  out.push_back(metric_column(name, f));
  out.push_back(
      {name + "_ci_low", [ci](const CsvRow& r) { return number((r.c.intervals.*ci).low); }});
  out.push_back(
      {name + "_ci_high", [ci](const CsvRow& r) { return number((r.c.intervals.*ci).high); }});
}

Columns bump_columns() {
  using C = ComparisonRow;
  using I = ComparisonIntervals;
  Columns out;
  out.push_back({"combined_relative_error", [](const CsvRow& r) { return number(r.combined); }});
  add_with_ci(
      out, "profile_rmse_terminator_rel", [](const C& r) { return r.profile.rmse_terminator; },
      &I::rmse_terminator);
  out.push_back(
      metric_column("profile_rmse_overall_rel", [](const C& r) { return r.profile.rmse_overall; }));
  add_with_ci(
      out, "profile_max_error_terminator_rel", [](const C& r) { return r.profile.max_error; },
      &I::max_error);
  out.push_back(
      metric_column("profile_max_step_rel", [](const C& r) { return r.profile.max_step; }));
  out.push_back(metric_column("reference_max_step_rel",
                              [](const C& r) { return r.profile.reference_max_step; }));
  out.push_back(metric_column("position_deg", [](const C& r) { return r.profile.position; }));
  out.push_back(metric_column("reference_position_deg",
                              [](const C& r) { return r.profile.reference_position; }));
  add_with_ci(
      out, "position_error_deg", [](const C& r) { return r.profile.position_error; },
      &I::position_error);
  out.push_back(metric_column("transition_width_deg", [](const C& r) { return r.profile.width; }));
  out.push_back(metric_column("reference_transition_width_deg",
                              [](const C& r) { return r.profile.reference_width; }));
  add_with_ci(
      out, "lit_bias_rel", [](const C& r) { return r.profile.lit_bias; }, &I::lit_bias);
  out.push_back(count_column("common_bin_count",
                             [](const C& r) -> std::uint64_t { return r.profile.common_bins; }));
  out.push_back(metric_column("image_mask_iou", [](const C& r) { return r.image.mask_iou; }));
  add_with_ci(
      out, "image_rmse_w_m2_sr", [](const C& r) { return r.image.rmse; }, &I::image_rmse);
  out.push_back(metric_column("image_ssim", [](const C& r) { return r.image.ssim; }));
  add_with_ci(
      out, "image_flip", [](const C& r) { return r.image.flip; }, &I::flip);
  out.push_back(
      metric_column("image_max_error_w_m2_sr", [](const C& r) { return r.image.max_error; }));
  out.push_back(
      metric_column("image_mean_error_w_m2_sr", [](const C& r) { return r.image.mean_error; }));
  out.push_back(count_column("image_pixel_count",
                             [](const C& r) -> std::uint64_t { return r.image.pixels; }));
  out.push_back(count_column("image_nonfinite_count",
                             [](const C& r) -> std::uint64_t { return r.image.nonfinite; }));
  add_with_ci(
      out, "view_rmse_grazing_rel", [](const C& r) { return r.view.rmse_grazing; },
      &I::view_rmse_grazing);
  add_with_ci(
      out, "view_bias_grazing_rel", [](const C& r) { return r.view.bias_grazing; },
      &I::view_bias_grazing);
  out.push_back(
      count_column("view_pixel_count", [](const C& r) -> std::uint64_t { return r.view.pixels; }));
  return out;
}

Columns lowpoly_columns() {
  using C = ComparisonRow;
  Columns out;
  out.push_back(
      metric_column("darkened_fraction", [](const C& r) { return r.shadow->darkened_fraction; }));
  out.push_back(
      metric_column("max_darkening_rel", [](const C& r) { return r.shadow->max_darkening; }));
  out.push_back(metric_column("lost_shadow_fraction",
                              [](const C& r) { return r.shadow->lost_shadow_fraction; }));
  out.push_back(
      metric_column("shadow_shift_px", [](const C& r) { return r.shadow->shadow_shift_px; }));
  out.push_back(count_column("lit_pixel_count",
                             [](const C& r) -> std::uint64_t { return r.shadow->lit_pixels; }));
  out.push_back(count_column("darkened_pixel_count", [](const C& r) -> std::uint64_t {
    return r.shadow->darkened_pixels;
  }));
  out.push_back(count_column("shadowed_pixel_count", [](const C& r) -> std::uint64_t {
    return r.shadow->shadowed_pixels;
  }));
  out.push_back(count_column("test_shadowed_pixel_count", [](const C& r) -> std::uint64_t {
    return r.shadow->test_shadowed_pixels;
  }));
  add_with_ci(
      out, "profile_rmse_terminator_rel", [](const C& r) { return r.profile.rmse_terminator; },
      &ComparisonIntervals::rmse_terminator);
  out.push_back(
      metric_column("profile_rmse_overall_rel", [](const C& r) { return r.profile.rmse_overall; }));
  out.push_back(
      metric_column("profile_max_step_rel", [](const C& r) { return r.profile.max_step; }));
  out.push_back(
      metric_column("position_error_deg", [](const C& r) { return r.profile.position_error; }));
  out.push_back(metric_column("lit_bias_rel", [](const C& r) { return r.profile.lit_bias; }));
  out.push_back(metric_column("image_rmse_w_m2_sr", [](const C& r) { return r.image.rmse; }));
  out.push_back(metric_column("image_ssim", [](const C& r) { return r.image.ssim; }));
  add_with_ci(
      out, "image_flip", [](const C& r) { return r.image.flip; }, &ComparisonIntervals::flip);
  out.push_back(metric_column("image_mask_iou", [](const C& r) { return r.image.mask_iou; }));
  out.push_back(count_column("image_nonfinite_count",
                             [](const C& r) -> std::uint64_t { return r.image.nonfinite; }));
  return out;
}

// The direction towards the light seen from the shape's centre.
Vec3 towards_light(const Scene& s) {
  return light_axis(s.light, s.shape.center);
}

// Angles of the direction towards the light (study/light_angles.h).
double light_elevation_deg(const Scene& s) {
  return elevation_deg(towards_light(s));
}
double light_azimuth_deg(const Scene& s) {
  return azimuth_deg(towards_light(s));
}

// "s=0.3", parameters in key order joined by ';' (the label's ',' would
// need quoting); "" without parameters.
std::string method_params(const StudyMethod* m) {
  std::string out;
  if (m == nullptr || !m->parameters.is_object()) return out;
  for (const auto& [k, v] : m->parameters.items())
    out += (out.empty() ? "" : ";") + k + "=" + v.dump();
  return out;
}

// Identification: what was rendered, how, and against which truth.
Columns key_columns(SectionKind kind) {
  const std::string m = kind == SectionKind::kBump ? "method" : "offset";
  const auto str = [](const char* s) { return std::string(s); };
  Columns out{
      {"renderer", [str](const CsvRow& r) { return str(to_string(r.test.renderer)); }},
      {"representation", [str](const CsvRow& r) { return str(to_string(r.test.representation)); }},
      {m, [](const CsvRow& r) { return r.method ? r.method->id : r.c.method; }},
      {m + "_params", [](const CsvRow& r) { return method_params(r.method); }},
      {m + "_label", [](const CsvRow& r) { return r.c.method; }},
      {"reference_renderer",
       [str](const CsvRow& r) { return str(to_string(r.c.reference_renderer)); }},
      {"reference_representation",
       [](const CsvRow& r) { return r.c.reference.substr(r.c.reference.find(':') + 1); }},
      {"truth",
       [str](const CsvRow& r) {
         return str(r.c.reference_renderer == r.c.renderer ? "own" : "evaluator");
       }},
      {"width_px", [](const CsvRow& r) { return count(r.test.scene().camera.width); }},
      {"height_px", [](const CsvRow& r) { return count(r.test.scene().camera.height); }},
      {"spp", [](const CsvRow& r) { return count(r.test.scene().camera.spp); }},
      {"reference_spp", [](const CsvRow& r) { return count(r.reference.scene().camera.spp); }},
      {"seed", [](const CsvRow& r) { return count(r.test.scene().camera.seed); }},
      {"light_elevation_deg",
       [](const CsvRow& r) { return number(light_elevation_deg(r.test.scene())); }},
      {"light_azimuth_deg",
       [](const CsvRow& r) { return number(light_azimuth_deg(r.test.scene())); }},
      {"exr", [](const CsvRow& r) { return RenderCache::relative_exr(r.test.key); }},
      {"reference_exr",
       [](const CsvRow& r) { return RenderCache::relative_exr(r.reference.key); }}};
  if (kind == SectionKind::kLowPoly)
    out.push_back({"triangle_count", [](const CsvRow& r) {
                     const Scene s = r.test.scene();
                     return s.tessellation
                                ? count(tessellated_triangle_count(s.shape, *s.tessellation))
                                : std::string();
                   }});
  return out;
}

// "/height/amplitude" -> "height_amplitude" (study/names.h).
std::string snake_name(const std::string& pointer) {
  const std::string out = lower_words(pointer, '_');
  return out.empty() ? "axis" : out;
}

// How an axis's values become columns, decided over all its values so that
// every row has the same columns and each column one type: numbers one
// numeric column; strings one text column; arrays of 2 or 3 numbers one
// numeric column per component (_x, _y, _z); anything else compact JSON
// text. null is an empty cell.
enum class AxisKind { kNumber, kString, kVector, kJson, kId };
struct AxisLayout {
  AxisKind kind = AxisKind::kJson;
  std::size_t size = 1;
};

AxisLayout axis_layout(const StudyAxis& a) {
  if (!a.sets.empty()) return {AxisKind::kId, 1};  // a compound axis: its values' short ids
  const auto all = [&a](const std::function<bool(const json&)>& pred) {
    return std::all_of(a.values.begin(), a.values.end(),
                       [&pred](const json& v) { return v.is_null() || pred(v); });
  };
  if (all([](const json& v) { return v.is_number(); })) return {AxisKind::kNumber, 1};
  if (all([](const json& v) { return v.is_string(); })) return {AxisKind::kString, 1};
  const auto first =
      std::find_if(a.values.begin(), a.values.end(), [](const json& v) { return v.is_array(); });
  const std::size_t n = first == a.values.end() ? 0 : first->size();
  const bool vectors = all([n](const json& v) {
    return v.is_array() && v.size() == n &&
           std::all_of(v.begin(), v.end(), [](const json& x) { return x.is_number(); });
  });
  return vectors && (n == 2 || n == 3) ? AxisLayout{AxisKind::kVector, n} : AxisLayout{};
}

std::string axis_cell(const json& v, AxisKind kind, std::size_t component) {
  if (v.is_null()) return "";
  if (kind == AxisKind::kId) return v.get<std::string>();
  switch (kind) {
    case AxisKind::kString:
      return v.get<std::string>();
    case AxisKind::kVector:
      return v[component].dump();
    default:
      return v.dump();
  }
}

// A compound axis's value as its short id; any other value as it is.
json axis_id_or_value(const StudyAxis& axis, const json& v, AxisKind kind) {
  if (kind != AxisKind::kId) return v;
  const auto it = std::find(axis.values.begin(), axis.values.end(), v);
  return it == axis.values.end()
             ? v
             : json(axis_value_ids(axis)[std::size_t(it - axis.values.begin())]);
}

// One column per axis (per component of a vector axis), named after its
// pointer; a name another column already has gets "_axis" appended.
Columns axis_columns(const std::vector<StudyAxis>& axes, const Columns& others) {
  std::set<std::string> taken;
  for (const Column& c : others) taken.insert(c.name);
  Columns out;
  for (std::size_t i = 0; i < axes.size(); ++i) {
    const AxisLayout layout = axis_layout(axes[i]);
    std::vector<std::string> suffixes{""};
    if (layout.kind == AxisKind::kVector)
      suffixes = layout.size == 2 ? std::vector<std::string>{"_x", "_y"}
                                  : std::vector<std::string>{"_x", "_y", "_z"};
    std::string base = snake_name(axes[i].pointer);
    while (std::any_of(suffixes.begin(), suffixes.end(),
                       [&](const std::string& s) { return taken.count(base + s) > 0; }))
      base += "_axis";
    for (std::size_t k = 0; k < suffixes.size(); ++k) {
      taken.insert(base + suffixes[k]);
      out.push_back(
          {base + suffixes[k], [i, k, kind = layout.kind, axis = axes[i]](const CsvRow& r) {
             return axis_cell(axis_id_or_value(axis, r.variant.axis_values[i], kind), kind, k);
           }});
    }
  }
  return out;
}

const StudyMethod* find_method(const Section& section, const std::string& label) {
  for (const StudyMethod& m : section.methods)
    if (m.label == label) return &m;
  return nullptr;
}

// Per bump variant, raw bump's E_term + E_view against the evaluator's truth.
std::map<std::size_t, double> baseline_errors(const std::vector<ComparisonRow>& rows) {
  std::map<std::size_t, double> out;
  for (const ComparisonRow& row : rows)
    if (row.method == "none" && row.renderer == RendererKind::kEvaluator &&
        row.reference_renderer == RendererKind::kEvaluator)
      out[row.variant] = row.profile.rmse_terminator + row.view.rmse_grazing;
  return out;
}

// The rows of a section's comparisons, in report order.
std::vector<CsvRow> csv_rows(const ReportInputs& in, const Section& section) {
  const std::map<std::size_t, double> baseline = baseline_errors(in.comparisons.rows);
  std::vector<CsvRow> out;
  for (const ComparisonRow& row : in.comparisons.rows) {
    const Variant& var = in.plan.variants[row.variant];
    if (var.section != section.kind) continue;
    CsvRow r{in.study.name,
             var,
             row,
             in.plan.jobs[row.job],
             in.plan.jobs[row.reference_job],
             find_method(section, row.method)};
    const auto none = baseline.find(row.variant);
    if (section.kind == SectionKind::kBump && none != baseline.end() && none->second > 0.0 &&
        row.renderer == RendererKind::kEvaluator &&
        row.reference_renderer == RendererKind::kEvaluator)
      r.combined = (row.profile.rmse_terminator + row.view.rmse_grazing) / none->second;
    out.push_back(r);
  }
  return out;
}

std::string csv_line(const Columns& columns, const CsvRow& r) {
  std::string line;
  for (std::size_t k = 0; k < columns.size(); ++k)
    line += (k ? "," : "") + csv_field(columns[k].value(r));
  return line + "\n";
}

std::string csv_header(const Columns& columns) {
  std::string line;
  for (const Column& c : columns) line += (line.empty() ? "" : ",") + csv_field(c.name);
  return line + "\n";
}

// `head` then the section's axis columns then `tail`, axis names kept clear
// of the others.
Columns with_axes(const Columns& head, const Section& section, const Columns& tail) {
  Columns columns = head;
  columns.insert(columns.end(), tail.begin(), tail.end());
  const Columns axes = axis_columns(section.axes, columns);
  columns.insert(columns.begin() + static_cast<std::ptrdiff_t>(head.size()), axes.begin(),
                 axes.end());
  return columns;
}

Columns identity_head() {
  return {{"study", [](const CsvRow& r) { return r.study; }},
          {"variant", [](const CsvRow& r) { return r.variant.id; }},
          {"scene", [](const CsvRow& r) { return r.variant.scene; }}};
}

// One header line, then one row per comparison of the section: study,
// variant, scene, the axes, the identification columns, then `metrics`.
std::string comparison_csv(const ReportInputs& in, const Section& section, const Columns& metrics) {
  Columns tail = key_columns(section.kind);
  tail.insert(tail.end(), metrics.begin(), metrics.end());
  const Columns columns = with_axes(identity_head(), section, tail);
  std::string csv = csv_header(columns);
  for (const CsvRow& r : csv_rows(in, section)) csv += csv_line(columns, r);
  return csv;
}

// metrics-long.csv: one row per (comparison, metric), for data frames.
struct LongMetric {
  const char* name;
  const char* unit;
  double (*value)(const CsvRow&);
  Interval ComparisonIntervals::*ci;  // null: no interval
};

const std::vector<LongMetric>& long_metrics() {
  using R = CsvRow;
  using I = ComparisonIntervals;
  static const char* rel = "fraction of albedo*E/pi";
  static const char* radiance = "W m^-2 sr^-1";
  static const std::vector<LongMetric> m{
      {"combined_relative_error", ranked_quantities().front().unit,
       [](const R& r) { return r.combined; }, nullptr},
      {"profile.rmse_terminator", rel, [](const R& r) { return r.c.profile.rmse_terminator; },
       &I::rmse_terminator},
      {"profile.rmse_overall", rel, [](const R& r) { return r.c.profile.rmse_overall; }, nullptr},
      {"profile.max_error_terminator", rel, [](const R& r) { return r.c.profile.max_error; },
       &I::max_error},
      {"profile.max_step", rel, [](const R& r) { return r.c.profile.max_step; }, nullptr},
      {"profile.position_error_deg", "degrees",
       [](const R& r) { return r.c.profile.position_error; }, &I::position_error},
      {"profile.width_deg", "degrees", [](const R& r) { return r.c.profile.width; }, nullptr},
      {"profile.lit_bias", rel, [](const R& r) { return r.c.profile.lit_bias; }, &I::lit_bias},
      {"image.rmse", radiance, [](const R& r) { return r.c.image.rmse; }, &I::image_rmse},
      {"image.ssim", "unitless", [](const R& r) { return r.c.image.ssim; }, nullptr},
      {"image.flip", "unitless, [0, 1]", [](const R& r) { return r.c.image.flip; }, &I::flip},
      {"image.max_error", radiance, [](const R& r) { return r.c.image.max_error; }, nullptr},
      {"image.mask_iou", "unitless", [](const R& r) { return r.c.image.mask_iou; }, nullptr},
      {"view.rmse_grazing", rel, [](const R& r) { return r.c.view.rmse_grazing; },
       &I::view_rmse_grazing},
      {"view.bias_grazing", rel, [](const R& r) { return r.c.view.bias_grazing; },
       &I::view_bias_grazing}};
  return m;
}

std::string long_csv(const ReportInputs& in, const Section& section) {
  const auto str = [](const char* s) { return std::string(s); };
  const Columns tail{
      {"method", [](const CsvRow& r) { return r.c.method; }},
      {"renderer", [str](const CsvRow& r) { return str(to_string(r.test.renderer)); }},
      {"reference", [](const CsvRow& r) { return r.c.reference; }}};
  const Columns columns = with_axes(identity_head(), section, tail);
  std::string csv = csv_header(columns);
  csv.pop_back();
  csv += ",metric,value,ci_low,ci_high,unit\n";
  for (const CsvRow& r : csv_rows(in, section)) {
    std::string key = csv_line(columns, r);
    key.pop_back();
    for (const LongMetric& m : long_metrics()) {
      const double v = m.value(r);
      if (!std::isfinite(v)) continue;  // long format: an undefined value is no row
      const Interval ci = m.ci ? r.c.intervals.*(m.ci) : Interval{kNaN, kNaN};
      csv += fmt::format("{},{},{},{},{},{}\n", key, m.name, number(v), number(ci.low),
                         number(ci.high), csv_field(m.unit));
    }
  }
  return csv;
}

// ---- report.json ----------------------------------------------------------------

// Each value as the figures and the page show it: a light direction as
// azimuth and elevation (study/light_angles.h), anything else as it is.
json axis_value_labels(const StudyAxis& a) {
  json out = json::array();
  for (const json& v : a.values) out.push_back(axis_value_text(a.pointer, v));
  return out;
}

json axes_json(const std::vector<StudyAxis>& axes) {
  json out = json::array();
  for (const StudyAxis& a : axes) {
    json axis = {{"pointer", a.pointer},
                 {"label", a.label},
                 {"values", a.values},
                 {"value_labels", axis_value_labels(a)},
                 {"value_ids", axis_value_ids(a)}};
    if (!a.sets.empty()) {
      json sets = json::array();
      for (const auto& pairs : a.sets) {
        json set = json::object();
        for (const auto& [pointer, value] : pairs) set[pointer] = value;
        sets.push_back(std::move(set));
      }
      axis["sets"] = std::move(sets);
    }
    out.push_back(std::move(axis));
  }
  return out;
}

json render_json(const ReportInputs& in, const RenderRow& r) {
  const Job& job = in.plan.jobs[r.job];
  json out = {{"renderer", to_string(job.renderer)},
              {"image", r.image},
              {"difference", r.difference.empty() ? json() : json(r.difference)},
              {"flip_map", r.flip_map.empty() ? json() : json(r.flip_map)},
              {"exr", RenderCache::relative_exr(job.key)},
              {"profile", profile_json(r.profile)}};
  if (in.plan.variants[job.variant].section == SectionKind::kBump) {
    out["representation"] = to_string(job.representation);
    out["method"] = job.method;
  } else {
    out["offset"] = job.method;
    const Scene scene = job.scene();
    out["triangles"] = scene.tessellation
                           ? json(tessellated_triangle_count(scene.shape, *scene.tessellation))
                           : json();
  }
  return out;
}

json variants_json(const ReportInputs& in, SectionKind kind) {
  json out = json::array();
  for (std::size_t v = 0; v < in.plan.variants.size(); ++v) {
    const Variant& var = in.plan.variants[v];
    if (var.section != kind) continue;
    json renders = json::array();
    for (const RenderRow& r : in.comparisons.renders[v]) renders.push_back(render_json(in, r));
    out.push_back({{"id", var.id},
                   {"scene", var.scene},
                   {"label", var.label},
                   {"axis_values", var.axis_values},
                   {"renders", renders}});
  }
  return out;
}

// JSON has no NaN: undefined quantities are null.
json value(double v) {
  return std::isfinite(v) ? json(v) : json();
}

json interval_json(const Interval& i) {
  return json::array({value(i.low), value(i.high)});
}

json comparisons_json(const ReportInputs& in, SectionKind kind) {
  json out = json::array();
  for (const ComparisonRow& row : in.comparisons.rows) {
    const Variant& var = in.plan.variants[row.variant];
    if (var.section != kind) continue;
    json c = {{"variant", var.id},
              {"scene", var.scene},
              {"axis_values", var.axis_values},
              {"renderer", to_string(row.renderer)},
              {kind == SectionKind::kBump ? "method" : "offset", row.method},
              {"reference", row.reference},
              {"profile", profile_metrics_json(row.profile)},
              {"image", image_metrics_json(row.image)},
              {"view", view_metrics_json(row.view)}};
    if (row.shadow) c["shadow"] = shadow_metrics_json(*row.shadow);
    c["profile"]["rmse_terminator_ci"] = interval_json(row.intervals.rmse_terminator);
    c["profile"]["max_error_terminator_ci"] = interval_json(row.intervals.max_error);
    c["profile"]["position_error_deg_ci"] = interval_json(row.intervals.position_error);
    c["profile"]["lit_bias_ci"] = interval_json(row.intervals.lit_bias);
    c["image"]["rmse_ci"] = interval_json(row.intervals.image_rmse);
    c["image"]["flip"] = value(row.image.flip);
    c["image"]["flip_ci"] = interval_json(row.intervals.flip);
    c["view"]["rmse_grazing_ci"] = interval_json(row.intervals.view_rmse_grazing);
    c["view"]["bias_grazing_ci"] = interval_json(row.intervals.view_bias_grazing);
    out.push_back(std::move(c));
  }
  return out;
}

// The scenes of a section's variants, in order of first appearance.
std::vector<std::string> section_scenes(const Plan& plan, SectionKind kind) {
  std::vector<std::string> names;
  for (const Variant& v : plan.variants)
    if (v.section == kind && std::find(names.begin(), names.end(), v.scene) == names.end())
      names.push_back(v.scene);
  return names;
}

json bump_rank_json(const std::vector<RankEntry>& entries) {
  json list = json::array();
  for (const RankEntry& e : entries)
    list.push_back({{"method", e.method}, {"mean", e.mean}, {"count", e.count}});
  return list;
}

json lowpoly_rank_json(const std::vector<RankEntry>& entries) {
  json list = json::array();
  for (const RankEntry& e : entries) {
    json entry = {{"offset", e.method},
                  {"darkened_fraction", e.mean},
                  {"darkened_fraction_ci", {e.interval.low, e.interval.high}},
                  {"rmse_terminator", e.second},
                  {"count", e.count},
                  {"versus_best", nullptr}};
    if (e.versus_best)
      entry["versus_best"] = {{"pairs", e.versus_best->n},
                              {"mean_difference", e.versus_best->mean_difference},
                              {"ci", {e.versus_best->interval.low, e.versus_best->interval.high}},
                              {"tie", e.versus_best->interval.contains(0.0)}};
    list.push_back(std::move(entry));
  }
  return list;
}

// Whole scenes a renderer leaves out, one row each; variants it leaves out
// (a glossy material), one row per renderer and reason with their ids.
json skipped_json(const Plan& plan, SectionKind kind) {
  json out = json::array();
  for (const SkippedRenderer& s : plan.skipped)
    if (s.section == kind && s.variant.empty())
      out.push_back({{"renderer", to_string(s.renderer)}, {"scene", s.scene}, {"why", s.why}});
  for (const SkippedRenderer& s : plan.skipped) {
    if (s.section != kind || s.variant.empty()) continue;
    auto row = std::find_if(out.begin(), out.end(), [&](const json& r) {
      return r.contains("variants") && r["renderer"] == to_string(s.renderer) && r["why"] == s.why;
    });
    if (row == out.end())
      out.push_back(
          {{"renderer", to_string(s.renderer)}, {"variants", json::array()}, {"why", s.why}});
    row = std::find_if(out.begin(), out.end(), [&](const json& r) {
      return r.contains("variants") && r["renderer"] == to_string(s.renderer) && r["why"] == s.why;
    });
    (*row)["variants"].push_back(s.variant);
  }
  return out;
}

}  // namespace

namespace {

// Per renderer of a section: what it offers of the study's methods, and a
// "missing" row (with the table's reason) for each one it does not.
struct Offered {
  json renderers = json::array();
  json missing = json::array();
};

Offered offered_json(const ReportInputs& in, const Section& section) {
  const bool bump = section.kind == SectionKind::kBump;
  Offered out;
  out.missing = bump ? json::array() : skipped_json(in.plan, section.kind);
  // A low-poly-only study has no bump rows to offer or miss.
  if (section.scenes.empty()) return out;
  for (RendererKind r : section.renderers) {
    const RendererInfo& info = renderer_info(r);
    json offered = json::array();
    for (const StudyMethod& m : section.methods) {
      const bool has = bump ? offers(r, Representation::kBump, *method_from_id(m.id))
                            : offers(r, *offset_method_from_id(m.id));
      if (has)
        offered.push_back(m.label);
      else
        out.missing.push_back({{"renderer", info.id},
                               {bump ? "method" : "offset", m.label},
                               {"why", bump ? info.methods_why_not : info.offsets_why_not}});
    }
    if (bump) {
      const auto version = in.versions.find(r);
      out.renderers.push_back(
          {{"id", info.id},
           {"version", version != in.versions.end() ? json(version->second) : json()},
           {"methods", offered},
           {"note", info.note}});
    } else {
      out.renderers.push_back({{"id", info.id}, {"offsets", offered}});
    }
  }
  if (bump)
    for (json& s : skipped_json(in.plan, section.kind)) out.missing.push_back(std::move(s));
  return out;
}

json lowpoly_json(const ReportInputs& in) {
  const Section& part = *in.study.lowpoly;
  const std::vector<ComparisonRow>& rows = in.comparisons.rows;
  json per_scene = json::array();
  for (const std::string& name : section_scenes(in.plan, SectionKind::kLowPoly))
    per_scene.push_back(
        {{"scene", name}, {"offsets", lowpoly_rank_json(rank_lowpoly(in.plan, part, rows, name))}});
  const Offered offered = offered_json(in, part);
  return {{"axes", axes_json(part.axes)},
          {"convergence_axis",
           part.convergence_axis >= 0 ? json(part.axes[part.convergence_axis].pointer) : json()},
          {"renderers", offered.renderers},
          {"variants", variants_json(in, SectionKind::kLowPoly)},
          {"comparisons", comparisons_json(in, SectionKind::kLowPoly)},
          {"ranking",
           {{"metric", "shadow.darkened_fraction"},
            {"reference", "evaluator:analytic"},
            {"renderer", "evaluator"},
            {"per_scene", per_scene},
            {"overall", lowpoly_rank_json(rank_lowpoly(in.plan, part, rows, ""))}}},
          {"missing", offered.missing},
          {"units",
           {{"darkened_fraction",
             "fraction of the pixels lit in the analytic render (>= 0.05 albedo*E/pi) that "
             "the mesh renders below half of it"},
            {"max_darkening", "largest analytic - mesh radiance, fraction of albedo*E/pi"},
            {"lost_shadow_fraction",
             "fraction of the analytic render's cast-shadow pixels (theta < 85 deg, below "
             "half of cos theta) that the mesh render lights"},
            {"shadow_shift_px", "distance between the two cast-shadow centroids, pixels"}}}};
}

json units_json() {
  return {{"profile", "fraction of albedo*E/pi"},
          {"intervals",
           fmt::format("*_ci: 95 % interval of a paired block bootstrap over {} bands of image "
                       "rows, {} resamples, seed 1, centred on the estimate (analysis/intervals.h)",
                       kIntervalBands, kIntervalResamples)},
          {"angles", "degrees"},
          {"image", "W m^-2 sr^-1"},
          {"view", "fraction of albedo*E/pi: lit pixels (theta < 60 deg) binned by the view angle"},
          {"grazing_region_deg", {kGrazingBegin, kGrazingEnd}},
          {"theta", "angle between wi and the base (undisplaced) surface normal"},
          {"terminator_region_deg", {kTerminatorBegin, kTerminatorEnd}},
          {"lit_region_deg", {0.0, kLitEnd}},
          {"dark_level", kDarkLevel}};
}

json paired_json(const PairedComparison& c) {
  return {{"pairs", c.n},
          {"better", c.a_better},
          {"worse", c.b_better},
          {"equal", c.equal},
          {"mean_difference", value(c.mean_difference)},
          {"ci", interval_json(c.interval)},
          {"p_sign_test", c.p}};
}

json means_json(const MethodStatistics& m) {
  json out = json::object();
  for (std::size_t k = 0; k < m.means.size(); ++k)
    out[ranked_quantities()[k].id] = {{"mean", value(m.means[k].mean)},
                                      {"ci", interval_json(m.means[k].interval)}};
  return out;
}

json method_statistics_json(const MethodStatistics& m) {
  return {{"method", m.method},
          {"rank", m.rank},
          {"group_leader", m.group_leader},
          {"versus_leader",
           {{"mean_difference", value(m.versus_leader.n ? m.versus_leader.mean_difference : 0.0)},
            {"ci",
             m.versus_leader.n ? interval_json(m.versus_leader.interval) : json::array({0.0, 0.0})},
            {"pairs", m.versus_leader.n}}},
          {"means", means_json(m)},
          {"rejected", m.rejected.empty() ? json() : json(m.rejected)},
          {"variants", m.variants},
          {"combined_relative_error", value(m.combined)},
          {"combined_ci", interval_json(m.combined_interval)},
          {"terminator_improvement", value(m.terminator_improvement)},
          {"terminator_improvement_ci", interval_json(m.terminator_interval)},
          {"terminator_vs_none", paired_json(m.terminator)},
          {"view_vs_none", paired_json(m.view)},
          {"view_bias", value(m.view_bias)},
          {"view_bias_ci", interval_json(m.view_bias_interval)},
          {"view_darker_variants", m.view_darker},
          {"view_darker_mean", value(m.view_darker_mean)}};
}

json ranking_statistics_json(const RankingStatistics& s) {
  json methods = json::array(), pairs = json::array();
  for (const MethodStatistics& m : s.methods) methods.push_back(method_statistics_json(m));
  for (const PairStatistics& p : s.pairs)
    pairs.push_back({{"a", p.a},
                     {"b", p.b},
                     {"combined", paired_json(p.combined)},
                     {"separated", p.separated}});
  return {{"scene", s.scene.empty() ? json() : json(s.scene)},
          {"variants", s.variants},
          {"confidence", s.confidence},
          {"methods", methods},
          {"pairs", pairs},
          {"headline", s.headline}};
}

// Cross-renderer agreement (study/ranking.h): summaries and every row.
json agreement_json(const ReportInputs& in) {
  json summaries = json::array(), rows = json::array(), headline = json::array();
  for (const AgreementSummary& a : agreement_summaries(in.comparisons.agreement)) {
    summaries.push_back({{"renderer", to_string(a.renderer)},
                         {"what", a.what},
                         {"variants", a.variants},
                         {"mean_rmse_terminator", value(a.mean)},
                         {"ci", interval_json(a.interval)},
                         {"max_rmse_terminator", value(a.max)},
                         {"above_threshold", a.above}});
    headline.push_back(a.sentence);
  }
  for (const AgreementRow& r : in.comparisons.agreement)
    rows.push_back({{"variant", in.plan.variants[r.variant].id},
                    {"renderer", to_string(r.renderer)},
                    {"what", r.what},
                    {"rmse_terminator", value(r.profile.rmse_terminator)},
                    {"rmse_terminator_ci", interval_json(r.intervals.rmse_terminator)}});
  return {{"definition",
           "each external renderer's render against the evaluator's render of the same scene "
           "(ground truth: displacement, method none; or a method both implement), "
           "terminator-region profile RMSE as a fraction of albedo*E/pi"},
          {"threshold", kAgreementThreshold},
          {"summaries", summaries},
          {"rows", rows},
          {"headline", headline}};
}

json interactions_json(const AxisStatistics& a) {
  json out = json::array();
  for (const Interaction& i : a.interactions) {
    json levels = json::array();
    for (const LevelRanking& l : a.levels) {
      const MethodStatistics* m = l.ranking.find(i.method);
      if (!m) continue;
      const char* verdict = m->combined_interval.high < 1.0  ? "helps"
                            : m->combined_interval.low > 1.0 ? "hurts"
                                                             : "tie";
      levels.push_back({{"value_label", l.value_label},
                        {"value_id", l.value_id},
                        {"combined", value(m->combined)},
                        {"combined_ci", interval_json(m->combined_interval)},
                        {"verdict", verdict}});
    }
    out.push_back({{"method", i.method},
                   {"statistic", i.test.statistic},
                   {"blocks", i.test.blocks},
                   {"p", i.test.p},
                   {"p_holm", i.p_holm},
                   {"depends", i.depends},
                   {"levels", levels}});
  }
  return out;
}

json by_axis_json(const StudyStatistics& s) {
  json out = json::array();
  for (const AxisStatistics& a : s.by_axis) {
    json levels = json::array();
    for (const LevelRanking& l : a.levels)
      levels.push_back({{"value", l.value},
                        {"value_label", l.value_label},
                        {"value_id", l.value_id},
                        {"ranking", ranking_statistics_json(l.ranking)}});
    out.push_back({{"pointer", a.pointer},
                   {"label", a.label},
                   {"numeric", a.numeric},
                   {"levels", levels},
                   {"interactions", interactions_json(a)}});
  }
  return out;
}

// Rankings with statistics (study/ranking.h): overall, per scene, per level
// of each axis, with the interaction tests and the report's lead.
json statistics_json(const ReportInputs& in) {
  const StudyStatistics s = study_statistics(in.plan, in.comparisons.rows, in.study.bump.axes);
  json per_scene = json::array();
  for (const RankingStatistics& r : s.per_scene) per_scene.push_back(ranking_statistics_json(r));
  return {{"definition",
           "per variant v and method m, evaluator against its displacement ground truth, both as "
           "fractions of albedo*E/pi: E_term = terminator-region profile RMSE (binned by the light "
           "angle, [60, 100) deg); E_view = grazing-view RMSE (lit pixels, theta < 60 deg, binned "
           "by the view angle, [60, 75) deg); combined relative error C = (E_term + E_view) / "
           "(E_term(none) + E_view(none)), 1 for raw bump, lower is better; terminator improvement "
           "= 1 - mean(E_term/E_term(none)); view_vs_none: paired E_view - E_view(none)"},
          {"primary_metric",
           {{"id", "combined_relative_error"},
            {"name", "combined error relative to raw bump"},
            {"unit", ranked_quantities().front().unit}}},
          {"confidence", kRankingFamilyConfidence},
          {"interval",
           "percentile bootstrap over variants, seed 1: intervals of the combined error and of "
           "paired differences at each ranking's confidence (95 % simultaneous over its K - 1 "
           "comparisons, Bonferroni; 10,000 resamples, 20,000 for the rank groups' paired "
           "differences); means of the other quantities at 95 %, 10,000 resamples"},
          {"test",
           fmt::format("rank groups by the rule below; interactions: permutation test of the "
                       "variance of the level means of C, levels exchanged within matched variants "
                       "(same scene and other axes), {} permutations, seed 1, Holm-adjusted over "
                       "every method and axis; depends when p_holm < {}",
                       kInteractionPermutations, kSignificance)},
          {"rule", rank_rule_text(s.overall.methods.size())},
          {"baseline", "none"},
          {"reference", "evaluator:displacement"},
          {"overall", ranking_statistics_json(s.overall)},
          {"per_scene", per_scene},
          {"by_axis", by_axis_json(s)},
          {"headline", s.headline},
          {"notes", s.notes}};
}

json bump_ranking_json(const ReportInputs& in) {
  json per_scene = json::array();
  for (const std::string& s : section_scenes(in.plan, SectionKind::kBump))
    per_scene.push_back(
        {{"scene", s}, {"methods", bump_rank_json(rank_bump(in.plan, in.comparisons.rows, s))}});
  return {{"metric", "profile.rmse_terminator"},
          {"reference", "evaluator:displacement"},
          {"renderer", "evaluator"},
          {"per_scene", per_scene},
          {"overall", bump_rank_json(rank_bump(in.plan, in.comparisons.rows, ""))}};
}

// The convergence of each variant's evaluator truth (study/convergence.h).
json ground_truth_json(const ReportInputs& in) {
  json variants = json::array();
  std::size_t converged = 0;
  double worst = 0.0;
  std::map<std::string, double> floor;  // per scene: the largest change reached
  for (const VariantConvergence& c : in.convergence) {
    double& f = floor[in.plan.variants[c.variant].scene];
    f = std::isfinite(c.reached) ? std::max(f, c.reached) : f;
    json steps = json::array();
    for (const ConvergenceStep& s : c.steps)
      steps.push_back({{"edge_length", s.edge_length},
                       {"spp", s.spp},
                       {"edge_change", value(s.edge_change)},
                       {"spp_change", value(s.spp_change)}});
    variants.push_back({{"variant", in.plan.variants[c.variant].id},
                        {"label", in.plan.variants[c.variant].label},
                        {"edge_length", c.edge_length},
                        {"spp", c.spp},
                        {"reached", value(c.reached)},
                        {"converged", c.converged},
                        {"why", c.converged ? json() : json(c.why)},
                        {"steps", steps}});
    converged += c.converged;
    worst = std::isfinite(c.reached) ? std::max(worst, c.reached) : worst;
  }
  const GroundTruthSettings& g = in.study.ground_truth;
  std::string headline =
      in.convergence.empty()
          ? std::string("no evaluator ground truth to check")
          : fmt::format(
                "{} of {} ground truths converged to a change below {:g} of albedo*E/pi "
                "(largest change reached {:.2g}){}.",
                converged, in.convergence.size(), g.tolerance, worst,
                converged == in.convergence.size()
                    ? ""
                    : "; the others are flagged below and their numbers are provisional");
  return {{"definition",
           "each variant's evaluator truth against itself with the edge length halved and with "
           "4x the samples per pixel; change = max(terminator-region profile RMSE, grazing-view "
           "RMSE) between the two, fraction of albedo*E/pi; refined until both changes are "
           "below the tolerance or the budget ends; the variant's evaluator renders use the "
           "settings reached"},
          {"tolerance", g.tolerance},
          {"max_edge_refinements", g.max_edge_refinements},
          {"max_spp_refinements", g.max_spp_refinements},
          {"converged", converged},
          {"floor_per_scene", floor},
          {"floor",
           "per scene, the largest change reached: how far any metric of that scene can move "
           "with a finer truth; differences below it are not resolved"},
          {"headline", headline},
          {"variants", variants}};
}

json report_json(const ReportInputs& in) {
  const Offered offered = offered_json(in, in.study.bump);
  json failures = json::array();
  for (std::size_t i = 0; i < in.plan.jobs.size(); ++i)
    if (!in.done[i])
      failures.push_back({{"render", in.plan.jobs[i].label}, {"error", in.errors[i]}});
  json plots = json::array();
  for (const StudyPlot& p : in.study.plots)
    plots.push_back(
        {{"metric", p.metric}, {"x", p.x}, {"y", p.y}, {"kind", p.kind}, {"renderer", p.renderer}});
  return {{"format", "penumbra-report"},
          {"version", kReportFormatVersion},
          {"penumbra", kPenumbraVersion},
          // Absolute: the same study run as `study.json` or `./study.json`
          // gives the same report (and keeps its figures).
          {"study", {{"name", in.study.name}, {"file", in.study.absolute_file}}},
          {"provenance", provenance_json(collect_provenance(in.study.absolute_file, in.versions))},
          {"notices", in.study.notices},
          {"figures", {{"methods", in.study.figure_methods}}},
          {"units", units_json()},
          {"axes", axes_json(in.study.bump.axes)},
          {"renderers", offered.renderers},
          {"variants", variants_json(in, SectionKind::kBump)},
          {"comparisons", comparisons_json(in, SectionKind::kBump)},
          {"ranking", bump_ranking_json(in)},
          {"statistics", statistics_json(in)},
          {"agreement", agreement_json(in)},
          {"ground_truth", ground_truth_json(in)},
          {"missing", offered.missing},
          {"failures", failures},
          {"nonfinite_pixels", in.comparisons.nonfinite},
          {"plots", plots},
          {"lowpoly", in.study.lowpoly ? lowpoly_json(in) : json()},
          {"filtering", filtering_report_json(in.filtering, in.study.filtering.has_value())},
          {"interplay", interplay_report_json(in.study.interplay ? &*in.study.interplay : nullptr,
                                              in.interplay)}};
}

}  // namespace

constexpr const char* kLowpolyCsv = "lowpoly.csv";
constexpr const char* kReportJson = "report.json";
constexpr const char* kMetricsCsv = "metrics.csv";
constexpr const char* kMetricsLongCsv = "metrics-long.csv";

void write_report_files(const ReportInputs& in, const std::string& folder) {
  const fs::path out(folder);
  if (in.study.lowpoly)
    write_text_file((out / kLowpolyCsv).string(),
                    comparison_csv(in, *in.study.lowpoly, lowpoly_columns()));
  write_text_file((out / kReportJson).string(), report_json(in).dump(1) + "\n");
  write_text_file((out / kMetricsCsv).string(), comparison_csv(in, in.study.bump, bump_columns()));
  write_text_file((out / kMetricsLongCsv).string(), long_csv(in, in.study.bump));
}

namespace {

void check_string_lengths(const json& j, const json::json_pointer& at, const std::string& file) {
  if (j.is_string() && j.get_ref<const std::string&>().size() > kMaxReportString)
    throw InputError(file, at.to_string(),
                     fmt::format("expected a string of at most {} bytes, got {}", kMaxReportString,
                                 j.get_ref<const std::string&>().size()));
  if (j.is_object())
    for (const auto& [key, value] : j.items()) check_string_lengths(value, at / key, file);
  if (j.is_array())
    for (std::size_t i = 0; i < j.size(); ++i) check_string_lengths(j[i], at / i, file);
}

}  // namespace

json read_report_json(const std::string& path) {
  json doc = read_json_file(path);
  check_string_lengths(doc, json::json_pointer(), path);
  return doc;
}

void remove_report_files(const std::string& folder) {
  std::error_code ignored;
  for (const char* name : {kLowpolyCsv, kReportJson, kMetricsCsv, kMetricsLongCsv})
    fs::remove(fs::path(folder) / name, ignored);
}

}  // namespace penumbra
