#include "study/plan.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>

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

JobResources job_resources(const ResourceEstimate& estimate) {
  return {estimate.memory_bytes, estimate.output_bytes, estimate.triangles};
}

const std::string& Job::origin() const {
  static const std::string none;
  return source_ ? source_->origin : none;
}

// The document with its name (the reader keeps the name).
json Job::document() const {
  json doc = *source_->document;
  apply_overrides(doc, source_->overrides, source_->origin);
  for (const OverrideList& list : overrides_)
    if (list) apply_overrides(doc, *list, source_->origin);
  if (!source_->scene_file.empty()) resolve_map_files(doc, source_->scene_file);
  return doc;
}

json Job::scene_json() const {
  json doc = document();
  if (!source_->scene_file.empty()) doc.erase("name");  // a name is not content
  return doc;
}

Scene Job::scene() const {
  if (!shared_) return scene_from_json(document(), source_->origin);
  Scene s = *shared_;
  s.representation = parts_->representation;
  s.terminator = parts_->terminator;
  s.offset = parts_->offset;
  s.tessellation = parts_->tessellation;
  return s;
}

namespace {

std::shared_ptr<const MethodParts> parts_of(const Scene& s) {
  return std::make_shared<const MethodParts>(
      MethodParts{s.representation, s.terminator, s.offset, s.tessellation});
}

}  // namespace

void Job::set_scene(json canonical, Scene scene, std::string origin) {
  source_ = std::make_shared<const SceneSource>(
      SceneSource{std::make_shared<const json>(std::move(canonical)), "", {}, std::move(origin)});
  overrides_ = {};
  parts_ = parts_of(scene);
  shared_ = std::make_shared<const Scene>(std::move(scene));
  representation = parts_->representation;
}

void Job::set_scene(std::shared_ptr<const SceneSource> source, OverrideList method_overrides,
                    OverrideList renderer_overrides, std::shared_ptr<const Scene> shared,
                    std::shared_ptr<const MethodParts> parts) {
  source_ = std::move(source);
  overrides_ = {std::move(method_overrides), std::move(renderer_overrides), nullptr};
  shared_ = std::move(shared);
  parts_ = std::move(parts);
  if (parts_) representation = parts_->representation;
}

void Job::refine(OverrideList settings, std::shared_ptr<const Scene>* shared) {
  overrides_[2] = std::move(settings);
  Scene s = scene_from_json(document(), source_->origin);
  resources = job_resources(estimate_resources(renderer, s));
  if (!shared) {
    shared_ = nullptr;
    return;
  }
  if (!*shared) *shared = std::make_shared<const Scene>(std::move(s));
  shared_ = *shared;
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
  const json::json_pointer shading("/shape/tessellation/shading");
  if (!info.consistent_normals && scene.contains(shading) && scene[shading] == "consistent")
    return info.consistent_normals_why_not;
  return "";
}

// Why renderer r renders a bump section's truth of this scene but none of
// its methods ("" when it renders them): its bump on a mesh shape would not
// be the evaluator's (the renderer table's mesh_bump_why_not).
std::string cannot_bump(RendererKind r, SectionKind kind, const json& scene) {
  const json::json_pointer shape("/shape/type");
  const RendererInfo& info = renderer_info(r);
  if (kind != SectionKind::kBump || info.mesh_bump || !scene.contains(shape) ||
      scene[shape] != "mesh")
    return "";
  return std::string(info.mesh_bump_why_not) + "; the displaced truth is rendered";
}

// Why renderer r renders this mesh scene's bump but not method m's (""
// when it does): the method's reference normal there is not the scene's
// (mesh_method_why_not).
std::string cannot_bump_method(RendererKind r, const Section& section, const StudyMethod& m,
                               const json& scene) {
  const json::json_pointer shape("/shape/type"), reference("/terminator/reference_normal");
  if (section.kind != SectionKind::kBump || !scene.contains(shape) || scene[shape] != "mesh")
    return "";
  const ReferenceNormal normal = scene.contains(reference) && scene[reference] == "Ni"
                                     ? ReferenceNormal::kInterpolated
                                     : ReferenceNormal::kGeometric;
  return mesh_method_why_not(renderer_info(r), *method_from_id(m.id), normal);
}

// ---- expansion ------------------------------------------------------------------

// The override lists a section shares between its variants: the truth's and
// each method's (in the order of Section::methods), and the renderers'.
struct SectionLists {
  std::shared_ptr<const std::vector<Override>> truth;
  std::vector<std::shared_ptr<const std::vector<Override>>> methods;
  std::shared_ptr<const std::vector<Override>> blender;  // its samples per pixel
};

SectionLists section_lists(const Section& section, int blender_spp) {
  SectionLists lists;
  lists.truth =
      std::make_shared<const std::vector<Override>>(section_overrides(section.kind, nullptr));
  for (const StudyMethod& m : section.methods)
    lists.methods.push_back(
        std::make_shared<const std::vector<Override>>(section_overrides(section.kind, &m)));
  lists.blender = std::make_shared<const std::vector<Override>>(
      std::vector<Override>{{"/camera/spp", blender_spp}});
  return lists;
}

struct VariantContext {
  const Section& section;
  const SectionLists& lists;
  std::shared_ptr<const SceneSource> source;
  double max_memory_bytes;
  // Method parts by what they are read from: equal parts are one object.
  std::map<std::string, std::shared_ptr<const MethodParts>>& parts;
};

// What the method parts of `doc` are read from, as text.
std::string parts_text(const json& doc) {
  std::string text;
  for (const char* pointer : {"/representation", "/terminator", "/offset", "/shape/tessellation"}) {
    const json::json_pointer p(pointer);
    text += doc.contains(p) ? doc[p].dump() : "-";
    text += '\n';
  }
  return text;
}

// Adds the job of method `m` (an index into the section's methods; none: the
// truth). Its scene is read in full, to check it, and kept as where it comes
// from and its parts, the shared one in `shared` (one per variant and
// renderer).
void add_job(const VariantContext& c, RendererKind r, std::optional<std::size_t> m, Variant& v,
             std::size_t variant_index, std::shared_ptr<const Scene>& shared, Plan& plan) {
  Job job;
  job.variant = variant_index;
  job.renderer = r;
  job.truth = !m;
  const StudyMethod* method = m ? &c.section.methods[*m] : nullptr;
  job.method = method ? method->label : c.section.kind == SectionKind::kBump ? "none" : "analytic";
  const OverrideList method_list = m ? c.lists.methods[*m] : c.lists.truth;
  const OverrideList renderer_list = r == RendererKind::kBlender ? c.lists.blender : nullptr;
  job.set_scene(c.source, method_list, renderer_list, nullptr, nullptr);
  const json doc = job.document();
  Scene scene = scene_from_json(doc, c.source->origin);
  const ResourceEstimate resources = estimate_resources(r, scene);
  check_resources(resources, c.max_memory_bytes, c.source->origin);
  job.resources = job_resources(resources);
  std::shared_ptr<const MethodParts>& parts = c.parts[parts_text(doc)];
  if (!parts) parts = parts_of(scene);
  if (!shared) shared = std::make_shared<const Scene>(std::move(scene));
  job.set_scene(c.source, method_list, renderer_list, shared, parts);
  job.label = job_label(c.section.kind, v, job);
  v.jobs.push_back(plan.jobs.size());
  plan.jobs.push_back(std::move(job));
}

void add_renderer_jobs(const VariantContext& c, RendererKind r, Variant& v, std::size_t index,
                       Plan& plan) {
  json scene = *c.source->document;
  apply_overrides(scene, c.source->overrides, c.source->origin);
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
  std::shared_ptr<const Scene> shared;
  add_job(c, r, std::nullopt, v, index, shared, plan);
  if (const std::string why = cannot_bump(r, c.section.kind, scene); !why.empty()) {
    const SkippedRenderer skipped{c.section.kind, r, v.scene, why, ""};
    if (std::find(plan.skipped.begin(), plan.skipped.end(), skipped) == plan.skipped.end())
      plan.skipped.push_back(skipped);
    return;
  }
  for (std::size_t m = 0; m < c.section.methods.size(); ++m) {
    if (!section_offers(c.section.kind, r, c.section.methods[m])) continue;
    if (const std::string why = cannot_bump_method(r, c.section, c.section.methods[m], scene);
        !why.empty()) {
      const SkippedRenderer skipped{c.section.kind, r, v.scene, why, ""};
      if (std::find(plan.skipped.begin(), plan.skipped.end(), skipped) == plan.skipped.end())
        plan.skipped.push_back(skipped);
      continue;
    }
    add_job(c, r, m, v, index, shared, plan);
  }
}

void add_section(const Study& study, const Section& section, double max_memory_bytes, Plan& plan) {
  const bool bump = section.kind == SectionKind::kBump;
  const SectionLists lists = section_lists(section, study.blender_spp);
  std::map<std::string, std::shared_ptr<const MethodParts>> parts;
  std::vector<Override> set;
  for (const auto& [pointer, value] : section.set.items()) set.push_back({pointer, value});
  std::size_t combinations = 1;
  for (const StudyAxis& a : section.axes) combinations *= a.values.size();
  std::size_t count = 0;
  for (const std::string& file : section.scenes) {
    auto document = std::make_shared<json>(read_json_file(file));
    resolve_map_files(*document, file);
    const std::string scene_name = fs::path(file).stem().string();
    for (std::size_t c = 0; c < combinations; ++c) {
      Variant v;
      v.section = section.kind;
      v.id = fmt::format("{}{:03d}", bump ? 'v' : 'l', count++);
      v.scene = scene_name;
      v.label = scene_name;
      auto source = std::make_shared<SceneSource>();
      source->document = document;
      source->scene_file = file;
      source->overrides = axis_combination(set, section.axes, c, &v);
      source->origin = fmt::format("{} (study {}, {} {})", file, study.file,
                                   bump ? "variant" : "low-poly variant", v.id);
      const VariantContext context{section, lists, std::move(source), max_memory_bytes, parts};
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
  plan.jobs.reserve(static_cast<std::size_t>(count));
  add_section(study, study.bump, max_memory_bytes, plan);
  if (study.lowpoly) add_section(study, *study.lowpoly, max_memory_bytes, plan);
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
      job.representation == Representation::kDisplacement)
    return "evaluator:" + displaced_mesh_key(job.scene());
  if (job.renderer != RendererKind::kBlender) return "";
  json mesh = job.scene_json();
  for (const char* part : {"light", "material", "terminator"}) mesh.erase(part);
  return "blender:" + mesh.dump();
}

}  // namespace penumbra
