// `penumbra export`: a scene as POV-Ray SDL or a Blender job, written by the
// renderer's entry (RendererEntry::export_files, renderers/renderer.h).
#include <filesystem>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "cli/command.h"
#include "image/image_io.h"
#include "renderers/renderers.h"

namespace penumbra {

namespace fs = std::filesystem;

namespace {

struct ExportArgs {
  std::string to;
  std::string scene;
  std::string output;
  SceneArgs scene_args;
};

// The renderers that have something to export, for `export --to`.
std::vector<std::string> exporter_ids() {
  std::vector<std::string> ids;
  for (RendererKind r : all_renderers())
    if (renderer(r).export_files) ids.push_back(to_string(r));
  return ids;
}

int export_scene(const ExportArgs& a, std::ostream& out) {
  const Scene scene = read_scene(a.scene, a.scene_args).scene;
  // --to is one of exporter_ids(); refused before a folder is made.
  out << export_scene_files(renderer_from_id(a.to).value(), scene, a.output);
  return kExitOk;
}

}  // namespace

std::string export_scene_files(RendererKind r, const Scene& scene, const std::string& output) {
  if (!renderer(r).export_files)
    throw UsageError(fmt::format("{} has nothing to export (exporters: {})", to_string(r),
                                 fmt::join(exporter_ids(), ", ")));
  check_offered(r, scene);
  std::error_code ec;
  fs::create_directories(output, ec);
  if (ec || !fs::is_directory(output))
    throw OutputError(fmt::format("{}: cannot create the output folder: {}", output,
                                  ec ? ec.message() : "not a folder"));
  // A folder that takes no files fails here, before the mesh is built.
  check_writable((fs::path(output) / renderer(r).export_file).string());
  return renderer(r).export_files(scene, output);
}

Command add_export_command(CLI::App& app, SharedOptions&) {
  auto a = std::make_shared<ExportArgs>();
  CLI::App* cmd =
      app.add_subcommand("export", "write a scene for POV-Ray (.pov) or Blender (job + mesh)");
  const std::vector<std::string> ids = exporter_ids();
  cmd->add_option("--to", a->to, fmt::format("{}", fmt::join(ids, " or ")))
      ->required()
      ->check(CLI::IsMember(ids));
  cmd->add_option("scene", a->scene,
                  "scene JSON file, or a mesh file (OBJ, PLY, glTF, ...) framed by a default "
                  "scene")
      ->required();
  cmd->add_option("-o,--output", a->output, "output folder")->required();
  add_scene_options(cmd, a->scene_args);
  return {cmd, [a](const CommandContext& c) { return export_scene(*a, c.out); }};
}

}  // namespace penumbra
