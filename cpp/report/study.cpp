#include "report/study.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <thread>

#include <fmt/format.h>

#include "analysis/metrics.h"
#include "analysis/metrics_json.h"
#include "export/export.h"
#include "render/image_io.h"
#include "renderers/parallel.h"
#include "renderers/process.h"
#include "scene/scene_json.h"
#include "util/files.h"

namespace penumbra {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// ---- study file -------------------------------------------------------------

std::string child(const std::string& pointer, const std::string& key) {
  return pointer + "/" + key;
}

void reject_unknown(const json& object, std::initializer_list<const char*> known,
                    const std::string& file, const std::string& pointer) {
  for (const auto& [key, value] : object.items()) {
    bool ok = false;
    for (const char* k : known) ok = ok || key == k;
    if (!ok) {
      std::string names;
      for (const char* k : known) names += (names.empty() ? "" : ", ") + std::string(k);
      throw InputError(file, child(pointer, key), "unknown key (expected one of: " + names + ")");
    }
  }
}

const json& require(const json& object, const char* key, const std::string& file,
                    const std::string& pointer) {
  if (!object.contains(key)) throw InputError(file, child(pointer, key), "missing required key");
  return object.at(key);
}

// The value of an integer in [lo, hi], or -1 when `v` is not one (no
// truncation: 4294967297 is not 1).
long long strict_integer(const json& v, long long lo, long long hi) {
  if (v.is_number_unsigned()) {
    const auto u = v.get<std::uint64_t>();
    return u >= static_cast<std::uint64_t>(lo) && u <= static_cast<std::uint64_t>(hi)
               ? static_cast<long long>(u)
               : -1;
  }
  if (!v.is_number_integer()) return -1;
  const auto i = v.get<std::int64_t>();
  return i >= lo && i <= hi ? i : -1;
}

bool plain_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.';
}

bool plain_name(const std::string& name) {
  if (name.empty() || name.size() > 100 || name[0] == '.') return false;
  return std::all_of(name.begin(), name.end(), plain_char);
}

// Labels carry method parameters ("shading-offset(s=0.3)"): keep file names plain.
std::string file_safe(const std::string& label) {
  std::string out;
  for (char c : label) out += plain_char(c) ? c : '_';
  return out;
}

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

std::vector<StudyAxis> read_axes(const json& doc, const std::string& f, const std::string& at) {
  std::vector<StudyAxis> out;
  if (!doc.contains("axes")) return out;
  const json& axes = doc["axes"];
  if (!axes.is_array()) throw InputError(f, at + "/axes", "expected an array");
  for (std::size_t i = 0; i < axes.size(); ++i) {
    const std::string p = fmt::format("{}/axes/{}", at, i);
    if (!axes[i].is_object()) throw InputError(f, p, "expected an object");
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
      throw InputError(f, fmt::format("{}/renderers/{}", at, i),
                       "expected \"evaluator\", \"povray\" or \"blender\"");
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

LowPolyPart read_lowpoly(const json& doc, const std::string& f, const fs::path& base) {
  const std::string at = "/lowpoly";
  if (!doc.is_object()) throw InputError(f, at, "expected an object");
  reject_unknown(doc, {"scenes", "set", "axes", "offsets", "renderers", "convergence"}, f, at);
  LowPolyPart part;
  read_scenes(doc, f, at, base, &part.scenes);
  part.set = read_set(doc, f, at);
  part.axes = read_axes(doc, f, at);
  part.offsets = read_method_list(doc, "offsets", f, at, offset_ids(), "offset method");
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
                                               "image.max_error"};
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
        throw InputError(f, p + "/renderer", "expected \"evaluator\", \"povray\" or \"blender\"");
      plot.renderer = r.get<std::string>();
    }
    out.push_back(plot);
  }
  return out;
}

}  // namespace

Study load_study(const std::string& path) {
  const json doc = read_json_file(path);
  const std::string& f = path;
  if (!doc.is_object()) throw InputError(f, "", "expected a JSON object");
  reject_unknown(doc,
                 {"version", "name", "scenes", "set", "axes", "methods", "renderers", "blender_spp",
                  "plots", "lowpoly"},
                 f, "");
  const json& version = require(doc, "version", f, "");
  if (strict_integer(version, 1, 1000) != kStudyFormatVersion)
    throw InputError(
        f, "/version",
        fmt::format("expected {}, got {}", kStudyFormatVersion, describe_json(version)));
  Study s;
  s.file = path;
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
  // A study is a bump study, a low-poly study, or both.
  if (doc.contains("scenes") || !s.lowpoly) read_scenes(doc, f, "", base, &s.scenes);
  s.set = read_set(doc, f, "");
  s.axes = read_axes(doc, f, "");
  s.methods = read_method_list(doc, "methods", f, "", terminator_ids(), "method");
  s.renderers = read_renderers(doc, f, "");
  if (doc.contains("blender_spp")) {
    const long long spp = strict_integer(doc["blender_spp"], 1, 65536);
    if (spp < 0)
      throw InputError(
          f, "/blender_spp",
          "expected an integer in [1, 65536], got " + describe_json(doc["blender_spp"]));
    s.blender_spp = static_cast<int>(spp);
  }
  if (doc.contains("plots")) s.plots = read_plots(doc["plots"], f, s.axes);
  return s;
}

std::string render_key(const json& canonical_scene, const std::string& renderer,
                       const std::string& renderer_version) {
  const std::string text =
      canonical_scene.dump() + "\n" + renderer + "\n" + renderer_version + "\n" + kPenumbraVersion;
  auto fnv = [&](std::uint64_t h) {
    for (unsigned char c : text) h = (h ^ c) * 0x100000001b3ull;
    return h;
  };
  return fmt::format("{:016x}{:016x}", fnv(0xcbf29ce484222325ull), fnv(0x84222325cbf29ce4ull));
}

namespace {

// ---- expansion ----------------------------------------------------------------

struct Job {
  std::size_t variant = 0;
  RendererKind renderer = RendererKind::kEvaluator;
  Representation representation = Representation::kBump;
  std::string method;  // label
  json scene_json;     // canonical
  Scene scene;
  std::string key, label;
  std::string origin;  // the scene file and variant, for error messages
  ResourceEstimate resources;
};

struct Variant {
  bool lowpoly = false;  // the low-poly section (truth: the analytic surface)
  std::string id, scene, label;
  std::vector<json> axis_values;
  std::vector<std::size_t> jobs;
};

std::string value_text(const json& v) {
  if (v.is_number_float()) return fmt::format("{:g}", v.get<double>());
  return v.dump();
}

// Combination `c` of the axes (mixed radix, the first axis fastest) as
// overrides after `set`; records the values and extends the label of `v`.
std::vector<Override> axis_combination(const std::vector<Override>& set,
                                       const std::vector<StudyAxis>& axes, std::size_t c,
                                       Variant* v) {
  std::vector<Override> overrides = set;
  for (const StudyAxis& a : axes) {
    const json& value = a.values[c % a.values.size()];
    c /= a.values.size();
    overrides.push_back({a.pointer, value});
    v->axis_values.push_back(value);
    v->label += fmt::format(", {}={}", a.label, value_text(value));
  }
  return overrides;
}

std::string python_executable(const std::string& preferred) {
  if (!preferred.empty()) return preferred;
  if (const char* env = std::getenv("PENUMBRA_PYTHON")) return env;
  // Debian's interpreter, where python3-matplotlib lives, even when a
  // different python3 comes first in PATH.
  if (find_executable("/usr/bin/python3")) return "/usr/bin/python3";
  return "python3";
}

// Signed difference test - reference in units of albedo*E/pi, on a diverging
// map saturating at +-0.25: red brighter, blue darker, white equal; grey
// where either image has no object.
void write_difference_png(const Image& test, const Image& reference, double scale,
                          const std::string& path) {
  std::vector<unsigned char> rgb(std::size_t(test.width) * test.height * 3);
  const int a1 = test.channel_index("A"), a2 = reference.channel_index("A");
  const int r1 = test.channel_index("R"), r2 = reference.channel_index("R");
  for (int y = 0; y < test.height; ++y)
    for (int x = 0; x < test.width; ++x) {
      unsigned char* p = &rgb[(std::size_t(y) * test.width + x) * 3];
      if (test.at(x, y, a1) < 0.5f || reference.at(x, y, a2) < 0.5f) {
        p[0] = p[1] = p[2] = 96;
        continue;
      }
      const double d = (test.at(x, y, r1) - reference.at(x, y, r2)) / scale;
      const double v = std::clamp(d / 0.25, -1.0, 1.0);
      const auto c = [](double t) { return static_cast<unsigned char>(std::lround(255.0 * t)); };
      if (v >= 0)
        p[0] = 255, p[1] = c(1 - v), p[2] = c(1 - v);
      else
        p[0] = c(1 + v), p[1] = c(1 + v), p[2] = 255;
    }
  write_png_rgb8(path, test.width, test.height, rgb);
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string csv_number(const json& v) {
  if (v.is_null()) return "";
  if (v.is_number_float()) return fmt::format("{}", v.get<double>());
  return v.dump();
}

// One metrics.csv / lowpoly.csv row: study, variant, scene, axis values,
// renderer, method or offset, reference, then the named fields of each
// metrics object in order.
struct CsvFields {
  const json* object;
  std::vector<const char*> keys;
};

std::string csv_row(const std::string& study, const Variant& var, const std::string& renderer,
                    const std::string& method, const std::string& reference,
                    std::initializer_list<CsvFields> fields) {
  std::string row = fmt::format("{},{},{}", csv_field(study), var.id, csv_field(var.scene));
  for (const json& value : var.axis_values) row += "," + csv_field(value.dump());
  row += fmt::format(",{},{},{}", renderer, csv_field(method), reference);
  for (const CsvFields& f : fields)
    for (const char* k : f.keys) row += "," + csv_number(f.object->at(k));
  return row + "\n";
}

}  // namespace

void run_plot_script(const std::vector<std::string>& arguments, const std::string& log_path,
                     const std::string& python, double timeout_s) {
  std::error_code ignored;
  fs::remove(log_path, ignored);
  const std::string name = python_executable(python);
  const auto exe = find_executable(name);
  if (!exe)
    throw RendererError(fmt::format(
        "{} not found: install python3 and python3-matplotlib (apt-get install python3-matplotlib)",
        name));
  std::vector<std::string> argv{*exe, std::string(PENUMBRA_SOURCE_DIR) + "/harness/report.py"};
  argv.insert(argv.end(), arguments.begin(), arguments.end());
  fs::path dir = fs::path(log_path).parent_path();
  const ProcessResult p = run_process(argv, dir.empty() ? "." : dir.string(), log_path, timeout_s);
  if (!p.ok())
    throw RendererError(
        fmt::format("harness/report.py failed ({}); log {}:\n{}",
                    p.timed_out ? std::string("timed out") : "exit " + std::to_string(p.exit_code),
                    log_path, tail_lines(log_path, 12)));
}

namespace {

struct Plan {
  std::vector<Variant> variants;
  std::vector<Job> jobs;
  json lowpoly_skipped = json::array();
};

// Number of renders the study expands to, counted before expanding so that
// a sweep of billions is refused instead of exhausting memory.
double planned_render_count(const Study& study) {
  auto product = [](const std::vector<StudyAxis>& axes) {
    double n = 1.0;
    for (const StudyAxis& a : axes) n *= double(a.values.size());
    return n;
  };
  double total = double(study.scenes.size()) * product(study.axes) *
                 double(study.renderers.size()) * double(1 + study.methods.size());
  if (study.lowpoly)
    total += double(study.lowpoly->scenes.size()) * product(study.lowpoly->axes) *
             double(study.lowpoly->renderers.size()) * double(1 + study.lowpoly->offsets.size());
  return total;
}

std::string version_of(const std::map<RendererKind, std::string>& versions, RendererKind r) {
  const auto it = versions.find(r);
  return it != versions.end() ? it->second : std::string("unavailable");
}

void add_bump_variants(const Study& study, const std::map<RendererKind, std::string>& versions,
                       Plan& plan) {
  std::vector<Override> base_set;
  for (const auto& [pointer, value] : study.set.items()) base_set.push_back({pointer, value});
  std::size_t combos = 1;
  for (const StudyAxis& a : study.axes) combos *= a.values.size();
  for (const std::string& scene_file : study.scenes) {
    const json base = read_json_file(scene_file);
    const std::string scene_name = fs::path(scene_file).stem().string();
    for (std::size_t c = 0; c < combos; ++c) {
      Variant v;
      v.id = fmt::format("v{:03d}", plan.variants.size());
      v.scene = scene_name;
      v.label = scene_name;
      const std::vector<Override> overrides = axis_combination(base_set, study.axes, c, &v);
      const std::string origin =
          fmt::format("{} (study {}, variant {})", scene_file, study.file, v.id);
      for (RendererKind r : study.renderers) {
        auto add = [&](Representation rep, const StudyMethod* m) {
          json doc = base;
          std::vector<Override> all = overrides;
          all.push_back({"/representation", to_string(rep)});
          all.push_back({"/terminator/method", m ? m->id : "none"});
          if (m && m->parameters.is_object())
            all.push_back({"/terminator/parameters", m->parameters});
          if (r == RendererKind::kBlender) all.push_back({"/camera/spp", study.blender_spp});
          apply_overrides(doc, all, origin);
          Job job;
          job.variant = plan.variants.size();
          job.renderer = r;
          job.representation = rep;
          job.method = m ? m->label : "none";
          job.scene = scene_from_json(doc, origin);
          doc.erase("name");  // a name is not content
          job.scene_json = doc;
          job.origin = origin;
          job.label = fmt::format("{}-{}-{}-{}", v.id, to_string(r), to_string(rep), job.method);
          job.key = render_key(doc, to_string(r), version_of(versions, r));
          v.jobs.push_back(plan.jobs.size());
          plan.jobs.push_back(std::move(job));
        };
        add(Representation::kDisplacement, nullptr);
        const auto offered = methods_offered(to_string(r), Representation::kBump);
        for (const StudyMethod& m : study.methods)
          if (std::find(offered.begin(), offered.end(), *method_from_id(m.id)) != offered.end())
            add(Representation::kBump, &m);
      }
      plan.variants.push_back(std::move(v));
    }
  }
}

void add_lowpoly_variants(const Study& study, const std::map<RendererKind, std::string>& versions,
                          Plan& plan) {
  const LowPolyPart& part = *study.lowpoly;
  std::vector<Override> part_set;
  for (const auto& [pointer, value] : part.set.items()) part_set.push_back({pointer, value});
  std::size_t part_combos = 1;
  for (const StudyAxis& a : part.axes) part_combos *= a.values.size();
  std::size_t count = 0;
  for (const std::string& scene_file : part.scenes) {
    const json base = read_json_file(scene_file);
    const std::string scene_name = fs::path(scene_file).stem().string();
    for (std::size_t c = 0; c < part_combos; ++c) {
      Variant v;
      v.lowpoly = true;
      v.id = fmt::format("l{:03d}", count++);
      v.scene = scene_name;
      v.label = scene_name;
      const std::vector<Override> overrides = axis_combination(part_set, part.axes, c, &v);
      const std::string origin =
          fmt::format("{} (study {}, low-poly variant {})", scene_file, study.file, v.id);
      json with_overrides = base;
      apply_overrides(with_overrides, overrides, origin);
      const bool has_props = with_overrides.contains("props") && !with_overrides["props"].empty();
      for (RendererKind r : part.renderers) {
        // m == nullptr: the ground truth, the same scene untessellated.
        auto add = [&](const StudyMethod* m) {
          json doc = base;
          std::vector<Override> all = overrides;
          json offset = {{"method", m ? m->id : "none"}};
          if (m && m->parameters.is_object())
            for (const auto& [k, value] : m->parameters.items()) offset[k] = value;
          all.push_back({"/offset", offset});
          if (!m) all.push_back({"/shape/tessellation", nullptr});
          if (r == RendererKind::kBlender) all.push_back({"/camera/spp", study.blender_spp});
          apply_overrides(doc, all, origin);
          Job job;
          job.variant = plan.variants.size();
          job.renderer = r;
          job.scene = scene_from_json(doc, origin);
          job.representation = job.scene.representation;
          job.method = m ? m->label : "analytic";
          doc.erase("name");
          job.scene_json = doc;
          job.origin = origin;
          job.label = fmt::format("{}-{}-{}", v.id, to_string(r), job.method);
          job.key = render_key(doc, to_string(r), version_of(versions, r));
          v.jobs.push_back(plan.jobs.size());
          plan.jobs.push_back(std::move(job));
        };
        if (r != RendererKind::kEvaluator && has_props) {
          const json skipped = {{"renderer", to_string(r)},
                                {"scene", scene_name},
                                {"why", "props (extra spheres) are evaluator-only"}};
          if (std::find(plan.lowpoly_skipped.begin(), plan.lowpoly_skipped.end(), skipped) ==
              plan.lowpoly_skipped.end())
            plan.lowpoly_skipped.push_back(skipped);
          continue;
        }
        add(nullptr);
        const auto offered = offsets_offered(to_string(r));
        for (const StudyMethod& m : part.offsets)
          if (std::find(offered.begin(), offered.end(), *offset_method_from_id(m.id)) !=
              offered.end())
            add(&m);
      }
      plan.variants.push_back(std::move(v));
    }
  }
}

// Expands the whole study and validates every scene and its resources;
// InputError before anything is written.
Plan plan_study(const Study& study, const std::map<RendererKind, std::string>& versions,
                double max_memory_bytes) {
  const double count = planned_render_count(study);
  if (count > double(kMaxStudyRenders))
    throw InputError(study.file, study.axes.empty() ? "/scenes" : "/axes",
                     fmt::format("expected a study of at most {} renders, it expands to {:.3g} "
                                 "(scenes x axis values x renderers x methods); split it",
                                 kMaxStudyRenders, count));
  Plan plan;
  add_bump_variants(study, versions, plan);
  if (study.lowpoly) add_lowpoly_variants(study, versions, plan);
  for (Job& job : plan.jobs) {
    job.resources = estimate_resources(job.renderer, job.scene);
    check_resources(job.resources, max_memory_bytes, job.origin);
  }
  return plan;
}

// A cache entry is used only if it reads, carries this job's key and its
// pixels match the checksum written with them; nullopt and a reason otherwise.
std::optional<Image> verified_cache_entry(const std::string& path, const std::string& key,
                                          std::string* reason) {
  std::map<std::string, std::string> attributes;
  Image image;
  try {
    image = read_image(path, &attributes);
  } catch (const std::exception& e) {
    *reason = fmt::format("unreadable ({})", printable(e.what(), 200));
    return std::nullopt;
  }
  if (attributes["penumbra:key"] != key) {
    *reason = fmt::format("it carries key \"{}\", not its own",
                          printable(attributes["penumbra:key"], 40));
    return std::nullopt;
  }
  if (attributes["penumbra:checksum"] != image_checksum(image)) {
    *reason = "its pixels do not match their checksum";
    return std::nullopt;
  }
  if (std::any_of(image.pixels.begin(), image.pixels.end(),
                  [](float v) { return !std::isfinite(v); })) {
    *reason = "it holds NaN or Inf values";
    return std::nullopt;
  }
  return image;
}

void warn(const StudyOptions& options, StudyRunStats& stats, const std::string& text) {
  stats.warnings.push_back(text);
  if (options.log) options.log("WARNING: " + text);
}

// The state of every job after the render phase.
struct Renders {
  std::vector<std::string> errors;
  std::vector<char> done, attempted;
  std::vector<Image> images;
  std::vector<long> same_as;  // a job with an earlier job's key takes its result
  explicit Renders(std::size_t n)
      : errors(n), done(n, 0), attempted(n, 0), images(n), same_as(n, -1) {}
};

// Takes what the cache holds (verified entries only; damaged ones are removed
// with a warning) and returns the jobs still to render. Jobs with the same key
// (a ground truth shared by every tessellation level) are rendered once.
std::vector<std::size_t> use_cache(const std::vector<Job>& jobs, const fs::path& out,
                                   const StudyOptions& options, Renders& r, StudyRunStats& stats) {
  std::vector<std::size_t> todo;
  std::map<std::string, std::size_t> first_with_key;
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    const fs::path cached = out / "cache" / (jobs[i].key + ".exr");
    if (fs::exists(cached)) {
      std::string reason;
      if (std::optional<Image> image =
              verified_cache_entry(cached.string(), jobs[i].key, &reason)) {
        r.images[i] = std::move(*image);
        r.done[i] = 1;
        ++stats.cached;
        continue;
      }
      warn(options, stats,
           fmt::format("cache entry {} of {} is damaged: {}; rendering it again", cached.string(),
                       jobs[i].label, reason));
      std::error_code ignored;
      fs::remove(cached, ignored);
    }
    if (const auto [it, inserted] = first_with_key.try_emplace(jobs[i].key, i); !inserted)
      r.same_as[i] = static_cast<long>(it->second);
    else
      todo.push_back(i);
  }
  return todo;
}

// Renders `job` and writes it into the cache with its key and checksum;
// returns the image. Throws RendererError (RenderCancelled when interrupted).
Image render_into_cache(const Job& job, const fs::path& out, const StudyOptions& options,
                        int threads, const std::string& renderer_version) {
  RenderSettings settings;
  settings.timeout_s = options.timeout_s;
  settings.threads = threads;
  settings.log_path = (out / "cache" / (job.key + ".log")).string();
  std::error_code ignored;
  fs::remove(settings.log_path, ignored);
  RendererRun run = render_with(job.renderer, job.scene, settings);
  write_exr(run.image, (out / "cache" / (job.key + ".exr")).string(),
            {{"penumbra:version", kPenumbraVersion},
             {"penumbra:renderer", to_string(job.renderer)},
             {"penumbra:renderer_version", renderer_version},
             {"penumbra:scene", job.scene_json.dump()},
             {"penumbra:method", job.method},
             {"penumbra:representation", to_string(job.representation)},
             {"penumbra:radiance_unit", "W m^-2 sr^-1"},
             {"penumbra:key", job.key},
             {"penumbra:checksum", image_checksum(run.image)}});
  if (job.renderer == RendererKind::kEvaluator) fs::remove(settings.log_path, ignored);
  return std::move(run.image);
}

// Renders `todo` in parallel, with progress, until done, interrupted or
// --max-renders is reached.
void render_todo(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo,
                 const fs::path& out, const StudyOptions& options,
                 const std::map<RendererKind, std::string>& versions,
                 const std::map<RendererKind, std::string>& unavailable, Renders& r,
                 StudyRunStats& stats) {
  std::mutex mutex;
  std::size_t finished = 0;
  long started_new = 0;
  double busy_seconds = 0.0;
  const int threads = std::max(
      1, static_cast<int>(std::thread::hardware_concurrency()) / std::max(1, options.jobs));
  run_parallel(options.jobs, todo.size(), [&](std::size_t t) {
    const std::size_t i = todo[t];
    const Job& job = jobs[i];
    {
      std::lock_guard<std::mutex> lock(mutex);
      if ((options.interrupted && options.interrupted->load()) ||
          (options.max_new_renders >= 0 && started_new >= options.max_new_renders))
        return;
      ++started_new;
      r.attempted[i] = 1;
    }
    const auto t0 = std::chrono::steady_clock::now();
    std::string error;
    try {
      if (const auto missing = unavailable.find(job.renderer); missing != unavailable.end())
        throw RendererError(missing->second);
      r.images[i] =
          render_into_cache(job, out, options, threads, version_of(versions, job.renderer));
    } catch (const RenderCancelled&) {  // interrupted: neither done nor failed; a resume renders it
      std::lock_guard<std::mutex> lock(mutex);
      r.attempted[i] = 0;
      return;
    } catch (const std::exception& e) {
      error = e.what();
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::lock_guard<std::mutex> lock(mutex);
    ++finished;
    busy_seconds += seconds;
    const std::string first_line = error.substr(0, error.find('\n'));
    if (error.empty()) {
      r.done[i] = 1;
      ++stats.rendered;
    } else {
      r.errors[i] = error;
      ++stats.failed;
      stats.failures.push_back(job.label + ": " + first_line);
    }
    const double eta = busy_seconds / double(finished) * double(todo.size() - finished) /
                       std::max(1, options.jobs);
    if (options.progress) options.progress(stats.cached + finished, jobs.size(), eta);
    if (options.log)
      options.log(fmt::format("[{}/{}] {} {} ({:.1f} s){}", stats.cached + finished, jobs.size(),
                              error.empty() ? "rendered" : "FAILED", job.label, seconds,
                              error.empty() ? "" : ": " + first_line));
  });
}

// The render phase: the cache, then what it lacks; counts what never started.
Renders render_jobs(const std::string& study_file, const std::vector<Job>& jobs,
                    const fs::path& out, const StudyOptions& options,
                    const std::map<RendererKind, std::string>& versions,
                    const std::map<RendererKind, std::string>& unavailable, StudyRunStats& stats) {
  Renders r(jobs.size());
  const std::vector<std::size_t> todo = use_cache(jobs, out, options, r, stats);
  // The cache must hold what is to be rendered (uncompressed EXR sizes).
  ResourceEstimate needed;
  for (std::size_t i : todo) needed.output_bytes += jobs[i].resources.output_bytes;
  check_resources(needed, std::numeric_limits<double>::infinity(), study_file,
                  (out / "cache").string());
  if (options.log)
    options.log(fmt::format("{} renders: {} cached, {} to do, {} in parallel", jobs.size(),
                            stats.cached, todo.size(), options.jobs));
  render_todo(jobs, todo, out, options, versions, unavailable, r, stats);
  for (std::size_t i = 0; i < jobs.size(); ++i)
    if (r.same_as[i] >= 0) {
      const auto j = static_cast<std::size_t>(r.same_as[i]);
      r.done[i] = r.done[j], r.attempted[i] = r.attempted[j], r.errors[i] = r.errors[j];
      r.images[i] = r.images[j];
    }
  for (std::size_t i = 0; i < jobs.size(); ++i)
    if (!r.done[i] && !r.attempted[i]) ++stats.not_started;
  return r;
}

}  // namespace

StudyRunStats run_study(const Study& study, const StudyOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const fs::path out(options.output_dir);

  // Renderer versions first: a missing renderer fails its renders, not the study.
  std::map<RendererKind, std::string> versions, unavailable;
  for (RendererKind r : study.renderers) {
    try {
      RenderSettings probe;
      probe.timeout_s = options.timeout_s;
      versions[r] = renderer_version(r, probe);
    } catch (const std::exception& e) {
      unavailable[r] = e.what();
    }
  }
  Plan plan = plan_study(study, versions, options.max_memory_bytes);
  std::vector<Variant>& variants = plan.variants;
  std::vector<Job>& jobs = plan.jobs;
  const json& lowpoly_skipped = plan.lowpoly_skipped;

  StudyRunStats stats;
  stats.renders = jobs.size();
  if (options.dry_run) {
    for (const Job& job : jobs) {
      ++stats.planned[to_string(job.renderer)];
      if (fs::exists(out / "cache" / (job.key + ".exr"))) ++stats.cached;
    }
    return stats;
  }
  for (const char* sub : {"cache", "images"}) {
    std::error_code ec;
    fs::create_directories(out / sub, ec);
    if (ec)
      throw OutputError(fmt::format("{}: cannot create: {}", (out / sub).string(), ec.message()));
    // What a killed earlier run (kill -9) left half-written.
    stats.stale_removed += remove_stale_temporaries((out / sub).string());
  }
  if (stats.stale_removed > 0)
    warn(options, stats,
         fmt::format("removed {} temporary files and work folders of killed runs",
                     stats.stale_removed));

  // Render what the cache lacks.
  const Renders rendered =
      render_jobs(study.file, jobs, out, options, versions, unavailable, stats);
  const std::vector<std::string>& errors = rendered.errors;
  const std::vector<char>& done = rendered.done;
  const std::vector<Image>& images = rendered.images;
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (stats.not_started > 0) return stats;  // interrupted: no report from a partial study

  // Profiles and comparisons, in job order (deterministic).
  auto find_job = [&](std::size_t v, RendererKind r, Representation rep,
                      const std::string& method) -> long {
    for (std::size_t i : variants[v].jobs)
      if (jobs[i].renderer == r && jobs[i].representation == rep && jobs[i].method == method)
        return static_cast<long>(i);
    return -1;
  };
  const ProfileOptions po;
  json variants_json = json::array(), comparisons = json::array();
  std::string csv = "study,variant,scene";
  for (const StudyAxis& a : study.axes) csv += "," + csv_field(a.pointer);
  csv +=
      ",renderer,method,reference,profile_rmse_terminator,profile_rmse_overall,"
      "profile_max_error_terminator,profile_max_step,reference_max_step,position_deg,"
      "reference_position_deg,position_error_deg,width_deg,reference_width_deg,lit_bias,"
      "common_bins,image_mask_iou,image_rmse,image_ssim,image_max_error,image_mean_error,"
      "image_pixels,image_nonfinite\n";
  std::size_t nonfinite_total = 0;
  for (std::size_t v = 0; v < variants.size(); ++v) {
    const Variant& var = variants[v];
    if (var.lowpoly) continue;
    json renders = json::array();
    for (std::size_t i : var.jobs) {
      const Job& job = jobs[i];
      if (!done[i]) continue;
      const double scale = radiance_scale(job.scene);
      const std::string stem = file_safe(job.label);
      const std::string image_rel = "images/" + stem + ".png";
      write_preview_png(images[i], (out / image_rel).string());
      json difference;
      const long ground = find_job(v, job.renderer, Representation::kDisplacement, "none");
      if (job.representation == Representation::kBump && ground >= 0 && done[ground]) {
        const std::string diff_rel = "images/" + stem + "-diff.png";
        write_difference_png(images[i], images[ground], scale, (out / diff_rel).string());
        difference = diff_rel;
      }
      renders.push_back({{"renderer", to_string(job.renderer)},
                         {"representation", to_string(job.representation)},
                         {"method", job.method},
                         {"image", image_rel},
                         {"difference", difference},
                         {"exr", "cache/" + job.key + ".exr"},
                         {"profile", profile_json(terminator_profile(images[i], scale, po))}});
      if (job.representation != Representation::kBump) continue;
      // Against the same renderer's ground truth, and the evaluator's.
      std::vector<std::pair<RendererKind, long>> refs{{job.renderer, ground}};
      if (job.renderer != RendererKind::kEvaluator)
        refs.push_back({RendererKind::kEvaluator, find_job(v, RendererKind::kEvaluator,
                                                           Representation::kDisplacement, "none")});
      for (const auto& [ref_renderer, ref] : refs) {
        if (ref < 0 || !done[ref]) continue;
        const ProfileMetrics pm = compare_profiles(terminator_profile(images[i], scale, po),
                                                   terminator_profile(images[ref], scale, po), po);
        const ImageMetrics im = compare_images(images[i], images[ref]);
        nonfinite_total += im.nonfinite;
        const std::string reference = std::string(to_string(ref_renderer)) + ":displacement";
        const json pj = profile_metrics_json(pm), ij = image_metrics_json(im);
        comparisons.push_back({{"variant", var.id},
                               {"scene", var.scene},
                               {"axis_values", var.axis_values},
                               {"renderer", to_string(job.renderer)},
                               {"method", job.method},
                               {"reference", reference},
                               {"profile", pj},
                               {"image", ij}});
        csv += csv_row(
            study.name, var, to_string(job.renderer), job.method, reference,
            {{&pj,
              {"rmse_terminator", "rmse_overall", "max_error_terminator", "max_step",
               "reference_max_step", "position_deg", "reference_position_deg", "position_error_deg",
               "width_deg", "reference_width_deg", "lit_bias", "common_bins"}},
             {&ij,
              {"mask_iou", "rmse", "ssim", "max_error", "mean_error", "pixels", "nonfinite"}}});
      }
    }
    variants_json.push_back({{"id", var.id},
                             {"scene", var.scene},
                             {"label", var.label},
                             {"axis_values", var.axis_values},
                             {"renders", renders}});
  }

  // Low-poly section: every offset against the analytic surface, the same
  // renderer's and the evaluator's.
  json lowpoly = nullptr;
  if (study.lowpoly) {
    const LowPolyPart& part = *study.lowpoly;
    json lp_variants = json::array(), lp_comparisons = json::array();
    std::string lp_csv = "study,variant,scene";
    for (const StudyAxis& a : part.axes) lp_csv += "," + csv_field(a.pointer);
    lp_csv +=
        ",renderer,offset,reference,darkened_fraction,max_darkening,lost_shadow_fraction,"
        "shadow_shift_px,shadowed_pixels,test_shadowed_pixels,profile_rmse_terminator,"
        "profile_rmse_overall,profile_max_step,position_error_deg,lit_bias,image_rmse,image_ssim,"
        "image_mask_iou,image_nonfinite\n";
    for (std::size_t v = 0; v < variants.size(); ++v) {
      const Variant& var = variants[v];
      if (!var.lowpoly) continue;
      json renders = json::array();
      for (std::size_t i : var.jobs) {
        const Job& job = jobs[i];
        if (!done[i]) continue;
        const double scale = radiance_scale(job.scene);
        const std::string stem = file_safe(job.label);
        const std::string image_rel = "images/" + stem + ".png";
        write_preview_png(images[i], (out / image_rel).string());
        const bool truth = job.method == "analytic";
        const long ground = find_job(v, job.renderer, job.representation, "analytic");
        json difference;
        if (!truth && ground >= 0 && done[ground]) {
          const std::string diff_rel = "images/" + stem + "-diff.png";
          write_difference_png(images[i], images[ground], scale, (out / diff_rel).string());
          difference = diff_rel;
        }
        renders.push_back(
            {{"renderer", to_string(job.renderer)},
             {"offset", job.method},
             {"triangles", job.scene.tessellation ? json(tessellated_triangle_count(
                                                        job.scene.shape, *job.scene.tessellation))
                                                  : json()},
             {"image", image_rel},
             {"difference", difference},
             {"exr", "cache/" + job.key + ".exr"},
             {"profile", profile_json(terminator_profile(images[i], scale, po))}});
        if (truth) continue;
        std::vector<std::pair<RendererKind, long>> refs{{job.renderer, ground}};
        if (job.renderer != RendererKind::kEvaluator)
          refs.push_back({RendererKind::kEvaluator,
                          find_job(v, RendererKind::kEvaluator, job.representation, "analytic")});
        for (const auto& [ref_renderer, ref] : refs) {
          if (ref < 0 || !done[ref]) continue;
          const ProfileMetrics pm =
              compare_profiles(terminator_profile(images[i], scale, po),
                               terminator_profile(images[ref], scale, po), po);
          const ImageMetrics im = compare_images(images[i], images[ref]);
          const ShadowMetrics sm = compare_shadows(images[i], images[ref], scale);
          nonfinite_total += im.nonfinite;
          const std::string reference = std::string(to_string(ref_renderer)) + ":analytic";
          const json pj = profile_metrics_json(pm), ij = image_metrics_json(im),
                     sj = shadow_metrics_json(sm);
          lp_comparisons.push_back({{"variant", var.id},
                                    {"scene", var.scene},
                                    {"axis_values", var.axis_values},
                                    {"renderer", to_string(job.renderer)},
                                    {"offset", job.method},
                                    {"reference", reference},
                                    {"shadow", sj},
                                    {"profile", pj},
                                    {"image", ij}});
          lp_csv += csv_row(
              study.name, var, to_string(job.renderer), job.method, reference,
              {{&sj,
                {"darkened_fraction", "max_darkening", "lost_shadow_fraction", "shadow_shift_px",
                 "shadowed_pixels", "test_shadowed_pixels"}},
               {&pj,
                {"rmse_terminator", "rmse_overall", "max_step", "position_error_deg", "lit_bias"}},
               {&ij, {"rmse", "ssim", "mask_iou", "nonfinite"}}});
        }
      }
      lp_variants.push_back({{"id", var.id},
                             {"scene", var.scene},
                             {"label", var.label},
                             {"axis_values", var.axis_values},
                             {"renders", renders}});
    }
    // Ranking: the evaluator's offsets against its analytic render, by the
    // mean fraction of lit pixels each one darkens.
    auto lp_rank = [&](const std::string& scene) {
      std::map<std::string, std::array<double, 3>> sums;  // darkened, rmse, count
      for (const json& c : lp_comparisons) {
        if (c["renderer"] != "evaluator" || c["reference"] != "evaluator:analytic") continue;
        if (!scene.empty() && c["scene"] != scene) continue;
        const json& d = c["shadow"]["darkened_fraction"];
        const json& e = c["profile"]["rmse_terminator"];
        if (!d.is_number() || !e.is_number()) continue;
        auto& sum = sums[c["offset"].get<std::string>()];
        sum[0] += d.get<double>(), sum[1] += e.get<double>(), sum[2] += 1.0;
      }
      std::vector<std::pair<double, std::string>> order;
      for (const auto& [m, sum] : sums) order.push_back({sum[0] / sum[2], m});
      std::sort(order.begin(), order.end());
      json list = json::array();
      for (const auto& [mean, m] : order)
        list.push_back({{"offset", m},
                        {"darkened_fraction", mean},
                        {"rmse_terminator", sums[m][1] / sums[m][2]},
                        {"count", static_cast<int>(sums[m][2])}});
      return list;
    };
    json lp_per_scene = json::array();
    std::vector<std::string> lp_scenes;
    for (const Variant& v : variants)
      if (v.lowpoly && std::find(lp_scenes.begin(), lp_scenes.end(), v.scene) == lp_scenes.end())
        lp_scenes.push_back(v.scene);
    for (const std::string& name : lp_scenes)
      lp_per_scene.push_back({{"scene", name}, {"offsets", lp_rank(name)}});
    json lp_renderers = json::array(), lp_missing = lowpoly_skipped;
    for (RendererKind r : part.renderers) {
      json offered = json::array();
      const auto available = offsets_offered(to_string(r));
      for (const StudyMethod& m : part.offsets) {
        if (std::find(available.begin(), available.end(), *offset_method_from_id(m.id)) !=
            available.end())
          offered.push_back(m.label);
        else
          lp_missing.push_back(
              {{"renderer", to_string(r)},
               {"offset", m.label},
               {"why", r == RendererKind::kPovray
                           ? "POV-Ray 3.7 has no shadow-ray offset: mesh2 with normal_vectors "
                             "shows the artifact (shadow line artifact, FS#242)"
                           : "Blender Cycles 3.4 offers only its geometry offset"}});
      }
      lp_renderers.push_back({{"id", to_string(r)}, {"offsets", offered}});
    }
    json lp_axes = json::array();
    for (const StudyAxis& a : part.axes)
      lp_axes.push_back({{"pointer", a.pointer}, {"label", a.label}, {"values", a.values}});
    lowpoly = {
        {"axes", lp_axes},
        {"convergence_axis",
         part.convergence_axis >= 0 ? json(part.axes[part.convergence_axis].pointer) : json()},
        {"renderers", lp_renderers},
        {"variants", lp_variants},
        {"comparisons", lp_comparisons},
        {"ranking",
         {{"metric", "shadow.darkened_fraction"},
          {"reference", "evaluator:analytic"},
          {"renderer", "evaluator"},
          {"per_scene", lp_per_scene},
          {"overall", lp_rank("")}}},
        {"missing", lp_missing},
        {"units",
         {{"darkened_fraction",
           "fraction of the pixels lit in the analytic render (>= 0.05 albedo*E/pi) that "
           "the mesh renders below half of it"},
          {"max_darkening", "largest analytic - mesh radiance, fraction of albedo*E/pi"},
          {"lost_shadow_fraction",
           "fraction of the analytic render's cast-shadow pixels (theta < 85 deg, below "
           "half of cos theta) that the mesh render lights"},
          {"shadow_shift_px", "distance between the two cast-shadow centroids, pixels"}}}};
    write_text_file((out / "lowpoly.csv").string(), lp_csv);
  }

  // Headline: evaluator methods against the evaluator's ground truth, by the
  // terminator-region profile RMSE, per base scene and overall.
  auto rank = [&](const std::string& scene) {
    std::map<std::string, std::pair<double, int>> sums;
    for (const json& c : comparisons) {
      if (c["renderer"] != "evaluator" || c["reference"] != "evaluator:displacement") continue;
      if (!scene.empty() && c["scene"] != scene) continue;
      const json& value = c["profile"]["rmse_terminator"];
      if (!value.is_number()) continue;
      auto& [sum, n] = sums[c["method"].get<std::string>()];
      sum += value.get<double>(), ++n;
    }
    std::vector<std::pair<double, std::string>> order;
    for (const auto& [m, sn] : sums) order.push_back({sn.first / sn.second, m});
    std::sort(order.begin(), order.end());
    json list = json::array();
    for (const auto& [mean, m] : order)
      list.push_back({{"method", m}, {"mean", mean}, {"count", sums[m].second}});
    return list;
  };
  json per_scene = json::array();
  std::vector<std::string> scene_names;
  for (const Variant& v : variants)  // the bump section's scenes: low-poly ones have no methods
    if (!v.lowpoly &&
        std::find(scene_names.begin(), scene_names.end(), v.scene) == scene_names.end())
      scene_names.push_back(v.scene);
  for (const std::string& s : scene_names)
    per_scene.push_back({{"scene", s}, {"methods", rank(s)}});

  json renderers = json::array(), missing = json::array(), failures = json::array();
  // A low-poly-only study has no bump rows to offer or miss.
  for (RendererKind r : study.scenes.empty() ? std::vector<RendererKind>{} : study.renderers) {
    json offered = json::array();
    const auto methods = methods_offered(to_string(r), Representation::kBump);
    for (const StudyMethod& m : study.methods) {
      if (std::find(methods.begin(), methods.end(), *method_from_id(m.id)) != methods.end())
        offered.push_back(m.label);
      else
        missing.push_back(
            {{"renderer", to_string(r)},
             {"method", m.label},
             {"why", r == RendererKind::kPovray
                         ? "POV-Ray has no shadow-terminator method (raw bump only)"
                         : "Blender Cycles 3.4 offers only none, chiang2019 (Bump node) and "
                           "shading-offset"}});
    }
    const char* note = r == RendererKind::kEvaluator
                           ? "reference evaluator: analytic shapes, exact displaced normals"
                       : r == RendererKind::kPovray
                           ? "POV-Ray 3.7: bump via normal{function}, ground truth via isosurface"
                           : "Blender 3.4 Cycles: bump via ray-differential finite differences, "
                             "ground truth via a displaced mesh";
    renderers.push_back({{"id", to_string(r)},
                         {"version", versions.count(r) ? json(versions[r]) : json()},
                         {"methods", offered},
                         {"note", note}});
  }
  for (std::size_t i = 0; i < jobs.size(); ++i)
    if (!done[i]) failures.push_back({{"render", jobs[i].label}, {"error", errors[i]}});
  json axes = json::array();
  for (const StudyAxis& a : study.axes)
    axes.push_back({{"pointer", a.pointer}, {"label", a.label}, {"values", a.values}});
  json plots = json::array();
  for (const StudyPlot& p : study.plots)
    plots.push_back(
        {{"metric", p.metric}, {"x", p.x}, {"y", p.y}, {"kind", p.kind}, {"renderer", p.renderer}});
  const json report = {{"format", "penumbra-report"},
                       {"version", kReportFormatVersion},
                       {"penumbra", kPenumbraVersion},
                       {"study", {{"name", study.name}, {"file", study.file}}},
                       {"units",
                        {{"profile", "fraction of albedo*E/pi"},
                         {"angles", "degrees"},
                         {"image", "W m^-2 sr^-1"},
                         {"theta", "angle between wi and the base (undisplaced) surface normal"},
                         {"terminator_region_deg", {kTerminatorBegin, kTerminatorEnd}},
                         {"lit_region_deg", {0.0, kLitEnd}},
                         {"dark_level", kDarkLevel}}},
                       {"axes", axes},
                       {"renderers", renderers},
                       {"variants", variants_json},
                       {"comparisons", comparisons},
                       {"ranking",
                        {{"metric", "profile.rmse_terminator"},
                         {"reference", "evaluator:displacement"},
                         {"renderer", "evaluator"},
                         {"per_scene", per_scene},
                         {"overall", rank("")}}},
                       {"missing", missing},
                       {"failures", failures},
                       {"nonfinite_pixels", nonfinite_total},
                       {"plots", plots},
                       {"lowpoly", lowpoly}};
  write_text_file((out / "report.json").string(), report.dump(1) + "\n");
  write_text_file((out / "metrics.csv").string(), csv);

  if (options.figures) {
    if (options.log)
      options.log(
          fmt::format("figures: drawing the figures and report.html (harness/report.py, "
                      "log {}) ...",
                      (out / "report.log").string()));
    run_plot_script({"report", fs::absolute(out).string()}, (out / "report.log").string(),
                    options.python, options.timeout_s);
    stats.report_html = (out / "report.html").string();
  }
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

}  // namespace penumbra
