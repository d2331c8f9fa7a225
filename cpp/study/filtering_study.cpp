#include "study/filtering_study.h"

#include <chrono>
#include <filesystem>

#include <fmt/format.h>

#include "image/bump_maps.h"
#include "image/image_io.h"
#include "renderers/code_digest.h"
#include "scene/scene_json.h"
#include "util/files.h"
#include "util/hash.h"
#include "util/strict_json.h"
#include "util/version.h"

namespace penumbra {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

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

std::vector<FilteringEntry> run_filtering_section(const FilteringSection& section,
                                                  const StepContext& context) {
  // The experiment's footprints are its parallel tasks, as many at once as
  // the run renders at once (the same bits on any number).
  const int jobs = context.parallelism.renders;
  const auto& log = context.log;
  std::vector<FilteringEntry> entries;
  for (const FilteringMapSpec& spec : section.maps) {
    const PreparedMap map = prepare_map(spec);
    const std::vector<PyramidLevel> pyramid = build_bump_pyramid(offsets_from_heights(
        map.heights, map.width, map.height, map.texel_size, map.height_scale, spec.edge));
    for (const FilteringRunSpec& run : section.runs) {
      entries.push_back(measure_entry(section, spec, run, map, pyramid, context.out_dir, jobs));
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
