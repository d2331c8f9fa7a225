#include "study/interplay.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <fmt/format.h>

#include "analysis/filtering.h"
#include "analysis/measure.h"
#include "core/roughness_filter.h"
#include "core/surface_map.h"
#include "core/terminator.h"
#include "image/bump_maps.h"
#include "image/image_io.h"
#include "renderers/renderers.h"
#include "scene/scene_json.h"
#include "study/plan.h"
#include "study/rendering.h"
#include "util/strict_json.h"

namespace penumbra {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// The scene document after the section's set, without its name (not content).
json base_document(const InterplaySection& s) {
  json doc = read_json_file(s.scene);
  std::vector<Override> overrides;
  for (const auto& [pointer, value] : s.set.items()) overrides.push_back({pointer, value});
  apply_overrides(doc, overrides, s.scene + " (study /interplay/set)");
  resolve_map_files(doc, s.scene);
  doc.erase("name");
  return doc;
}

std::string level_text(const std::optional<int>& level) {
  return level ? fmt::format("level {}", *level) : std::string("unfiltered");
}

struct JobSpec {
  Representation representation = Representation::kBump;
  std::string method = "none";
  std::optional<int> level;
  double edge_length = 0.0;  // displacement: the grid's; 0 keeps the scene's
};

Job make_job(const json& base, const InterplaySection& s, const std::string& map_path,
             const JobSpec& spec) {
  json doc = base;
  json height = {{"type", "height-map"}, {"file", map_path}, {"amplitude", 1}};
  if (spec.level) height["filter"] = {{"method", s.filter}, {"level", *spec.level}};
  doc["height"] = height;
  doc["representation"] = to_string(spec.representation);
  doc["terminator"]["method"] = spec.method;
  if (spec.edge_length > 0.0) doc["displacement"]["edge_length"] = spec.edge_length;
  Job job;
  job.renderer = RendererKind::kEvaluator;
  job.representation = spec.representation;
  job.truth = spec.representation == Representation::kDisplacement;
  job.method = spec.method;
  job.label = job.truth ? fmt::format("interplay-displacement-edge{}", spec.edge_length)
                        : fmt::format("interplay-{}-{}", spec.method, level_text(spec.level));
  std::string origin = s.scene + " (study /interplay, " + job.label + ")";
  Scene scene = scene_from_json(doc, origin);
  job.set_scene(std::move(doc), std::move(scene), std::move(origin));
  return job;
}

std::string percent(double value, const Interval& ci) {
  return fmt::format("{:.2f} % [{:.2f}, {:.2f}]", 100.0 * value, 100.0 * ci.low, 100.0 * ci.high);
}

// Lower, higher or a tie: whether the two 95 % intervals overlap.
const char* against(const Interval& a, const Interval& b) {
  if (a.high < b.low) return "lower";
  if (a.low > b.high) return "higher";
  return "tie";
}

std::vector<std::string> interplay_findings(const InterplaySection& s, const InterplayResult& r) {
  std::vector<std::string> out;
  const std::size_t nm = s.methods.size();
  const auto row = [&](std::size_t level, std::size_t method) -> const InterplayRow& {
    return r.rows[level * nm + method];
  };
  const std::size_t last = s.levels.size() - 1;
  for (std::size_t m = 0; m < nm && last > 0; ++m) {
    const InterplayRow& a = row(0, m);
    const InterplayRow& b = row(last, m);
    const char* v = against(b.intervals.rmse_terminator, a.intervals.rmse_terminator);
    out.push_back(fmt::format(
        "{}: terminator RMSE {} {}, {} {} ({}).", s.methods[m], level_text(a.level),
        percent(a.profile.rmse_terminator, a.intervals.rmse_terminator), level_text(b.level),
        percent(b.profile.rmse_terminator, b.intervals.rmse_terminator),
        std::string(v) == "tie" ? "a tie: the intervals overlap"
                                : fmt::format("{} at {}", v, level_text(b.level))));
  }
  for (std::size_t m = 1; m < nm; ++m) {
    std::string per_level;
    for (std::size_t l = 0; l < s.levels.size(); ++l)
      per_level += fmt::format(
          "{}{} {}", l ? ", " : "", level_text(s.levels[l]),
          against(row(l, m).intervals.rmse_terminator, row(l, 0).intervals.rmse_terminator));
    out.push_back(
        fmt::format("{} against {} per level (lower, higher or a tie by the overlap of "
                    "the 95 % intervals): {}.",
                    s.methods[m], s.methods[0], per_level));
  }
  out.push_back(fmt::format(
      "The truth (displaced grid, edge {:g}) moves by {} of albedo*E/pi in the terminator region "
      "when its edge length halves.",
      r.edge_length, percent(r.truth_change, r.truth_change_interval)));
  return out;
}

// The map over the shape's (u, v), as `penumbra bake --on shape` makes it.
std::string bake_map(const json& base, const InterplaySection& s, const fs::path& folder,
                     InterplayResult& result) {
  const Scene scene = scene_from_json(base, s.scene + " (study /interplay)");
  if (scene.height.family == HeightFamily::kNone || scene.height.map)
    throw InputError(s.scene, "/height", "expected an analytic height function to bake");
  const int rows = shape_map_rows(scene.shape, s.size, kMaxImageSize);
  const Image map = bake_surface_map(scene.shape, scene.height.function, scene.height.amplitude,
                                     s.size, rows, MapKind::kHeight);
  fs::create_directories(folder);
  const fs::path path = fs::absolute(folder / "map.exr");
  write_exr(map, path.string(), {{"penumbra:baked_from", s.scene}});
  result.map_width = map.width, result.map_height = map.height;
  result.edge_length = scene.displacement.edge_length;
  return path.string();
}

}  // namespace

InterplayJobs plan_interplay_section(const InterplaySection& s, const StepContext& context) {
  InterplayJobs planned;
  InterplayResult& result = planned.result;
  const json base = base_document(s);
  const std::string map_path = bake_map(base, s, fs::path(context.out_dir) / "interplay", result);
  result.map_file = "interplay/map.exr";
  std::vector<Job>& work = planned.jobs;
  work.push_back(
      make_job(base, s, map_path, {Representation::kDisplacement, "none", std::nullopt, 0.0}));
  work.push_back(
      make_job(base, s, map_path,
               {Representation::kDisplacement, "none", std::nullopt, 0.5 * result.edge_length}));
  for (const std::optional<int>& level : s.levels)
    for (const std::string& method : s.methods)
      work.push_back(make_job(base, s, map_path, {Representation::kBump, method, level, 0.0}));
  assign_keys(work, context.renderers.identities);
  result.map_digest = work[0].scene().height.map->digest;
  result.truth_key = work[0].key;
  return planned;
}

InterplayResult measure_interplay_section(const InterplaySection& s, const InterplayJobs& planned,
                                          const SectionRenders& renders,
                                          const StepContext& context) {
  const std::vector<Job>& work = planned.jobs;
  for (std::size_t i = 0; i < work.size(); ++i)
    if (!renders.done[i]) throw RendererError(renders.errors[i]);
  InterplayResult result = planned.result;
  for (std::size_t i = 0; i < work.size(); ++i)
    ++(renders.cached[i] ? result.reused : result.rendered);
  const Image& truth = renders.images[0];
  // The terminator profile and its interval only.
  MeasureOptions profile;
  profile.scale = radiance_scale(work[0].scene());
  profile.image = profile.view = false;
  // The truth (as the test) against the truth at half its edge length.
  const Measurement check = measure(truth, renders.images[1], profile);
  result.truth_change = check.profile.rmse_terminator;
  result.truth_change_interval = check.intervals.rmse_terminator;
  for (std::size_t i = 2; i < work.size(); ++i) {
    const std::size_t k = i - 2;
    const Measurement m = measure(renders.images[i], truth, profile);
    InterplayRow row{s.levels[k / s.methods.size()], s.methods[k % s.methods.size()], work[i].key,
                     m.profile, m.intervals};
    result.rows.push_back(std::move(row));
    if (context.log)
      context.log(fmt::format("interplay: {} {}: {}/{} done", result.rows.back().method,
                              level_text(result.rows.back().level), k + 1, work.size() - 2));
  }
  result.findings = interplay_findings(s, result);
  if (context.log)
    context.log(fmt::format("interplay: {} renders, {} rendered now, {} from the cache",
                            work.size(), result.rendered, result.reused));
  return result;
}

json interplay_report_json(const InterplaySection* s, const InterplayResult* r) {
  if (!s || !r) return nullptr;
  const auto number = [](double x) { return std::isfinite(x) ? json(x) : json(nullptr); };
  json rows = json::array();
  for (const InterplayRow& row : r->rows)
    rows.push_back(
        {{"level", row.level ? json(*row.level) : json(nullptr)},
         {"method", row.method},
         {"rmse_terminator", number(row.profile.rmse_terminator)},
         {"rmse_terminator_ci",
          {number(row.intervals.rmse_terminator.low), number(row.intervals.rmse_terminator.high)}},
         {"rmse_overall", number(row.profile.rmse_overall)},
         {"position_error_deg", number(row.profile.position_error)},
         {"image", RenderCache::relative_exr(row.key)}});
  json levels = json::array();
  for (const std::optional<int>& l : s->levels) levels.push_back(l ? json(*l) : json(nullptr));
  return {
      {"scene", s->scene},
      {"map",
       {{"file", r->map_file}, {"size", {r->map_width, r->map_height}}, {"digest", r->map_digest}}},
      {"filter", s->filter},
      {"levels", levels},
      {"methods", s->methods},
      {"compared_against",
       fmt::format("the evaluator's displacement of the same height map (grid edge {:g} scene "
                   "units), unfiltered",
                   r->edge_length)},
      {"truth", RenderCache::relative_exr(r->truth_key)},
      {"truth_check",
       {{"edge_length", 0.5 * r->edge_length},
        {"rmse_terminator", number(r->truth_change)},
        {"rmse_terminator_ci",
         {number(r->truth_change_interval.low), number(r->truth_change_interval.high)}}}},
      {"units",
       "rmse_terminator and rmse_overall: fraction of albedo*E/pi; intervals: 95 % paired "
       "block bootstrap over bands of image rows; position_error_deg: degrees"},
      {"rows", rows},
      {"findings", r->findings}};
}

}  // namespace penumbra
