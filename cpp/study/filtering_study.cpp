#include "study/filtering_study.h"

#include <chrono>
#include <filesystem>
#include <set>

#include <fmt/format.h>

#include "image/bump_maps.h"
#include "image/image_io.h"
#include "renderers/code_digest.h"
#include "scene/scene_json.h"
#include "study/json_fields.h"
#include "study/names.h"
#include "util/files.h"
#include "util/hash.h"
#include "util/strict_json.h"
#include "util/version.h"

namespace penumbra {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// ---- reading ---------------------------------------------------------------

std::string read_plain_name(const json& object, const std::string& f, const std::string& p,
                            std::set<std::string>* seen) {
  const json& name = require(object, "name", f, p);
  if (!name.is_string() || !plain_name(name.get<std::string>()))
    throw InputError(f, p + "/name",
                     "expected a name of 1 to 100 letters, digits, '-', '_' or '.' (not "
                     "starting with '.'), got " +
                         describe_json(name));
  if (!seen->insert(name.get<std::string>()).second)
    throw InputError(f, p + "/name", "repeats an earlier name: " + describe_json(name));
  return name.get<std::string>();
}

double read_number(const json& object, const char* key, double lo, double hi, bool open_lo,
                   double fallback, const std::string& f, const std::string& p) {
  if (!object.contains(key)) return fallback;
  const json& v = object.at(key);
  const double x = v.is_number() ? v.get<double>() : lo - 1.0;
  if (!v.is_number() || (open_lo ? !(x > lo) : !(x >= lo)) || !(x <= hi))
    throw InputError(f, child(p, key),
                     fmt::format("expected a number in {}{}, {}], got {}", open_lo ? "(" : "[", lo,
                                 hi, describe_json(v)));
  return x;
}

int read_integer(const json& object, const char* key, int lo, int hi, int fallback,
                 const std::string& f, const std::string& p) {
  if (!object.contains(key)) return fallback;
  const long long n = strict_integer(object.at(key), lo, hi);
  if (n < 0 && lo >= 0)
    throw InputError(f, child(p, key),
                     fmt::format("expected an integer in [{}, {}], got {}", lo, hi,
                                 describe_json(object.at(key))));
  return static_cast<int>(n);
}

std::string read_string(const json& object, const char* key, const std::string& f,
                        const std::string& p) {
  const json& v = object.at(key);
  if (!v.is_string() || v.get<std::string>().empty())
    throw InputError(f, child(p, key), "expected a non-empty string, got " + describe_json(v));
  return v.get<std::string>();
}

MapEdge read_edge(const json& m, MapEdge fallback, const std::string& f, const std::string& p) {
  if (!m.contains("edge")) return fallback;
  const json& e = m["edge"];
  for (const auto& entry : kMapEdgeNames)
    if (e.is_string() && e.get<std::string>() == entry.name) return entry.value;
  throw InputError(f, p + "/edge", "expected \"wrap\" or \"clamp\", got " + describe_json(e));
}

// {"name", "bake": scene, "size", "extent", "edge"} or
// {"name", "file", "channel", "texel_size", "height_scale", "edge"}.
FilteringMapSpec read_map(const json& m, const std::string& f, const std::string& p,
                          const fs::path& base, std::set<std::string>* names) {
  if (!m.is_object()) throw InputError(f, p, "expected an object with \"bake\" or \"file\"");
  FilteringMapSpec map;
  map.name = read_plain_name(m, f, p, names);
  if (m.contains("bake") == m.contains("file"))
    throw InputError(f, p, "expected exactly one of \"bake\" (a scene file) and \"file\" (a map)");
  if (m.contains("bake")) {
    reject_unknown(m, {"name", "bake", "size", "extent", "edge"}, f, p);
    const fs::path scene = base / read_string(m, "bake", f, p);
    if (!fs::is_regular_file(scene))
      throw InputError(f, p + "/bake", "no such scene file: " + scene.string());
    map.bake_scene = scene.lexically_normal().string();
    map.size = read_integer(m, "size", 2, 16384, 1024, f, p);
    map.extent = read_number(m, "extent", 0.0, 1e6, true, 1.0, f, p);
    map.edge = read_edge(m, MapEdge::kClamp, f, p);
    return map;
  }
  reject_unknown(m, {"name", "file", "channel", "texel_size", "height_scale", "edge"}, f, p);
  const fs::path file = base / read_string(m, "file", f, p);
  if (!fs::is_regular_file(file))
    throw InputError(f, p + "/file", "no such height map: " + file.string());
  map.file = file.lexically_normal().string();
  if (m.contains("channel")) map.channel = read_string(m, "channel", f, p);
  map.texel_size = read_number(m, "texel_size", 0.0, 1e6, true, 0.0, f, p);
  map.height_scale = read_number(m, "height_scale", 0.0, 1e6, true, 1.0, f, p);
  map.edge = read_edge(m, MapEdge::kWrap, f, p);
  return map;
}

// {"name", "lookup": "box" | "trilinear", "shift": pixels in [0, 1) | "random"}.
FilteringRunSpec read_run(const json& r, const std::string& f, const std::string& p,
                          std::set<std::string>* names) {
  if (!r.is_object()) throw InputError(f, p, "expected {\"name\", \"lookup\", \"shift\"}");
  reject_unknown(r, {"name", "lookup", "shift"}, f, p);
  FilteringRunSpec run;
  run.name = read_plain_name(r, f, p, names);
  if (r.contains("lookup")) {
    const json& l = r["lookup"];
    if (l == "box")
      run.lookup = FilteringOptions::Lookup::kBox;
    else if (l == "trilinear")
      run.lookup = FilteringOptions::Lookup::kTrilinear;
    else
      throw InputError(f, p + "/lookup",
                       "expected \"box\" or \"trilinear\", got " + describe_json(l));
  }
  if (!r.contains("shift")) return run;
  const json& shift = r["shift"];
  if (shift == "random") {
    run.random_shift = true;
  } else if (shift.is_number() && shift.get<double>() >= 0.0 && shift.get<double>() < 1.0) {
    run.shift = shift.get<double>();
  } else {
    throw InputError(
        f, p + "/shift",
        "expected a number of pixels in [0, 1) or \"random\", got " + describe_json(shift));
  }
  return run;
}

std::vector<RoughnessFilter> read_filters(const json& list, const std::string& f,
                                          const std::string& p) {
  if (!list.is_array() || list.empty())
    throw InputError(f, p, "expected a non-empty array of roughness filter ids");
  std::vector<RoughnessFilter> filters;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string q = fmt::format("{}/{}", p, i);
    const auto filter =
        list[i].is_string() ? roughness_filter_from_id(list[i].get<std::string>()) : std::nullopt;
    if (!filter)
      throw InputError(
          f, q, "expected a roughness filter id (penumbra methods), got " + describe_json(list[i]));
    if (!is_measurable(*filter))
      throw InputError(f, q,
                       fmt::format("{} has no normalised BRDF in its source, so it cannot be "
                                   "measured",
                                   roughness_filter_info(*filter).id));
    filters.push_back(*filter);
  }
  return filters;
}

std::vector<double> read_alphas(const json& list, const std::string& f, const std::string& p) {
  if (!list.is_array() || list.empty())
    throw InputError(f, p, "expected a non-empty array of GGX alphas in (0, 1]");
  std::vector<double> alphas;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const double a = list[i].is_number() ? list[i].get<double>() : -1.0;
    if (!(a > 0.0 && a <= 1.0))
      throw InputError(f, fmt::format("{}/{}", p, i),
                       "expected a GGX alpha in (0, 1], got " + describe_json(list[i]));
    alphas.push_back(a);
  }
  return alphas;
}

}  // namespace

FilteringSection read_filtering_section(const json& s, const std::string& f,
                                        const std::string& base_dir) {
  const std::string p = "/filtering";
  if (!s.is_object()) throw InputError(f, p, "expected an object with \"maps\"");
  reject_unknown(s,
                 {"maps", "runs", "alphas", "filters", "max_level", "footprints", "view_deg",
                  "sweep_step_deg", "seed"},
                 f, p);
  FilteringSection out;
  const json& maps = require(s, "maps", f, p);
  if (!maps.is_array() || maps.empty())
    throw InputError(f, p + "/maps", "expected a non-empty array of maps");
  std::set<std::string> map_names, run_names;
  for (std::size_t i = 0; i < maps.size(); ++i)
    out.maps.push_back(
        read_map(maps[i], f, fmt::format("{}/maps/{}", p, i), fs::path(base_dir), &map_names));
  if (s.contains("runs")) {
    const json& runs = s["runs"];
    if (!runs.is_array() || runs.empty())
      throw InputError(f, p + "/runs", "expected a non-empty array of runs");
    for (std::size_t i = 0; i < runs.size(); ++i)
      out.runs.push_back(read_run(runs[i], f, fmt::format("{}/runs/{}", p, i), &run_names));
  } else {
    out.runs.push_back({"box", FilteringOptions::Lookup::kBox, 0.0, false});
  }
  FilteringOptions& o = out.options;
  if (s.contains("alphas")) o.alphas = read_alphas(s["alphas"], f, p + "/alphas");
  o.filters =
      s.contains("filters") ? read_filters(s["filters"], f, p + "/filters") : measurable_filters();
  o.max_level = read_integer(s, "max_level", 0, 14, o.max_level, f, p);
  o.footprints = read_integer(s, "footprints", 1, 1 << 20, o.footprints, f, p);
  o.view_deg = read_number(s, "view_deg", 0.0, 80.0, false, o.view_deg, f, p);
  o.sweep_step_deg = read_number(s, "sweep_step_deg", 0.0, 10.0, true, o.sweep_step_deg, f, p);
  o.seed = static_cast<std::uint64_t>(read_integer(s, "seed", 0, 1 << 30, 1, f, p));
  return out;
}

namespace {

// ---- running ---------------------------------------------------------------

struct PreparedMap {
  std::vector<float> heights;  // row-major from the top row
  int width = 0, height = 0;
  double texel_size = 0.0, height_scale = 1.0;
  std::string channel, source;
};

PreparedMap prepare_map(const FilteringMapSpec& m) {
  PreparedMap p;
  if (!m.bake_scene.empty()) {
    const Scene scene = load_scene(m.bake_scene);
    if (scene.height.family == HeightFamily::kNone || scene.height.map)
      throw InputError(m.bake_scene, "/height",
                       "expected an analytic height function to bake for the filtering study");
    const Image image =
        bake_height_map(scene.height.function, scene.height.amplitude, m.size, m.extent);
    p.heights.assign(image.pixels.begin(), image.pixels.end());  // one channel, "Y"
    p.width = p.height = m.size;
    p.texel_size = m.extent / m.size;
    p.channel = "Y";
    p.source = fmt::format(
        "{} baked over the plane [0, {:g})^2 at {}x{} texels (heights in scene "
        "units)",
        m.bake_scene, m.extent, m.size, m.size);
    return p;
  }
  HeightMap map = read_height_map(m.file, m.channel);
  p.heights = std::move(map.heights);
  p.width = map.width, p.height = map.height;
  p.texel_size = m.texel_size > 0.0 ? m.texel_size : 1.0 / map.width;
  p.height_scale = m.height_scale;
  p.channel = map.channel;
  p.source = fmt::format("{} (channel {}, {}x{} texels)", m.file, p.channel, p.width, p.height);
  return p;
}

FilteringOptions run_options(const FilteringSection& section, const FilteringRunSpec& run,
                             int jobs) {
  FilteringOptions o = section.options;
  o.lookup = run.lookup;
  o.shift = run.shift;
  o.random_shift = run.random_shift;
  o.jobs = jobs;
  return o;
}

// Everything the entry's numbers depend on (not the thread count: the
// experiment gives the same bits on any number of threads).
std::string entry_key(const PreparedMap& map, MapEdge edge, const FilteringOptions& o) {
  json filters = json::array();
  for (RoughnessFilter f : o.filters) filters.push_back(roughness_filter_info(f).id);
  const json inputs = {{"format", "penumbra-filtering-key/1"},
                       {"penumbra", kPenumbraVersion},
                       {"code", build_code_digests().filtering},
                       {"size", {map.width, map.height}},
                       {"texel_size", map.texel_size},
                       {"height_scale", map.height_scale},
                       {"edge", name_of<MapEdge>(kMapEdgeNames, edge)},
                       {"alphas", o.alphas},
                       {"filters", filters},
                       {"max_level", o.max_level},
                       {"footprints", o.footprints},
                       {"view_deg", o.view_deg},
                       {"sweep", {o.sweep_max_deg, o.sweep_step_deg}},
                       {"shift", o.random_shift ? json("random") : json(o.shift)},
                       {"lookup", o.lookup == FilteringOptions::Lookup::kBox ? "box" : "trilinear"},
                       {"seed", o.seed}};
  std::uint64_t h = fnv1a(inputs.dump());
  h = fnv1a(map.heights.data(), map.heights.size() * sizeof(float), h);
  return fmt::format("{:016x}", h);
}

// The findings of a filtering.json written earlier; nullopt when it is not
// one (the entry is then measured again).
std::optional<std::vector<std::string>> read_findings(const fs::path& path) {
  try {
    const json doc = read_json_file(path.string());
    std::vector<std::string> lines;
    for (const json& line : doc.at("findings")) lines.push_back(line.get<std::string>());
    return lines;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

FilteringEntry measure_entry(const FilteringSection& section, const FilteringMapSpec& spec,
                             const FilteringRunSpec& run, const PreparedMap& map,
                             const std::vector<PyramidLevel>& pyramid, const fs::path& out,
                             int jobs) {
  FilteringEntry e{
      spec.name, run.name, map.source, (fs::path("filtering") / spec.name / run.name).string(),
      false,     0.0,      {}};
  const FilteringOptions o = run_options(section, run, jobs);
  const fs::path folder = out / e.folder;
  const std::string key = entry_key(map, spec.edge, o);
  if (read_file((folder / "key").string()) == key + "\n") {
    if (auto findings = read_findings(folder / "filtering.json")) {
      e.reused = true;
      e.findings = std::move(*findings);
      return e;
    }
  }
  const auto start = std::chrono::steady_clock::now();
  const FilteringResult result = run_filtering_experiment(pyramid, o);
  e.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  e.findings = filtering_findings(result);
  const FilteringSource source{spec.bake_scene.empty() ? spec.file : spec.bake_scene,
                               map.channel,
                               map.width,
                               map.height,
                               map.texel_size,
                               map.height_scale,
                               name_of<MapEdge>(kMapEdgeNames, spec.edge)};
  fs::create_directories(folder);
  fs::remove(folder / "key");  // a half-rewritten folder never looks current
  write_text_file((folder / "filtering.csv").string(), filtering_csv(result));
  write_text_file((folder / "filtering.json").string(), filtering_json(result, o, source) + "\n");
  write_text_file((folder / "key").string(), key + "\n");
  return e;
}

}  // namespace

std::vector<FilteringEntry> run_filtering_section(
    const FilteringSection& section, const std::string& out_dir, int jobs,
    const std::function<void(const std::string&)>& log) {
  std::vector<FilteringEntry> entries;
  for (const FilteringMapSpec& spec : section.maps) {
    const PreparedMap map = prepare_map(spec);
    const std::vector<PyramidLevel> pyramid = build_bump_pyramid(offsets_from_heights(
        map.heights, map.width, map.height, map.texel_size, map.height_scale, spec.edge));
    for (const FilteringRunSpec& run : section.runs) {
      entries.push_back(measure_entry(section, spec, run, map, pyramid, out_dir, jobs));
      const FilteringEntry& e = entries.back();
      if (log)
        log(e.reused ? fmt::format("filtering {}/{}: unchanged, reused {}", e.map, e.run, e.folder)
                     : fmt::format("filtering {}/{}: measured in {:.1f} s into {}", e.map, e.run,
                                   e.seconds, e.folder));
    }
  }
  return entries;
}

json filtering_report_json(const std::vector<FilteringEntry>& entries, bool has_section) {
  if (!has_section) return nullptr;
  json out = json::array();
  for (const FilteringEntry& e : entries)
    out.push_back({{"map", e.map},
                   {"run", e.run},
                   {"source", e.source},
                   {"json", (fs::path(e.folder) / "filtering.json").generic_string()},
                   {"csv", (fs::path(e.folder) / "filtering.csv").generic_string()},
                   {"findings", e.findings}});
  return out;
}

}  // namespace penumbra
