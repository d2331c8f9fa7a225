#include "study/study_file.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <set>

#include <fmt/format.h>

#include "scene/scene_json.h"
#include "study/names.h"
#include "study/study_file_sections.h"
#include "util/files.h"
#include "util/json_reader.h"
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
// overrides, sweep axes and renderers, of the object `r` reads.
void read_scenes(Reader& r, const fs::path& base, std::vector<std::string>* scenes) {
  const json& list = r.nonempty_array("scenes", "scene file paths");
  for (std::size_t i = 0; i < list.size(); ++i) {
    if (!list[i].is_string()) r.fail_item("scenes", i, "expected a path (string)");
    const fs::path p = base / list[i].get<std::string>();
    if (const std::string problem = input_file_problem(p.string()); !problem.empty())
      r.fail_item("scenes", i,
                  problem == "no such file"
                      ? fmt::format("no such scene file: {}", p.string())
                      : fmt::format("scene file {}: {}", p.string(), problem));
    scenes->push_back(p.lexically_normal().string());
  }
}

json read_set(Reader& r) {
  if (!r.has("set")) return json::object();
  const json& set = r.at("set");
  if (!set.is_object()) r.fail("set", "expected an object of JSON pointer -> value");
  return set;
}

// An axis's "label" for plots and tables; absent: `fallback`.
std::string read_label(Reader& a, const std::string& fallback) {
  if (!a.has("label")) return fallback;
  if (!a.at("label").is_string()) a.fail("label", "expected a string");
  return a.at("label").get<std::string>();
}

// A compound axis: {"name", "label", "values": [{"id", "label", "set": {pointer: value}}]}.
StudyAxis read_compound_axis(Reader a) {
  a.expect({"name", "label", "values"});
  StudyAxis axis;
  const json& name = a.at("name");
  if (!name.is_string() || name.get<std::string>().empty() ||
      name.get<std::string>().find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_") !=
          std::string::npos)
    a.fail("name", "expected a snake_case name such as \"shading\"");
  axis.pointer = name.get<std::string>();
  axis.label = read_label(a, axis.pointer);
  const json& values = a.nonempty_array("values", "{\"label\", \"set\"} objects");
  for (std::size_t k = 0; k < values.size(); ++k) {
    Reader v = a.item("values", k, "expected {\"label\": ..., \"set\": {...}}");
    v.expect({"id", "label", "set"});
    const json& label = v.at("label");
    std::string id;
    if (v.has("id")) {
      const json& i = v.at("id");
      if (!i.is_string() || i.get<std::string>().empty() || i.get<std::string>().size() > 32 ||
          i.get<std::string>().find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789-_.") !=
              std::string::npos)
        v.fail("id",
               "expected a short id of 1 to 32 lower-case letters, digits, '-', '_' or '.', such "
               "as \"ggx-diffuse\", got " +
                   Reader::describe(i));
      id = i.get<std::string>();
      if (std::find(axis.ids.begin(), axis.ids.end(), id) != axis.ids.end())
        v.fail("id", fmt::format("the id \"{}\" is already used", id));
    }
    const json& set = v.at("set");
    if (!label.is_string()) v.fail("label", "expected a string");
    if (!set.is_object() || set.empty())
      v.fail("set", "expected an object of JSON pointers and values");
    std::vector<std::pair<std::string, json>> pairs;
    for (const auto& [pointer, value] : set.items()) {
      if (pointer.rfind("/", 0) != 0)
        v.fail("set", fmt::format("expected JSON pointers as keys, got \"{}\"", pointer));
      pairs.emplace_back(pointer, value);
    }
    v.finish();
    axis.values.push_back(label);
    axis.sets.push_back(std::move(pairs));
    axis.ids.push_back(std::move(id));
  }
  a.finish();
  return axis;
}

StudyAxis read_axis(Reader a) {
  if (a.has("name")) return read_compound_axis(a);
  a.expect({"pointer", "label", "values"});
  StudyAxis axis;
  const json& pointer = a.at("pointer");
  if (!pointer.is_string() || pointer.get<std::string>().rfind("/", 0) != 0)
    a.fail("pointer", "expected a JSON pointer such as \"/height/amplitude\"");
  axis.pointer = pointer.get<std::string>();
  axis.label = read_label(a, axis.pointer);
  axis.values = a.nonempty_array("values", "values").get<std::vector<json>>();
  a.finish();
  return axis;
}

std::vector<StudyAxis> read_axes(Reader& r) {
  std::vector<StudyAxis> out;
  if (!r.has("axes")) return out;
  if (!r.at("axes").is_array()) r.fail("axes", "expected an array");
  for (std::size_t i = 0; i < r.at("axes").size(); ++i)
    out.push_back(read_axis(r.item("axes", i, "expected an object")));
  return out;
}

std::vector<RendererKind> read_renderers(Reader& r) {
  if (!r.has("renderers")) return all_renderers();
  std::vector<RendererKind> out;
  const json& renderers = r.nonempty_array("renderers", "renderer ids");
  for (std::size_t i = 0; i < renderers.size(); ++i) {
    const auto kind =
        renderers[i].is_string() ? renderer_from_id(renderers[i].get<std::string>()) : std::nullopt;
    if (!kind) r.fail_item("renderers", i, "expected " + renderer_choices());
    out.push_back(*kind);
  }
  if (std::find(out.begin(), out.end(), RendererKind::kEvaluator) == out.end())
    r.fail("renderers", "must include \"evaluator\": it provides the geometry and the reference");
  return out;
}

// A relative "table" parameter (the fitted method's table.json) is taken
// from the study file's folder, as its scene paths are.
void resolve_table_path(const std::string& study_file, json* parameters) {
  const auto it = parameters->find("table");
  if (it == parameters->end() || !it->is_string()) return;
  const fs::path path(it->get<std::string>());
  if (path.empty() || path.is_absolute()) return;
  *it = (fs::absolute(fs::path(study_file).parent_path()) / path).lexically_normal().string();
}

// {"id": ..., "parameters": {...}}, element `i` of the list under `key`.
StudyMethod read_method_object(Reader m, const char* what) {
  m.expect({"id", "parameters"});
  StudyMethod method;
  const json& id = m.at("id");
  if (!id.is_string()) m.fail("id", fmt::format("expected a {} id", what));
  method.id = id.get<std::string>();
  if (m.has("parameters")) {
    if (!m.at("parameters").is_object())
      m.fail("parameters", "expected an object of parameter values");
    method.parameters = m.at("parameters");
    resolve_table_path(m.origin(), &method.parameters);
  }
  m.finish();
  return method;
}

// Method ids, or {"id": ..., "parameters": {...}} objects, under `key`;
// parameter values are checked by the scene reader when variants expand.
// Absent: every id of `defaults`. `what` names the kind in errors ("method",
// "offset method").
std::vector<StudyMethod> read_method_list(Reader& r, const char* key,
                                          const std::vector<std::string>& ids,
                                          const std::vector<std::string>& defaults,
                                          const char* what) {
  std::vector<StudyMethod> out;
  if (!r.has(key)) {
    for (const std::string& id : defaults) out.push_back({id, json(), id});
    return out;
  }
  const json& list = r.nonempty_array(key, fmt::format("{} ids", what));
  for (std::size_t i = 0; i < list.size(); ++i) {
    StudyMethod m;
    if (list[i].is_string())
      m.id = list[i].get<std::string>();
    else if (list[i].is_object())
      m = read_method_object(r.item(key, i), what);
    else
      r.fail_item(
          key, i,
          fmt::format("expected a {} id or {{\"id\": ..., \"parameters\": {{...}}}}", what));
    if (std::find(ids.begin(), ids.end(), m.id) == ids.end())
      r.fail_item(key, i,
                  fmt::format("unknown {} \"{}\" (valid: {})", what, m.id, fmt::join(ids, ", ")));
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

// Every method a study may name; `with_table`: also those that need a table
// file, which a study without "methods" cannot give them, and the user
// methods registered in this process (core/user_method.h), which it takes
// only by name. The `python` row itself is never a study's.
std::vector<std::string> terminator_ids(bool with_table) {
  std::vector<std::string> ids;
  for (const MethodInfo& info : all_methods())
    if (!info.user_defined && (with_table || !info.needs_table)) ids.emplace_back(info.id);
  if (with_table)
    for (std::string& id : user_method_ids()) ids.push_back(std::move(id));
  return ids;
}

Section read_lowpoly(Reader r, const fs::path& base) {
  r.expect({"scenes", "set", "axes", "offsets", "renderers", "convergence"});
  Section part;
  part.kind = SectionKind::kLowPoly;
  read_scenes(r, base, &part.scenes);
  part.set = read_set(r);
  part.axes = read_axes(r);
  part.methods = read_method_list(r, "offsets", offset_ids(), offset_ids(), "offset method");
  part.renderers = read_renderers(r);
  if (r.has("convergence")) {
    const json& c = r.at("convergence");
    for (std::size_t a = 0; a < part.axes.size(); ++a)
      if (c.is_string() && c.get<std::string>() == part.axes[a].pointer)
        part.convergence_axis = static_cast<int>(a);
    if (part.convergence_axis < 0)
      r.fail("convergence",
             "expected the pointer of one of /lowpoly/axes (the tessellation level)");
  }
  r.finish();
  return part;
}

// The metrics a plot may draw.
const std::set<std::string>& plot_metrics() {
  static const std::set<std::string> metrics{"profile.rmse_terminator",
                                             "profile.rmse_overall",
                                             "profile.max_error_terminator",
                                             "profile.max_step",
                                             "profile.position_error_deg",
                                             "profile.width_deg",
                                             "profile.lit_bias",
                                             "image.rmse",
                                             "image.ssim",
                                             "image.flip",
                                             "image.max_error",
                                             "view.rmse_grazing",
                                             "view.bias_grazing"};
  return metrics;
}

// A plot: a metric over two different axes of the study.
StudyPlot read_plot(Reader p, const std::vector<StudyAxis>& axes) {
  p.expect({"metric", "x", "y", "kind", "renderer"});
  StudyPlot plot;
  const json& metric = p.at("metric");
  if (!metric.is_string() || !plot_metrics().count(metric.get<std::string>()))
    p.fail("metric", fmt::format("expected one of {}", fmt::join(plot_metrics(), ", ")));
  plot.metric = metric.get<std::string>();
  auto axis_index = [&](const char* key) {
    const json& v = p.at(key);
    for (std::size_t a = 0; a < axes.size(); ++a)
      if (v.is_string() && v.get<std::string>() == axes[a].pointer) return static_cast<int>(a);
    p.fail(key, "expected the pointer of one of the study's axes");
  };
  plot.x = axis_index("x");
  plot.y = axis_index("y");
  if (plot.x == plot.y) p.fail("y", "expected an axis other than x (a plot needs two axes)");
  if (p.has("kind")) {
    const json& k = p.at("kind");
    if (!k.is_string() || (k != "contour" && k != "heatmap"))
      p.fail("kind", "expected \"contour\" or \"heatmap\"");
    plot.kind = k.get<std::string>();
  }
  if (p.has("renderer")) {
    const json& r = p.at("renderer");
    if (!r.is_string() || !renderer_from_id(r.get<std::string>()))
      p.fail("renderer", "expected " + renderer_choices());
    plot.renderer = r.get<std::string>();
  }
  p.finish();
  return plot;
}

std::vector<StudyPlot> read_plots(Reader& r, const std::vector<StudyAxis>& axes) {
  if (!r.at("plots").is_array()) r.fail("plots", "expected an array");
  std::vector<StudyPlot> out;
  for (std::size_t i = 0; i < r.at("plots").size(); ++i)
    out.push_back(read_plot(r.item("plots", i, "expected an object"), axes));
  return out;
}

GroundTruthSettings read_ground_truth(Reader g) {
  g.expect({"tolerance", "max_edge_refinements", "max_spp_refinements"});
  GroundTruthSettings out;
  out.tolerance = g.number_or(
      "tolerance", out.tolerance, [](double t) { return t > 0.0 && t <= 1.0; },
      "in (0, 1] (fraction of albedo*E/pi)");
  out.max_edge_refinements =
      static_cast<int>(g.integer_or("max_edge_refinements", out.max_edge_refinements, 0, 5));
  out.max_spp_refinements =
      static_cast<int>(g.integer_or("max_spp_refinements", out.max_spp_refinements, 0, 5));
  g.finish();
  return out;
}

// "figures": {"methods": [...]}: labels of the study's own bump methods, as
// the study names them ("shading-offset(s=0.3)", or its id when that is
// unambiguous).
std::vector<std::string> read_figure_methods(Reader figures, const Section& bump) {
  figures.expect({"methods"});
  std::vector<std::string> out;
  if (!figures.has("methods")) return out;
  const json& list = figures.at("methods");
  if (!list.is_array()) figures.fail("methods", "expected an array of methods");
  for (std::size_t i = 0; i < list.size(); ++i) {
    if (!list[i].is_string()) figures.fail_item("methods", i, "expected a method label (string)");
    const std::string name = list[i].get<std::string>();
    std::vector<std::string> matches;
    for (const StudyMethod& m : bump.methods)
      if (m.label == name || m.id == name) matches.push_back(m.label);
    if (matches.size() != 1)
      figures.fail_item(
          "methods", i,
          fmt::format("expected one of the study's /methods by label, got \"{}\" ({})", name,
                      matches.empty() ? "not in the study" : "ambiguous"));
    out.push_back(matches.front());
  }
  figures.finish();
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

// /name, or the file's stem made plain: the default output folder results/NAME.
std::string read_name(Reader& r, const std::string& path) {
  if (!r.has("name")) {
    std::string name = file_safe(fs::path(path).stem().string().substr(0, 100));
    return name.empty() || name[0] == '.' ? "study" + name : name;
  }
  if (!r.at("name").is_string()) r.fail("name", "expected a string");
  const std::string name = r.at("name").get<std::string>();
  if (!plain_name(name))
    r.fail("name", fmt::format("expected a study name of 1 to 100 letters, digits, '-', '_' or "
                               "'.' (not starting with '.'), got \"{}\"",
                               name));
  return name;
}

// The sections: bump (the document's own scenes), low-poly, filtering and
// interplay. A study is one of them, or several.
void read_sections(Reader& r, const fs::path& base, Study& s) {
  if (r.has("lowpoly")) s.lowpoly = read_lowpoly(r.object("lowpoly", "expected an object"), base);
  if (r.has("filtering"))
    s.filtering =
        read_filtering_section(r.object("filtering", "expected an object with \"maps\""), base);
  if (r.has("interplay"))
    s.interplay =
        read_interplay_section(r.object("interplay", "expected an object with \"scene\""), base);
  if (r.has("scenes") || (!s.lowpoly && !s.filtering && !s.interplay))
    read_scenes(r, base, &s.bump.scenes);
  // Without scenes these would sweep nothing: an error, not a silent no-op.
  if (s.bump.scenes.empty())
    for (const char* key : {"set", "axes", "methods", "renderers", "plots", "figures"})
      if (r.has(key))
        r.fail(key, "unused key: it belongs to the bump section, and the study has no /scenes");
  s.bump.set = read_set(r);
  s.bump.axes = read_axes(r);
  s.bump.methods =
      read_method_list(r, "methods", terminator_ids(true), terminator_ids(false), "method");
  add_baseline(s);
  s.bump.renderers = read_renderers(r);
}

}  // namespace

Study load_study(const std::string& path) {
  const json doc = read_json_file(path);
  Reader r(doc, "", path, "expected a JSON object");
  r.expect({"version", "name", "scenes", "set", "axes", "methods", "renderers", "blender_spp",
            "ground_truth", "plots", "figures", "lowpoly", "filtering", "interplay"});
  const json& version = r.at("version");
  if (strict_integer(version, 1, 1000) != kStudyFormatVersion)
    r.fail("version",
           fmt::format("expected {}, got {}", kStudyFormatVersion, Reader::describe(version)));
  Study s;
  s.file = path;
  s.absolute_file = fs::absolute(path).lexically_normal().string();
  s.name = read_name(r, path);
  read_sections(r, fs::path(path).parent_path(), s);
  s.blender_spp = static_cast<int>(r.integer_or("blender_spp", s.blender_spp, 1, 65536));
  if (r.has("ground_truth"))
    s.ground_truth = read_ground_truth(r.object("ground_truth", "expected an object"));
  if (r.has("plots")) s.plots = read_plots(r, s.bump.axes);
  if (r.has("figures"))
    s.figure_methods = read_figure_methods(r.object("figures", "expected an object"), s.bump);
  r.finish();
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
