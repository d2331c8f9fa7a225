// Options and checks that several commands share (cli/command.h).
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include <fmt/format.h>

#include "cli/command.h"
#include "core/terminator.h"
#include "renderers/renderers.h"
#include "util/strict_json.h"

namespace penumbra {

namespace fs = std::filesystem;

const CLI::Validator& finite_number() {
  static const CLI::Validator validator(
      [](std::string& text) -> std::string {
        errno = 0;
        char* end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || std::isfinite(value)) return "";  // CLI11 says "not a number"
        return fmt::format("expected a finite number, got \"{}\"", printable(text, 40));
      },
      "", "finite");
  return validator;
}

void require_finite_numbers(CLI::App& app) {
  for (CLI::Option* option : app.get_options())
    // transform() puts it first: before a range check says "not in range".
    if (option->get_type_name().find("FLOAT") != std::string::npos)
      option->transform(finite_number());
  for (CLI::App* sub : app.get_subcommands({})) require_finite_numbers(*sub);
}

CLI::Option* add_jobs_option(CLI::App* cmd, SharedOptions& shared) {
  return cmd->add_option("--jobs", shared.jobs,
                         "renders at once, or other independent tasks (comparisons, filtering "
                         "footprints); default: --threads (all cores). Each render gets "
                         "--threads / JOBS threads, at least one");
}

void add_scene_options(CLI::App* cmd, SceneArgs& a) {
  cmd->add_option("--method", a.method, "terminator method id (see `penumbra methods`)");
  cmd->add_option("--offset", a.offset,
                  "shadow-ray origin method of a low-poly mesh (see `penumbra methods`)");
  cmd->add_option("--segments", a.segments,
                  "tessellate the shape: segments around the axis "
                  "(sets /shape/tessellation/segments)")
      ->check(CLI::Range(3, 65536));
  cmd->add_option("--representation", a.representation, "smooth, bump or displacement");
  cmd->add_option("--width", a.width, "image width in pixels")->check(CLI::PositiveNumber);
  cmd->add_option("--height", a.height, "image height in pixels")->check(CLI::PositiveNumber);
  cmd->add_option("--spp", a.spp, "samples per pixel")->check(CLI::PositiveNumber);
  cmd->add_option("--set", a.sets, "override a scene value: /json/pointer=VALUE (repeatable)");
}

namespace {

std::vector<Override> collect_overrides(const SceneArgs& a) {
  std::vector<Override> overrides;
  if (!a.method.empty()) overrides.push_back({"/terminator/method", a.method});
  if (!a.offset.empty()) overrides.push_back({"/offset/method", a.offset});
  if (a.segments > 0) overrides.push_back({"/shape/tessellation/segments", a.segments});
  if (!a.representation.empty()) overrides.push_back({"/representation", a.representation});
  if (a.width > 0) overrides.push_back({"/camera/width", a.width});
  if (a.height > 0) overrides.push_back({"/camera/height", a.height});
  if (a.spp > 0) overrides.push_back({"/camera/spp", a.spp});
  for (const std::string& s : a.sets) overrides.push_back(parse_override(s));
  return overrides;
}

}  // namespace

LoadedScene read_scene(const std::string& path, const SceneArgs& a) {
  if (!is_scene_file_name(path)) {
    // The default scene frames what will be read: the node a --set names.
    std::string node;
    for (const Override& o : collect_overrides(a))
      if (o.pointer == "/shape/node" && o.value.is_string()) node = o.value.get<std::string>();
    return read_scene_document(asset_scene_document(path, node), path, a);
  }
  return read_scene_document(read_json_file(path), path, a);
}

LoadedScene read_scene_document(nlohmann::json document, const std::string& path,
                                const SceneArgs& a) {
  const std::vector<Override> overrides = collect_overrides(a);
  const std::string origin = overrides.empty() ? path : path + " (after --set)";
  apply_overrides(document, overrides, origin);
  resolve_map_files(document, path);  // after --set: its /height/file too
  Scene scene = scene_from_json(document, origin);
  return {std::move(document), origin, std::move(scene)};
}

void check_offered(RendererKind renderer, const Scene& scene) {
  const auto methods = methods_offered(renderer, scene.representation);
  const TerminatorMethod method = scene.terminator.method.method;
  if (std::find(methods.begin(), methods.end(), method) == methods.end()) {
    std::string ids;
    for (TerminatorMethod m : methods)
      ids += (ids.empty() ? "" : ", ") + std::string(method_info(m).id);
    throw ExportError(fmt::format(
        "{} does not offer the method \"{}\" for the {} representation "
        "(it offers: {})",
        to_string(renderer), method_info(method).id, to_string(scene.representation), ids));
  }
  const auto offsets = offsets_offered(renderer);
  if (std::find(offsets.begin(), offsets.end(), scene.offset.method) == offsets.end())
    throw ExportError(fmt::format("{} does not offer the shadow-ray offset \"{}\"",
                                  to_string(renderer), offset_method_info(scene.offset.method).id));
}

void check_extension(const std::string& path, const char* extension, const char* option,
                     const char* why) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  if (ext != extension)
    throw UsageError(fmt::format("{} {}: expected a file name ending in {} (got \"{}\"){}", option,
                                 path, extension, ext, why));
}

void add_map_options(CLI::App* cmd, MapArgs& a) {
  cmd->add_option("heights", a.heights, "height map (EXR, PNG, ...)")->required();
  cmd->add_option("-o,--output", a.output, "output folder")->required();
  cmd->add_option("--channel", a.channel,
                  "the height channel (required when the file has several)");
  cmd->add_option("--texel-size", a.texel_size,
                  "scene units per texel (default: 1 / width, the map spans one unit)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--height-scale", a.height_scale, "scene units per unit of the file's values")
      ->capture_default_str();
  cmd->add_option("--edge", a.edge, "differences across the map's edge: wrap (tiled) or clamp")
      ->capture_default_str();
}

MapEdge check_map_args(const MapArgs& a) {
  std::optional<MapEdge> edge;
  for (const EnumName<MapEdge>& e : kMapEdgeNames)
    if (a.edge == e.name) edge = e.value;
  if (!edge) throw UsageError(fmt::format("--edge: expected wrap or clamp, got \"{}\"", a.edge));
  if (a.output.empty()) throw UsageError("-o: expected a folder name, got \"\"");
  if (!std::isfinite(a.height_scale))
    throw UsageError(
        fmt::format("--height-scale: expected a finite number, got {}", a.height_scale));
  return *edge;
}

}  // namespace penumbra
