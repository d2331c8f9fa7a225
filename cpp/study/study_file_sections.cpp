#include "study/study_file_sections.h"

#include <optional>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "core/roughness_filter.h"
#include "core/terminator.h"
#include "image/bump_maps.h"
#include "study/names.h"
#include "util/files.h"
#include "util/strict_json.h"

namespace penumbra {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// ---- /filtering --------------------------------------------------------------

std::string read_plain_name(Reader& r, std::set<std::string>* seen) {
  const json& name = r.at("name");
  if (!name.is_string() || !plain_name(name.get<std::string>()))
    r.fail("name",
           "expected a name of 1 to 100 letters, digits, '-', '_' or '.' (not starting with "
           "'.'), got " +
               Reader::describe(name));
  if (!seen->insert(name.get<std::string>()).second)
    r.fail("name", "repeats an earlier name: " + Reader::describe(name));
  return name.get<std::string>();
}

// A number in [lo, hi], or (lo, hi] when `open_lo`.
double read_number(Reader& r, const char* key, double lo, double hi, bool open_lo,
                   double fallback) {
  return r.number_or(
      key, fallback, [&](double x) { return (open_lo ? x > lo : x >= lo) && x <= hi; },
      fmt::format("in {}{}, {}]", open_lo ? "(" : "[", lo, hi));
}

std::string read_string(Reader& r, const char* key) {
  const json& v = r.at(key);
  if (!v.is_string() || v.get<std::string>().empty())
    r.fail(key, "expected a non-empty string, got " + Reader::describe(v));
  return v.get<std::string>();
}

MapEdge read_edge(Reader& r, MapEdge fallback) {
  if (!r.has("edge")) return fallback;
  const json& e = r.at("edge");
  for (const auto& entry : kMapEdgeNames)
    if (e.is_string() && e.get<std::string>() == entry.name) return entry.value;
  r.fail("edge", "expected \"wrap\" or \"clamp\", got " + Reader::describe(e));
}

// {"name", "bake": scene, "size", "extent", "edge"} or
// {"name", "file", "channel", "texel_size", "height_scale", "edge"}.
FilteringMapSpec read_map(Reader m, const fs::path& base, std::set<std::string>* names) {
  FilteringMapSpec map;
  map.name = read_plain_name(m, names);
  if (m.has("bake") == m.has("file"))
    m.fail("", "expected exactly one of \"bake\" (a scene file) and \"file\" (a map)");
  if (m.has("bake")) {
    m.expect({"name", "bake", "size", "extent", "edge"});
    const fs::path scene = base / read_string(m, "bake");
    if (const std::string problem = input_file_problem(scene.string()); !problem.empty())
      m.fail("bake", fmt::format("scene file {}: {}", scene.string(), problem));
    map.bake_scene = scene.lexically_normal().string();
    map.size = static_cast<int>(m.integer_or("size", 1024, 2, 16384));
    map.extent = read_number(m, "extent", 0.0, 1e6, true, 1.0);
    map.edge = read_edge(m, MapEdge::kClamp);
    m.finish();
    return map;
  }
  m.expect({"name", "file", "channel", "texel_size", "height_scale", "edge"});
  const fs::path file = base / read_string(m, "file");
  if (const std::string problem = input_file_problem(file.string()); !problem.empty())
    m.fail("file", fmt::format("height map {}: {}", file.string(), problem));
  map.file = file.lexically_normal().string();
  if (m.has("channel")) map.channel = read_string(m, "channel");
  map.texel_size = read_number(m, "texel_size", 0.0, 1e6, true, 0.0);
  map.height_scale = read_number(m, "height_scale", 0.0, 1e6, true, 1.0);
  map.edge = read_edge(m, MapEdge::kWrap);
  m.finish();
  // Read now, as scene maps are: a map that cannot be measured (NaN, slopes
  // too steep) is refused before the run writes anything.
  try {
    const HeightMap heights = read_height_map(map.file, map.channel);
    check_map_slopes(heights, map.file, map.texel_size > 0.0 ? map.texel_size : 1.0 / heights.width,
                     map.height_scale);
  } catch (const InputError& e) {
    m.fail("file", e.what());
  }
  return map;
}

// {"name", "lookup": "box" | "trilinear", "shift": pixels in [0, 1) | "random"}.
FilteringRunSpec read_run(Reader r, std::set<std::string>* names) {
  r.expect({"name", "lookup", "shift"});
  FilteringRunSpec run;
  run.name = read_plain_name(r, names);
  if (r.has("lookup")) {
    const json& l = r.at("lookup");
    if (l == "box")
      run.lookup = FilteringOptions::Lookup::kBox;
    else if (l == "trilinear")
      run.lookup = FilteringOptions::Lookup::kTrilinear;
    else
      r.fail("lookup", "expected \"box\" or \"trilinear\", got " + Reader::describe(l));
  }
  if (r.has("shift")) {
    const json& shift = r.at("shift");
    if (shift == "random")
      run.random_shift = true;
    else if (shift.is_number() && shift.get<double>() >= 0.0 && shift.get<double>() < 1.0)
      run.shift = shift.get<double>();
    else
      r.fail("shift",
             "expected a number of pixels in [0, 1) or \"random\", got " + Reader::describe(shift));
  }
  r.finish();
  return run;
}

std::vector<RoughnessFilter> read_filters(Reader& s) {
  const json& list = s.nonempty_array("filters", "roughness filter ids");
  std::vector<RoughnessFilter> filters;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const auto filter =
        list[i].is_string() ? roughness_filter_from_id(list[i].get<std::string>()) : std::nullopt;
    if (!filter)
      s.fail_item(
          "filters", i,
          "expected a roughness filter id (penumbra methods), got " + Reader::describe(list[i]));
    if (!is_measurable(*filter))
      s.fail_item("filters", i,
                  fmt::format("{} has no normalised BRDF in its source, so it cannot be measured",
                              roughness_filter_info(*filter).id));
    filters.push_back(*filter);
  }
  return filters;
}

std::vector<double> read_alphas(Reader& s) {
  const json& list = s.nonempty_array("alphas", "GGX alphas in (0, 1]");
  std::vector<double> alphas;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const double a = list[i].is_number() ? list[i].get<double>() : -1.0;
    if (!(a > 0.0 && a <= 1.0))
      s.fail_item("alphas", i, "expected a GGX alpha in (0, 1], got " + Reader::describe(list[i]));
    alphas.push_back(a);
  }
  return alphas;
}

// ---- /interplay --------------------------------------------------------------

std::vector<std::optional<int>> read_levels(Reader& s) {
  const json& list = s.nonempty_array("levels", "pyramid levels (null: unfiltered)");
  std::vector<std::optional<int>> levels;
  for (std::size_t i = 0; i < list.size(); ++i) {
    if (list[i].is_null()) {
      levels.push_back(std::nullopt);
      continue;
    }
    const std::optional<long long> level = strict_integer(list[i], 0, 16);
    if (!level)
      s.fail_item(
          "levels", i,
          "expected null (unfiltered) or a level in [0, 16], got " + Reader::describe(list[i]));
    levels.push_back(static_cast<int>(*level));
  }
  return levels;
}

std::vector<std::string> read_methods(Reader& s) {
  const json& list = s.nonempty_array("methods", "terminator method ids");
  std::vector<std::string> methods;
  for (std::size_t i = 0; i < list.size(); ++i) {
    if (!list[i].is_string() || !method_from_id(list[i].get<std::string>()))
      s.fail_item(
          "methods", i,
          "expected a terminator method id (penumbra methods), got " + Reader::describe(list[i]));
    methods.push_back(list[i].get<std::string>());
  }
  return methods;
}

}  // namespace

FilteringSection read_filtering_section(Reader s, const fs::path& base) {
  s.expect({"maps", "runs", "alphas", "filters", "max_level", "footprints", "view_deg",
            "sweep_step_deg", "seed"});
  FilteringSection out;
  const json& maps = s.nonempty_array("maps", "maps");
  std::set<std::string> map_names, run_names;
  for (std::size_t i = 0; i < maps.size(); ++i)
    out.maps.push_back(read_map(s.item("maps", i, "expected an object with \"bake\" or \"file\""),
                                base, &map_names));
  if (s.has("runs")) {
    const json& runs = s.nonempty_array("runs", "runs");
    for (std::size_t i = 0; i < runs.size(); ++i)
      out.runs.push_back(
          read_run(s.item("runs", i, "expected {\"name\", \"lookup\", \"shift\"}"), &run_names));
  } else {
    out.runs.push_back({"box", FilteringOptions::Lookup::kBox, 0.0, false});
  }
  FilteringOptions& o = out.options;
  if (s.has("alphas")) o.alphas = read_alphas(s);
  o.filters = s.has("filters") ? read_filters(s) : measurable_filters();
  o.max_level = static_cast<int>(s.integer_or("max_level", o.max_level, 0, 14));
  o.footprints = static_cast<int>(s.integer_or("footprints", o.footprints, 1, 1 << 20));
  o.view_deg = read_number(s, "view_deg", 0.0, 80.0, false, o.view_deg);
  o.sweep_step_deg = read_number(s, "sweep_step_deg", 0.0, 10.0, true, o.sweep_step_deg);
  o.seed = static_cast<std::uint64_t>(s.integer_or("seed", 1, 0, 1 << 30));
  s.finish();
  return out;
}

InterplaySection read_interplay_section(Reader s, const fs::path& base) {
  s.expect({"scene", "size", "filter", "levels", "methods", "set"});
  InterplaySection out;
  const json& scene = s.at("scene");
  const fs::path path = base / (scene.is_string() ? scene.get<std::string>() : "");
  if (!scene.is_string()) s.fail("scene", "expected a scene file, got " + Reader::describe(scene));
  if (const std::string problem = input_file_problem(path.string()); !problem.empty())
    s.fail("scene", fmt::format("scene file {}: {}", path.string(), problem));
  out.scene = path.lexically_normal().string();
  if (s.has("size")) {
    const std::optional<long long> size = strict_integer(s.at("size"), 16, 16384);
    if (!size)
      s.fail("size", "expected an integer in [16, 16384] (texels around the shape), got " +
                         Reader::describe(s.at("size")));
    out.size = static_cast<int>(*size);
  }
  if (s.has("filter")) {
    const json& id = s.at("filter");
    const auto filter =
        id.is_string() ? roughness_filter_from_id(id.get<std::string>()) : std::nullopt;
    if (!filter || !is_measurable(*filter))
      s.fail("filter", "expected a roughness filter id with a BRDF (penumbra methods), got " +
                           Reader::describe(id));
    out.filter = id.get<std::string>();
  }
  out.levels =
      s.has("levels") ? read_levels(s) : std::vector<std::optional<int>>{std::nullopt, 2, 4, 6};
  out.methods =
      s.has("methods") ? read_methods(s) : std::vector<std::string>{"none", "estevez2019"};
  if (s.has("set")) {
    if (!s.at("set").is_object()) s.fail("set", "expected an object of JSON pointer -> value");
    out.set = s.at("set");
  }
  s.finish();
  return out;
}

}  // namespace penumbra
