#include "study/study_file.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <set>

#include <fmt/format.h>

#include "scene/scene_json.h"
#include "study/filtering_study.h"
#include "study/interplay.h"
#include "study/json_fields.h"
#include "study/names.h"
#include "util/strict_json.h"

namespace penumbra {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string method_label(const std::string& id, const json& parameters) {
  if (!parameters.is_object() || parameters.empty()) return id;
  std::string s = id + "(";
  bool first = true;
  for (const auto& [k, v] : parameters.items()) {
    s += (first ? "" : ",") + k + "=" + v.dump();
    first = false;
  }
  return s + ")";
}

}  // namespace

namespace {

// The parts the bump and low-poly sections share: scene files, fixed
// overrides, sweep axes and renderers, under the JSON pointer `at`.
void read_scenes(const json& doc, const std::string& f, const std::string& at, const fs::path& base,
                 std::vector<std::string>* scenes) {
  const json& list = require(doc, "scenes", f, at);
  if (!list.is_array() || list.empty())
    throw InputError(f, at + "/scenes", "expected a non-empty array of scene file paths");
  for (std::size_t i = 0; i < list.size(); ++i) {
    if (!list[i].is_string())
      throw InputError(f, fmt::format("{}/scenes/{}", at, i), "expected a path (string)");
    const fs::path p = base / list[i].get<std::string>();
    if (!fs::is_regular_file(p))
      throw InputError(f, fmt::format("{}/scenes/{}", at, i),
                       fmt::format("no such scene file: {}", p.string()));
    scenes->push_back(p.lexically_normal().string());
  }
}

json read_set(const json& doc, const std::string& f, const std::string& at) {
  if (!doc.contains("set")) return json::object();
  if (!doc["set"].is_object())
    throw InputError(f, at + "/set", "expected an object of JSON pointer -> value");
  return doc["set"];
}

// A compound axis: {"name", "label", "values": [{"label", "set": {pointer: value}}]}.
StudyAxis read_compound_axis(const json& a, const std::string& f, const std::string& p) {
  reject_unknown(a, {"name", "label", "values"}, f, p);
  StudyAxis axis;
  const json& name = require(a, "name", f, p);
  if (!name.is_string() || name.get<std::string>().empty() ||
      name.get<std::string>().find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_") !=
          std::string::npos)
    throw InputError(f, p + "/name", "expected a snake_case name such as \"shading\"");
  axis.pointer = axis.label = name.get<std::string>();
  if (a.contains("label")) {
    if (!a["label"].is_string()) throw InputError(f, p + "/label", "expected a string");
    axis.label = a["label"].get<std::string>();
  }
  const json& values = require(a, "values", f, p);
  if (!values.is_array() || values.empty())
    throw InputError(f, p + "/values",
                     "expected a non-empty array of {\"label\", \"set\"} objects");
  for (std::size_t k = 0; k < values.size(); ++k) {
    const std::string q = fmt::format("{}/values/{}", p, k);
    if (!values[k].is_object()) throw InputError(f, q, "expected {\"label\": ..., \"set\": {...}}");
    reject_unknown(values[k], {"id", "label", "set"}, f, q);
    const json& label = require(values[k], "label", f, q);
    std::string id;
    if (values[k].contains("id")) {
      const json& i = values[k]["id"];
      if (!i.is_string() || i.get<std::string>().empty() || i.get<std::string>().size() > 32 ||
          i.get<std::string>().find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789-_.") !=
              std::string::npos)
        throw InputError(f, q + "/id",
                         "expected a short id of 1 to 32 lower-case letters, digits, '-', '_' or "
                         "'.', such as \"ggx-diffuse\", got " + describe_json(i));
      id = i.get<std::string>();
      for (const std::string& other : axis.ids)
        if (other == id)
          throw InputError(f, q + "/id", fmt::format("the id \"{}\" is already used", id));
    }
    const json& set = require(values[k], "set", f, q);
    if (!label.is_string()) throw InputError(f, q + "/label", "expected a string");
    if (!set.is_object() || set.empty())
      throw InputError(f, q + "/set", "expected an object of JSON pointers and values");
    std::vector<std::pair<std::string, json>> pairs;
    for (const auto& [pointer, value] : set.items()) {
      if (pointer.rfind("/", 0) != 0)
        throw InputError(f, q + "/set",
                         fmt::format("expected JSON pointers as keys, got \"{}\"", pointer));
      pairs.emplace_back(pointer, value);
    }
    axis.values.push_back(label);
    axis.sets.push_back(std::move(pairs));
    axis.ids.push_back(std::move(id));
  }
  return axis;
}

std::vector<StudyAxis> read_axes(const json& doc, const std::string& f, const std::string& at) {
  std::vector<StudyAxis> out;
  if (!doc.contains("axes")) return out;
  const json& axes = doc["axes"];
  if (!axes.is_array()) throw InputError(f, at + "/axes", "expected an array");
  for (std::size_t i = 0; i < axes.size(); ++i) {
    const std::string p = fmt::format("{}/axes/{}", at, i);
    if (!axes[i].is_object()) throw InputError(f, p, "expected an object");
    if (axes[i].contains("name")) {
      out.push_back(read_compound_axis(axes[i], f, p));
      continue;
    }
    reject_unknown(axes[i], {"pointer", "label", "values"}, f, p);
    StudyAxis axis;
    const json& pointer = require(axes[i], "pointer", f, p);
    if (!pointer.is_string() || pointer.get<std::string>().rfind("/", 0) != 0)
      throw InputError(f, p + "/pointer", "expected a JSON pointer such as \"/height/amplitude\"");
    axis.pointer = pointer.get<std::string>();
    axis.label = axis.pointer;
    if (axes[i].contains("label")) {
      if (!axes[i]["label"].is_string()) throw InputError(f, p + "/label", "expected a string");
      axis.label = axes[i]["label"].get<std::string>();
    }
    const json& values = require(axes[i], "values", f, p);
    if (!values.is_array() || values.empty())
      throw InputError(f, p + "/values", "expected a non-empty array of values");
    axis.values = values.get<std::vector<json>>();
    out.push_back(std::move(axis));
  }
  return out;
}

std::vector<RendererKind> read_renderers(const json& doc, const std::string& f,
                                         const std::string& at) {
  if (!doc.contains("renderers")) return all_renderers();
  std::vector<RendererKind> out;
  const json& renderers = doc["renderers"];
  if (!renderers.is_array() || renderers.empty())
    throw InputError(f, at + "/renderers", "expected a non-empty array of renderer ids");
  for (std::size_t i = 0; i < renderers.size(); ++i) {
    const auto r =
        renderers[i].is_string() ? renderer_from_id(renderers[i].get<std::string>()) : std::nullopt;
    if (!r)
      throw InputError(f, fmt::format("{}/renderers/{}", at, i), "expected " + renderer_choices());
    out.push_back(*r);
  }
  if (std::find(out.begin(), out.end(), RendererKind::kEvaluator) == out.end())
    throw InputError(f, at + "/renderers",
                     "must include \"evaluator\": it provides the geometry and the reference");
  return out;
}

// Method ids, or {"id": ..., "parameters": {...}} objects, under `key`;
// parameter values are checked by the scene reader when variants expand.
// Absent: every id. `what` names the kind in errors ("method", "offset method").
std::vector<StudyMethod> read_method_list(const json& doc, const char* key, const std::string& f,
                                          const std::string& at,
                                          const std::vector<std::string>& ids, const char* what) {
  std::vector<StudyMethod> out;
  if (!doc.contains(key)) {
    for (const std::string& id : ids) out.push_back({id, json(), id});
    return out;
  }
  const std::string pointer = at + "/" + key;
  const json& list = doc[key];
  if (!list.is_array() || list.empty())
    throw InputError(f, pointer, fmt::format("expected a non-empty array of {} ids", what));
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string p = fmt::format("{}/{}", pointer, i);
    StudyMethod m;
    if (list[i].is_string()) {
      m.id = list[i].get<std::string>();
    } else if (list[i].is_object()) {
      reject_unknown(list[i], {"id", "parameters"}, f, p);
      const json& id = require(list[i], "id", f, p);
      if (!id.is_string()) throw InputError(f, p + "/id", fmt::format("expected a {} id", what));
      m.id = id.get<std::string>();
      if (list[i].contains("parameters")) {
        if (!list[i]["parameters"].is_object())
          throw InputError(f, p + "/parameters", "expected an object of parameter values");
        m.parameters = list[i]["parameters"];
      }
    } else {
      throw InputError(
          f, p, fmt::format("expected a {} id or {{\"id\": ..., \"parameters\": {{...}}}}", what));
    }
    if (std::find(ids.begin(), ids.end(), m.id) == ids.end()) {
      std::string valid;
      for (const std::string& id : ids) valid += (valid.empty() ? "" : ", ") + id;
      throw InputError(f, p, fmt::format("unknown {} \"{}\" (valid: {})", what, m.id, valid));
    }
    m.label = method_label(m.id, m.parameters);
    out.push_back(std::move(m));
  }
  return out;
}

std::vector<std::string> offset_ids() {
  std::vector<std::string> ids;
  for (const OffsetMethodInfo& info : all_offset_methods()) ids.emplace_back(info.id);
  return ids;
}

std::vector<std::string> terminator_ids() {
  std::vector<std::string> ids;
  for (const MethodInfo& info : all_methods()) ids.emplace_back(info.id);
  return ids;
}

Section read_lowpoly(const json& doc, const std::string& f, const fs::path& base) {
  const std::string at = "/lowpoly";
  if (!doc.is_object()) throw InputError(f, at, "expected an object");
  reject_unknown(doc, {"scenes", "set", "axes", "offsets", "renderers", "convergence"}, f, at);
  Section part;
  part.kind = SectionKind::kLowPoly;
  read_scenes(doc, f, at, base, &part.scenes);
  part.set = read_set(doc, f, at);
  part.axes = read_axes(doc, f, at);
  part.methods = read_method_list(doc, "offsets", f, at, offset_ids(), "offset method");
  part.renderers = read_renderers(doc, f, at);
  if (doc.contains("convergence")) {
    const json& c = doc["convergence"];
    bool found = false;
    for (std::size_t a = 0; a < part.axes.size(); ++a)
      if (c.is_string() && c.get<std::string>() == part.axes[a].pointer) {
        part.convergence_axis = static_cast<int>(a);
        found = true;
      }
    if (!found)
      throw InputError(f, at + "/convergence",
                       "expected the pointer of one of /lowpoly/axes (the tessellation level)");
  }
  return part;
}

// Plots: a metric over two different axes of the study.
std::vector<StudyPlot> read_plots(const json& plots, const std::string& f,
                                  const std::vector<StudyAxis>& axes) {
  if (!plots.is_array()) throw InputError(f, "/plots", "expected an array");
  std::vector<StudyPlot> out;
  for (std::size_t i = 0; i < plots.size(); ++i) {
    const std::string p = fmt::format("/plots/{}", i);
    if (!plots[i].is_object()) throw InputError(f, p, "expected an object");
    reject_unknown(plots[i], {"metric", "x", "y", "kind", "renderer"}, f, p);
    StudyPlot plot;
    const json& metric = require(plots[i], "metric", f, p);
    static const std::set<std::string> metrics{"profile.rmse_terminator",
                                               "profile.rmse_overall",
                                               "profile.max_error_terminator",
                                               "profile.max_step",
                                               "profile.position_error_deg",
                                               "profile.width_deg",
                                               "profile.lit_bias",
                                               "image.rmse",
                                               "image.ssim",
                                               "image.max_error",
                                               "view.rmse_grazing",
                                               "view.bias_grazing"};
    if (!metric.is_string() || !metrics.count(metric.get<std::string>())) {
      std::string names;
      for (const std::string& m : metrics) names += (names.empty() ? "" : ", ") + m;
      throw InputError(f, p + "/metric", "expected one of " + names);
    }
    plot.metric = metric.get<std::string>();
    auto axis_index = [&](const char* key) {
      const json& v = require(plots[i], key, f, p);
      for (std::size_t a = 0; a < axes.size(); ++a)
        if (v.is_string() && v.get<std::string>() == axes[a].pointer) return static_cast<int>(a);
      throw InputError(f, child(p, key), "expected the pointer of one of the study's axes");
    };
    plot.x = axis_index("x");
    plot.y = axis_index("y");
    if (plot.x == plot.y)
      throw InputError(f, p + "/y", "expected an axis other than x (a plot needs two axes)");
    if (plots[i].contains("kind")) {
      const json& k = plots[i]["kind"];
      if (!k.is_string() || (k != "contour" && k != "heatmap"))
        throw InputError(f, p + "/kind", "expected \"contour\" or \"heatmap\"");
      plot.kind = k.get<std::string>();
    }
    if (plots[i].contains("renderer")) {
      const json& r = plots[i]["renderer"];
      if (!r.is_string() || !renderer_from_id(r.get<std::string>()))
        throw InputError(f, p + "/renderer", "expected " + renderer_choices());
      plot.renderer = r.get<std::string>();
    }
    out.push_back(plot);
  }
  return out;
}

GroundTruthSettings read_ground_truth(const json& g, const std::string& f) {
  if (!g.is_object()) throw InputError(f, "/ground_truth", "expected an object");
  reject_unknown(g, {"tolerance", "max_edge_refinements", "max_spp_refinements"}, f,
                 "/ground_truth");
  GroundTruthSettings out;
  if (g.contains("tolerance")) {
    const json& t = g["tolerance"];
    if (!t.is_number() || !(t.get<double>() > 0.0 && t.get<double>() <= 1.0))
      throw InputError(
          f, "/ground_truth/tolerance",
          "expected a number in (0, 1] (fraction of albedo*E/pi), got " + describe_json(t));
    out.tolerance = t.get<double>();
  }
  for (auto [key, target] : {std::pair{"max_edge_refinements", &out.max_edge_refinements},
                             std::pair{"max_spp_refinements", &out.max_spp_refinements}}) {
    if (!g.contains(key)) continue;
    const long long n = strict_integer(g[key], 0, 5);
    if (n < 0)
      throw InputError(f, std::string("/ground_truth/") + key,
                       "expected an integer in [0, 5], got " + describe_json(g[key]));
    *target = static_cast<int>(n);
  }
  return out;
}

// "figures": {"methods": [...]}: labels of the study's own bump methods, as
// the study names them ("shading-offset(s=0.3)", or its id when that is
// unambiguous).
std::vector<std::string> read_figure_methods(const json& figures, const std::string& f,
                                             const Section& bump) {
  if (!figures.is_object()) throw InputError(f, "/figures", "expected an object");
  reject_unknown(figures, {"methods"}, f, "/figures");
  std::vector<std::string> out;
  if (!figures.contains("methods")) return out;
  const json& list = figures["methods"];
  if (!list.is_array()) throw InputError(f, "/figures/methods", "expected an array of methods");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string p = fmt::format("/figures/methods/{}", i);
    if (!list[i].is_string()) throw InputError(f, p, "expected a method label (string)");
    const std::string name = list[i].get<std::string>();
    std::vector<std::string> matches;
    for (const StudyMethod& m : bump.methods)
      if (m.label == name || m.id == name) matches.push_back(m.label);
    if (matches.size() != 1)
      throw InputError(f, p,
                       fmt::format("expected one of the study's /methods by label, got \"{}\" ({})",
                                   name, matches.empty() ? "not in the study" : "ambiguous"));
    out.push_back(matches.front());
  }
  return out;
}

// Every ranking measures against raw bump: a bump study that does not name
// `none` gets it first, and a notice says so.
void add_baseline(Study& s) {
  if (s.bump.scenes.empty()) return;
  for (const StudyMethod& m : s.bump.methods)
    if (m.id == "none") return;
  s.bump.methods.insert(s.bump.methods.begin(), StudyMethod{"none", json(), "none"});
  s.notices.push_back(
      "The study's methods do not include raw bump (\"none\"), the baseline of every ranking "
      "and of the combined error: it was added to /methods.");
}

}  // namespace

Study load_study(const std::string& path) {
  const json doc = read_json_file(path);
  const std::string& f = path;
  if (!doc.is_object()) throw InputError(f, "", "expected a JSON object");
  reject_unknown(doc,
                 {"version", "name", "scenes", "set", "axes", "methods", "renderers", "blender_spp",
                  "ground_truth", "plots", "figures", "lowpoly", "filtering", "interplay"},
                 f, "");
  const json& version = require(doc, "version", f, "");
  if (strict_integer(version, 1, 1000) != kStudyFormatVersion)
    throw InputError(
        f, "/version",
        fmt::format("expected {}, got {}", kStudyFormatVersion, describe_json(version)));
  Study s;
  s.file = path;
  s.absolute_file = std::filesystem::absolute(path).lexically_normal().string();
  if (doc.contains("name")) {
    if (!doc["name"].is_string()) throw InputError(f, "/name", "expected a string");
    s.name = doc["name"].get<std::string>();
    // The name becomes the default output folder results/NAME: a plain name only.
    if (!plain_name(s.name))
      throw InputError(f, "/name",
                       fmt::format("expected a study name of 1 to 100 letters, digits, '-', '_' "
                                   "or '.' (not starting with '.'), got \"{}\"",
                                   s.name));
  } else {  // the file's stem, made plain
    s.name = file_safe(fs::path(path).stem().string().substr(0, 100));
    if (s.name.empty() || s.name[0] == '.') s.name = "study" + s.name;
  }
  const fs::path base = fs::path(path).parent_path();
  if (doc.contains("lowpoly")) s.lowpoly = read_lowpoly(doc["lowpoly"], f, base);
  if (doc.contains("filtering"))
    s.filtering = read_filtering_section(doc["filtering"], f, base.string());
  if (doc.contains("interplay"))
    s.interplay = read_interplay_section(doc["interplay"], f, base.string());
  // A study is a bump, low-poly, filtering or interplay study, or several.
  if (doc.contains("scenes") || (!s.lowpoly && !s.filtering && !s.interplay))
    read_scenes(doc, f, "", base, &s.bump.scenes);
  s.bump.set = read_set(doc, f, "");
  s.bump.axes = read_axes(doc, f, "");
  s.bump.methods = read_method_list(doc, "methods", f, "", terminator_ids(), "method");
  add_baseline(s);
  s.bump.renderers = read_renderers(doc, f, "");
  if (doc.contains("blender_spp")) {
    const long long spp = strict_integer(doc["blender_spp"], 1, 65536);
    if (spp < 0)
      throw InputError(
          f, "/blender_spp",
          "expected an integer in [1, 65536], got " + describe_json(doc["blender_spp"]));
    s.blender_spp = static_cast<int>(spp);
  }
  if (doc.contains("ground_truth")) s.ground_truth = read_ground_truth(doc["ground_truth"], f);
  if (doc.contains("plots")) s.plots = read_plots(doc["plots"], f, s.bump.axes);
  if (doc.contains("figures")) s.figure_methods = read_figure_methods(doc["figures"], f, s.bump);
  return s;
}

double planned_render_count(const Study& study) {
  auto section_count = [](const Section& s) {
    double n = double(s.scenes.size()) * double(s.renderers.size()) * double(1 + s.methods.size());
    for (const StudyAxis& a : s.axes) n *= double(a.values.size());
    return n;
  };
  return section_count(study.bump) + (study.lowpoly ? section_count(*study.lowpoly) : 0.0);
}

}  // namespace penumbra
