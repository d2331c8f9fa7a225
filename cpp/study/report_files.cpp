#include "study/report_files.h"

#include <cmath>
#include <filesystem>
#include <functional>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "analysis/metrics_json.h"
#include "core/tessellation.h"
#include "image/image_io.h"
#include "scene/scene_json.h"
#include "study/cache.h"
#include "study/ranking.h"

namespace penumbra {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// ---- CSV ----------------------------------------------------------------------

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

// An undefined quantity (NaN) is an empty field.
std::string number(double v) {
  return std::isfinite(v) ? fmt::format("{}", v) : std::string();
}
std::string count(std::size_t n) {
  return fmt::format("{}", n);
}

struct Column {
  const char* name;
  std::function<std::string(const ComparisonRow&)> value;
};

const std::vector<Column>& bump_columns() {
  static const std::vector<Column> columns{
      {"profile_rmse_terminator", [](auto& r) { return number(r.profile.rmse_terminator); }},
      {"profile_rmse_overall", [](auto& r) { return number(r.profile.rmse_overall); }},
      {"profile_max_error_terminator", [](auto& r) { return number(r.profile.max_error); }},
      {"profile_max_step", [](auto& r) { return number(r.profile.max_step); }},
      {"reference_max_step", [](auto& r) { return number(r.profile.reference_max_step); }},
      {"position_deg", [](auto& r) { return number(r.profile.position); }},
      {"reference_position_deg", [](auto& r) { return number(r.profile.reference_position); }},
      {"position_error_deg", [](auto& r) { return number(r.profile.position_error); }},
      {"width_deg", [](auto& r) { return number(r.profile.width); }},
      {"reference_width_deg", [](auto& r) { return number(r.profile.reference_width); }},
      {"lit_bias", [](auto& r) { return number(r.profile.lit_bias); }},
      {"common_bins", [](auto& r) { return count(r.profile.common_bins); }},
      {"image_mask_iou", [](auto& r) { return number(r.image.mask_iou); }},
      {"image_rmse", [](auto& r) { return number(r.image.rmse); }},
      {"image_ssim", [](auto& r) { return number(r.image.ssim); }},
      {"image_max_error", [](auto& r) { return number(r.image.max_error); }},
      {"image_mean_error", [](auto& r) { return number(r.image.mean_error); }},
      {"image_pixels", [](auto& r) { return count(r.image.pixels); }},
      {"image_nonfinite", [](auto& r) { return count(r.image.nonfinite); }},
      {"profile_rmse_terminator_ci_low",
       [](auto& r) { return number(r.intervals.rmse_terminator.low); }},
      {"profile_rmse_terminator_ci_high",
       [](auto& r) { return number(r.intervals.rmse_terminator.high); }},
      {"image_rmse_ci_low", [](auto& r) { return number(r.intervals.image_rmse.low); }},
      {"image_rmse_ci_high", [](auto& r) { return number(r.intervals.image_rmse.high); }},
      {"profile_max_error_terminator_ci_low",
       [](auto& r) { return number(r.intervals.max_error.low); }},
      {"profile_max_error_terminator_ci_high",
       [](auto& r) { return number(r.intervals.max_error.high); }},
      {"position_error_deg_ci_low", [](auto& r) { return number(r.intervals.position_error.low); }},
      {"position_error_deg_ci_high",
       [](auto& r) { return number(r.intervals.position_error.high); }},
      {"lit_bias_ci_low", [](auto& r) { return number(r.intervals.lit_bias.low); }},
      {"lit_bias_ci_high", [](auto& r) { return number(r.intervals.lit_bias.high); }},
      {"view_rmse_grazing", [](auto& r) { return number(r.view.rmse_grazing); }},
      {"view_rmse_grazing_ci_low",
       [](auto& r) { return number(r.intervals.view_rmse_grazing.low); }},
      {"view_rmse_grazing_ci_high",
       [](auto& r) { return number(r.intervals.view_rmse_grazing.high); }},
      {"view_bias_grazing", [](auto& r) { return number(r.view.bias_grazing); }},
      {"view_bias_grazing_ci_low",
       [](auto& r) { return number(r.intervals.view_bias_grazing.low); }},
      {"view_bias_grazing_ci_high",
       [](auto& r) { return number(r.intervals.view_bias_grazing.high); }},
      {"view_pixels", [](auto& r) { return count(r.view.pixels); }},
  };
  return columns;
}

const std::vector<Column>& lowpoly_columns() {
  static const std::vector<Column> columns{
      {"darkened_fraction", [](auto& r) { return number(r.shadow->darkened_fraction); }},
      {"max_darkening", [](auto& r) { return number(r.shadow->max_darkening); }},
      {"lost_shadow_fraction", [](auto& r) { return number(r.shadow->lost_shadow_fraction); }},
      {"shadow_shift_px", [](auto& r) { return number(r.shadow->shadow_shift_px); }},
      {"shadowed_pixels", [](auto& r) { return count(r.shadow->shadowed_pixels); }},
      {"test_shadowed_pixels", [](auto& r) { return count(r.shadow->test_shadowed_pixels); }},
      {"profile_rmse_terminator", [](auto& r) { return number(r.profile.rmse_terminator); }},
      {"profile_rmse_overall", [](auto& r) { return number(r.profile.rmse_overall); }},
      {"profile_max_step", [](auto& r) { return number(r.profile.max_step); }},
      {"position_error_deg", [](auto& r) { return number(r.profile.position_error); }},
      {"lit_bias", [](auto& r) { return number(r.profile.lit_bias); }},
      {"image_rmse", [](auto& r) { return number(r.image.rmse); }},
      {"image_ssim", [](auto& r) { return number(r.image.ssim); }},
      {"image_mask_iou", [](auto& r) { return number(r.image.mask_iou); }},
      {"image_nonfinite", [](auto& r) { return count(r.image.nonfinite); }},
      {"profile_rmse_terminator_ci_low",
       [](auto& r) { return number(r.intervals.rmse_terminator.low); }},
      {"profile_rmse_terminator_ci_high",
       [](auto& r) { return number(r.intervals.rmse_terminator.high); }},
  };
  return columns;
}

// Header and rows: study, variant, scene, one column per axis, renderer,
// method (or offset), reference, then `columns`.
std::string comparison_csv(const ReportInputs& in, const Section& section,
                           const std::vector<Column>& columns) {
  const bool bump = section.kind == SectionKind::kBump;
  std::string csv = "study,variant,scene";
  for (const StudyAxis& a : section.axes) csv += "," + csv_field(a.pointer);
  csv += bump ? ",renderer,method,reference" : ",renderer,offset,reference";
  for (const Column& c : columns) csv += std::string(",") + c.name;
  csv += "\n";
  for (const ComparisonRow& row : in.comparisons.rows) {
    const Variant& var = in.plan.variants[row.variant];
    if (var.section != section.kind) continue;
    csv += fmt::format("{},{},{}", csv_field(in.study.name), var.id, csv_field(var.scene));
    for (const json& value : var.axis_values) csv += "," + csv_field(value.dump());
    csv += fmt::format(",{},{},{}", to_string(row.renderer), csv_field(row.method), row.reference);
    for (const Column& c : columns) csv += "," + c.value(row);
    csv += "\n";
  }
  return csv;
}

// ---- report.json ----------------------------------------------------------------

json axes_json(const std::vector<StudyAxis>& axes) {
  json out = json::array();
  for (const StudyAxis& a : axes)
    out.push_back({{"pointer", a.pointer}, {"label", a.label}, {"values", a.values}});
  return out;
}

json render_json(const ReportInputs& in, const RenderRow& r) {
  const Job& job = in.plan.jobs[r.job];
  json out = {{"renderer", to_string(job.renderer)},
              {"image", r.image},
              {"difference", r.difference.empty() ? json() : json(r.difference)},
              {"exr", RenderCache::relative_exr(job.key)},
              {"profile", profile_json(r.profile)}};
  if (in.plan.variants[job.variant].section == SectionKind::kBump) {
    out["representation"] = to_string(job.representation);
    out["method"] = job.method;
  } else {
    out["offset"] = job.method;
    out["triangles"] =
        job.scene.tessellation
            ? json(tessellated_triangle_count(job.scene.shape, *job.scene.tessellation))
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
  for (const RankEntry& e : entries)
    list.push_back({{"offset", e.method},
                    {"darkened_fraction", e.mean},
                    {"rmse_terminator", e.second},
                    {"count", e.count}});
  return list;
}

json skipped_json(const Plan& plan, SectionKind kind) {
  json out = json::array();
  for (const SkippedRenderer& s : plan.skipped)
    if (s.section == kind)
      out.push_back({{"renderer", to_string(s.renderer)}, {"scene", s.scene}, {"why", s.why}});
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
        {{"scene", name}, {"offsets", lowpoly_rank_json(rank_lowpoly(in.plan, rows, name))}});
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
            {"overall", lowpoly_rank_json(rank_lowpoly(in.plan, rows, ""))}}},
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

json method_statistics_json(const MethodStatistics& m) {
  return {{"method", m.method},
          {"rank", m.rank},
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
                     {"p_holm", p.p_holm},
                     {"tied", p.tied}});
  return {{"scene", s.scene.empty() ? json() : json(s.scene)},
          {"variants", s.variants},
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

// Rankings with statistics (study/ranking.h), overall and per scene.
json statistics_json(const ReportInputs& in) {
  json per_scene = json::array();
  for (const std::string& s : section_scenes(in.plan, SectionKind::kBump))
    per_scene.push_back(
        ranking_statistics_json(ranking_statistics(in.plan, in.comparisons.rows, s)));
  return {
      {"definition",
       "per variant v and method m, evaluator against its displacement ground truth, both as "
       "fractions of albedo*E/pi: E_term = terminator-region profile RMSE (binned by the light "
       "angle, [60, 100) deg); E_view = grazing-view RMSE (lit pixels, theta < 60 deg, binned "
       "by the view angle, [60, 75) deg); combined relative error C = (E_term + E_view) / "
       "(E_term(none) + E_view(none)), 1 for raw bump, lower is better; terminator improvement "
       "= 1 - mean(E_term/E_term(none)); view_vs_none: paired E_view - E_view(none)"},
      {"confidence", kRankingConfidence},
      {"interval", "percentile bootstrap over variants, 10000 resamples, seed 1"},
      {"test",
       "two-sided exact sign test over variants; pairs of methods Holm-adjusted as one family; "
       "tied when the interval of the mean paired difference contains 0 or p_holm >= 0.05"},
      {"baseline", "none"},
      {"reference", "evaluator:displacement"},
      {"overall", ranking_statistics_json(ranking_statistics(in.plan, in.comparisons.rows, ""))},
      {"per_scene", per_scene}};
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
          {"study", {{"name", in.study.name}, {"file", in.study.file}}},
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
          {"lowpoly", in.study.lowpoly ? lowpoly_json(in) : json()}};
}

}  // namespace

void write_report_files(const ReportInputs& in, const std::string& folder) {
  const fs::path out(folder);
  if (in.study.lowpoly)
    write_text_file((out / "lowpoly.csv").string(),
                    comparison_csv(in, *in.study.lowpoly, lowpoly_columns()));
  write_text_file((out / "report.json").string(), report_json(in).dump(1) + "\n");
  write_text_file((out / "metrics.csv").string(),
                  comparison_csv(in, in.study.bump, bump_columns()));
}

}  // namespace penumbra
