#include "study/plan.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>

#include <fmt/format.h>

#include "evaluator/displaced_mesh.h"
#include "scene/scene_json.h"
#include "study/light_angles.h"
#include "study/names.h"
#include "util/strict_json.h"

namespace penumbra {
namespace fs = std::filesystem;
using nlohmann::json;

long Plan::find(std::size_t v, RendererKind r, const std::string& method) const {
  for (std::size_t i : variants[v].jobs)
    if (jobs[i].renderer == r && jobs[i].method == method) return static_cast<long>(i);
  return -1;
}

long Plan::truth(std::size_t v, RendererKind r) const {
  for (std::size_t i : variants[v].jobs)
    if (jobs[i].renderer == r && jobs[i].truth) return static_cast<long>(i);
  return -1;
}

namespace {

std::string value_text(const json& v) {
  if (v.is_number_float()) return fmt::format("{:g}", v.get<double>());
  if (v.is_string()) return v.get<std::string>();  // a compound axis's label, unquoted
  return v.dump();
}

bool light_direction(const std::string& pointer, const json& v) {
  return pointer == "/light/direction" && v.is_array() && v.size() == 3 &&
         std::all_of(v.begin(), v.end(), [](const json& x) { return x.is_number(); });
}

Vec3 vec3(const json& v) {
  return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
}

// Combination `c` of the axes (mixed radix, the first axis fastest) as
// overrides after `set`; records the values and extends the label of `v`.
std::vector<Override> axis_combination(const std::vector<Override>& set,
                                       const std::vector<StudyAxis>& axes, std::size_t c,
                                       Variant* v) {
  std::vector<Override> overrides = set;
  for (const StudyAxis& a : axes) {
    const std::size_t k = c % a.values.size();
    const json& value = a.values[k];
    c /= a.values.size();
    if (a.sets.empty()) {
      overrides.push_back({a.pointer, value});
    } else {
      for (const auto& [pointer, set_value] : a.sets[k]) overrides.push_back({pointer, set_value});
    }
    v->axis_values.push_back(value);
    v->label += fmt::format(", {}={}", a.label, value_text(value));
    if (light_direction(a.pointer, value))
      v->label += fmt::format(" ({})", direction_text(vec3(value)));
  }
  return overrides;
}

// ---- what differs between the sections ----------------------------------------

// The overrides that make a variant's scene the truth (m == nullptr) or the
// test of method m.
std::vector<Override> section_overrides(SectionKind kind, const StudyMethod* m) {
  if (kind == SectionKind::kBump) {
    std::vector<Override> o{
        {"/representation", to_string(m ? Representation::kBump : Representation::kDisplacement)},
        {"/terminator/method", m ? m->id : "none"}};
    if (m && m->parameters.is_object()) o.push_back({"/terminator/parameters", m->parameters});
    return o;
  }
  json offset = {{"method", m ? m->id : "none"}};
  if (m && m->parameters.is_object())
    for (const auto& [k, value] : m->parameters.items()) offset[k] = value;
  std::vector<Override> o{{"/offset", offset}};
  if (!m) o.push_back({"/shape/tessellation", nullptr});  // the analytic surface
  return o;
}

bool section_offers(SectionKind kind, RendererKind r, const StudyMethod& m) {
  if (kind == SectionKind::kBump) return offers(r, Representation::kBump, *method_from_id(m.id));
  return offers(r, *offset_method_from_id(m.id));
}

std::string job_label(SectionKind kind, const Variant& v, const Job& job) {
  if (kind == SectionKind::kBump)
    return fmt::format("{}-{}-{}-{}", v.id, to_string(job.renderer), to_string(job.representation),
                       job.method);
  return fmt::format("{}-{}-{}", v.id, to_string(job.renderer), job.method);
}

// Why renderer r cannot render this scene at all ("" when it can).
std::string cannot_render(RendererKind r, const json& scene) {
  const RendererInfo& info = renderer_info(r);
  if (!info.props && scene.contains("props") && !scene["props"].empty()) return info.props_why_not;
  const json::json_pointer type("/height/type");
  if (!info.height_maps && scene.contains(type) && scene[type] == "height-map")
    return info.height_maps_why_not;
  if (!info.normal_maps && scene.contains(type) && scene[type] == "normal-map")
    return info.normal_maps_why_not;
  const json::json_pointer shape("/shape/type");
  if (!info.plane && scene.contains(shape) && scene[shape] == "plane") return info.plane_why_not;
  return "";
}

// Why renderer r cannot render this variant's scene, which it could
// render with other axis values ("" when it can).
std::string cannot_render_variant(RendererKind r, const json& scene) {
  const RendererInfo& info = renderer_info(r);
  // The scene reader checks the value; here only whether the lobe is on.
  const json::json_pointer weight("/material/specular/weight");
  if (!info.specular && scene.contains(weight) && scene[weight].is_number() &&
      scene[weight].get<double>() > 0.0)
    return info.specular_why_not;
  return "";
}

// ---- expansion ------------------------------------------------------------------

struct VariantContext {
  const Section& section;
  const json& base;
  const std::vector<Override>& overrides;
  const std::string& origin;
  const std::string& scene_file;  // a relative /height/file is from its folder
  int blender_spp;
};

void add_job(const VariantContext& c, RendererKind r, const StudyMethod* m, Variant& v,
             std::size_t variant_index, Plan& plan) {
  json doc = c.base;
  std::vector<Override> all = c.overrides;
  for (Override& o : section_overrides(c.section.kind, m)) all.push_back(std::move(o));
  if (r == RendererKind::kBlender) all.push_back({"/camera/spp", c.blender_spp});
  apply_overrides(doc, all, c.origin);
  resolve_map_files(doc, c.scene_file);
  Job job;
  job.variant = variant_index;
  job.renderer = r;
  job.truth = m == nullptr;
  job.scene = scene_from_json(doc, c.origin);
  job.representation = job.scene.representation;
  job.method = m ? m->label : c.section.kind == SectionKind::kBump ? "none" : "analytic";
  doc.erase("name");  // a name is not content
  job.scene_json = std::move(doc);
  job.origin = c.origin;
  job.label = job_label(c.section.kind, v, job);
  v.jobs.push_back(plan.jobs.size());
  plan.jobs.push_back(std::move(job));
}

void add_renderer_jobs(const VariantContext& c, RendererKind r, Variant& v, std::size_t index,
                       Plan& plan) {
  json scene = c.base;
  apply_overrides(scene, c.overrides, c.origin);
  if (const std::string why = cannot_render(r, scene); !why.empty()) {
    const SkippedRenderer skipped{c.section.kind, r, v.scene, why, ""};
    if (std::find(plan.skipped.begin(), plan.skipped.end(), skipped) == plan.skipped.end())
      plan.skipped.push_back(skipped);
    return;
  }
  if (const std::string why = cannot_render_variant(r, scene); !why.empty()) {
    plan.skipped.push_back({c.section.kind, r, v.scene, why, v.id});
    return;
  }
  add_job(c, r, nullptr, v, index, plan);
  for (const StudyMethod& m : c.section.methods)
    if (section_offers(c.section.kind, r, m)) add_job(c, r, &m, v, index, plan);
}

void add_section(const Study& study, const Section& section, Plan& plan) {
  const bool bump = section.kind == SectionKind::kBump;
  std::vector<Override> set;
  for (const auto& [pointer, value] : section.set.items()) set.push_back({pointer, value});
  std::size_t combinations = 1;
  for (const StudyAxis& a : section.axes) combinations *= a.values.size();
  std::size_t count = 0;
  for (const std::string& scene_file : section.scenes) {
    json base = read_json_file(scene_file);
    resolve_map_files(base, scene_file);
    const std::string scene_name = fs::path(scene_file).stem().string();
    for (std::size_t c = 0; c < combinations; ++c) {
      Variant v;
      v.section = section.kind;
      v.id = fmt::format("{}{:03d}", bump ? 'v' : 'l', count++);
      v.scene = scene_name;
      v.label = scene_name;
      const std::vector<Override> overrides = axis_combination(set, section.axes, c, &v);
      const std::string origin = fmt::format("{} (study {}, {} {})", scene_file, study.file,
                                             bump ? "variant" : "low-poly variant", v.id);
      const VariantContext context{section, base, overrides, origin, scene_file, study.blender_spp};
      const std::size_t index = plan.variants.size();
      for (RendererKind r : section.renderers) add_renderer_jobs(context, r, v, index, plan);
      plan.variants.push_back(std::move(v));
    }
  }
}

}  // namespace

Plan plan_study(const Study& study, double max_memory_bytes) {
  const double count = planned_render_count(study);
  if (count > double(kMaxStudyRenders))
    throw InputError(study.file, study.bump.axes.empty() ? "/scenes" : "/axes",
                     fmt::format("expected a study of at most {} renders, it expands to {:.3g} "
                                 "(scenes x axis values x renderers x methods); split it",
                                 kMaxStudyRenders, count));
  Plan plan;
  add_section(study, study.bump, plan);
  if (study.lowpoly) add_section(study, *study.lowpoly, plan);
  for (Job& job : plan.jobs) {
    job.resources = estimate_resources(job.renderer, job.scene);
    check_resources(job.resources, max_memory_bytes, job.origin);
  }
  return plan;
}

std::string axis_value_text(const std::string& pointer, const json& value) {
  return light_direction(pointer, value) ? direction_text(vec3(value)) : value_text(value);
}

namespace {

std::string value_id(const StudyAxis& axis, std::size_t k) {
  if (k < axis.ids.size() && !axis.ids[k].empty()) return axis.ids[k];
  const json& v = axis.values[k];
  if (v.is_number()) return fmt::format("{:g}", v.get<double>());
  if (light_direction(axis.pointer, v)) {
    const Vec3 d = vec3(v);
    return fmt::format("az{:.0f}-el{:.0f}", std::round(azimuth_deg(d)) + 0.0,
                       std::round(elevation_deg(d)) + 0.0);
  }
  return lower_words(v.is_string() ? v.get<std::string>() : v.dump(), '-').substr(0, 32);
}

}  // namespace

std::vector<std::string> axis_value_ids(const StudyAxis& axis) {
  std::vector<std::string> ids;
  for (std::size_t k = 0; k < axis.values.size(); ++k) {
    std::string id = value_id(axis, k);
    if (id.empty()) id = fmt::format("v{}", k);
    if (std::find(ids.begin(), ids.end(), id) != ids.end()) id += fmt::format("-{}", k);
    ids.push_back(std::move(id));
  }
  return ids;
}

std::string render_group_key(const Job& job) {
  if (job.renderer == RendererKind::kEvaluator &&
      job.scene.representation == Representation::kDisplacement)
    return "evaluator:" + displaced_mesh_key(job.scene);
  if (job.renderer != RendererKind::kBlender) return "";
  json mesh = job.scene_json;
  for (const char* part : {"light", "material", "terminator"}) mesh.erase(part);
  return "blender:" + mesh.dump();
}

}  // namespace penumbra
