// `penumbra renderers`: the renderer table (renderers/registry.h) with the
// methods and offsets each offers.
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli/command.h"
#include "core/shadow_origin.h"
#include "renderers/renderers.h"

namespace penumbra {

using nlohmann::json;

namespace {

json method_ids(const std::vector<TerminatorMethod>& methods) {
  json ids = json::array();
  for (TerminatorMethod m : methods) ids.push_back(method_info(m).id);
  return ids;
}

json offset_ids(const std::vector<OffsetMethod>& offsets) {
  json ids = json::array();
  for (OffsetMethod m : offsets) ids.push_back(offset_method_info(m).id);
  return ids;
}

json renderer_json(const RendererInfo& info) {
  return {{"id", info.id},
          {"name", info.name},
          {"debian_package", info.debian_package},
          {"executable", info.executable},
          {"executable_variable", info.executable_variable},
          {"note", info.note},
          {"bump_methods", method_ids(methods_offered(info, Representation::kBump))},
          {"smooth_and_displacement_methods",
           method_ids(methods_offered(info, Representation::kDisplacement))},
          {"methods_why_not", info.methods_why_not},
          {"offsets", offset_ids(offsets_offered(info))},
          {"offsets_why_not", info.offsets_why_not},
          {"props", info.props},
          {"height_maps", info.height_maps},
          {"height_maps_why_not", info.height_maps_why_not},
          {"normal_maps", info.normal_maps},
          {"normal_maps_why_not", info.normal_maps_why_not},
          {"plane", info.plane},
          {"plane_why_not", info.plane_why_not},
          {"consistent_normals", info.consistent_normals},
          {"consistent_normals_why_not", info.consistent_normals_why_not},
          {"mesh_bump", info.mesh_bump},
          {"mesh_bump_why_not", info.mesh_bump_why_not},
          {"reference_ni_methods", method_ids(info.reference_ni_methods)}};
}

std::string join_ids(const json& ids) {
  std::string text;
  for (const json& id : ids) text += (text.empty() ? "" : ", ") + id.get<std::string>();
  return text;
}

void print_renderer(const RendererInfo& info, std::ostream& out) {
  const json j = renderer_json(info);
  out << fmt::format("{} ({})\n  {}\n", info.id, info.name, info.note);
  if (*info.debian_package)
    out << fmt::format("  Debian package {}, executable `{}` (or ${})\n", info.debian_package,
                       info.executable, info.executable_variable);
  out << fmt::format("  bump methods: {}\n", join_ids(j["bump_methods"]));
  out << fmt::format("  smooth/displacement methods: {}\n",
                     join_ids(j["smooth_and_displacement_methods"]));
  out << fmt::format("  shadow-ray offsets: {}\n", join_ids(j["offsets"]));
  if (*info.methods_why_not) out << fmt::format("  why not more: {}\n", info.methods_why_not);
  if (*info.props_why_not) out << fmt::format("  props: {}\n", info.props_why_not);
  if (*info.specular_why_not) out << fmt::format("  glossy: {}\n", info.specular_why_not);
  if (*info.height_maps_why_not)
    out << fmt::format("  height maps: {}\n", info.height_maps_why_not);
  if (*info.normal_maps_why_not)
    out << fmt::format("  normal maps: {}\n", info.normal_maps_why_not);
  if (*info.plane_why_not) out << fmt::format("  plane: {}\n", info.plane_why_not);
  if (*info.consistent_normals_why_not)
    out << fmt::format("  consistent normals: {}\n", info.consistent_normals_why_not);
  if (*info.mesh_bump_why_not) out << fmt::format("  mesh bump: {}\n", info.mesh_bump_why_not);
  if (!info.reference_ni_methods.empty())
    out << fmt::format("  reference normal Ni whatever the scene says: {}\n",
                       join_ids(j["reference_ni_methods"]));
}

}  // namespace

Command add_renderers_command(CLI::App& app, SharedOptions&) {
  auto as_json = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand(
      "renderers", "list the renderers: package, version probe, methods and offsets offered");
  cmd->add_flag("--json", *as_json, "print a JSON array");
  return {cmd, [as_json](const CommandContext& c) {
            if (*as_json) {
              json list = json::array();
              for (RendererKind r : all_renderers())
                list.push_back(renderer_json(renderer_info(r)));
              c.out << list.dump(2) << "\n";
              return kExitOk;
            }
            for (RendererKind r : all_renderers()) print_renderer(renderer_info(r), c.out);
            return kExitOk;
          }};
}

}  // namespace penumbra
