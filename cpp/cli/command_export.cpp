// `penumbra export`: a scene as POV-Ray SDL or a Blender job (export/export.h).
#include <filesystem>

#include <fmt/format.h>

#include "cli/command.h"
#include "export/export.h"
#include "image/image_io.h"
#include "renderers/renderers.h"
#include "util/data_files.h"

namespace penumbra {

namespace fs = std::filesystem;

namespace {

struct ExportArgs {
  std::string to;
  std::string scene;
  std::string output;
  SceneArgs scene_args;
};

// The external renderers' ids, for `export --to`.
std::vector<std::string> external_renderer_ids() {
  std::vector<std::string> ids;
  for (const RendererInfo& info : renderer_table())
    if (info.kind != RendererKind::kEvaluator) ids.push_back(info.id);
  return ids;
}

int write_povray_job(const Scene& scene, const std::string& folder, std::ostream& out) {
  const PovrayExport job = export_povray(scene);
  const std::string path = (fs::path(folder) / "scene.pov").string();
  write_povray_files(job, folder);
  out << fmt::format(
      "wrote {}{} (render {}x{} without anti-aliasing, box-filter {}x{} down to "
      "{}x{}; the command line is in its first lines)\n",
      path, job.map.pixels.empty() ? "" : std::string(" and its ") + kPovrayMapFile,
      job.width * job.supersample_x, job.height * job.supersample_y, job.supersample_x,
      job.supersample_y, job.width, job.height);
  return kExitOk;
}

int write_blender_job(const Scene& scene, const std::string& folder, std::ostream& out) {
  const BlenderExport job = export_blender(scene);
  const fs::path dir(folder);
  const TriangleMesh& m = job.mesh;
  write_blender_files(job, dir.string());
  out << fmt::format(
      "wrote {} and its mesh ({} vertices, {} triangles); render with\n  blender -b -t 1 "
      "--factory-startup -noaudio --python-exit-code 1 --python {} -- "
      "{} out.exr\n",
      (dir / kBlenderJobFile).string(), m.vertex_count(), m.triangle_count(),
      data_file("harness/blender_render.py"), (dir / kBlenderJobFile).string());
  return kExitOk;
}

int export_scene(const ExportArgs& a, std::ostream& out) {
  const Scene scene = read_scene(a.scene, a.scene_args).scene;
  const std::optional<RendererKind> renderer = renderer_from_id(a.to);
  if (renderer) check_offered(*renderer, scene);  // before a folder is made
  std::error_code ec;
  fs::create_directories(a.output, ec);
  if (ec || !fs::is_directory(a.output))
    throw OutputError(fmt::format("{}: cannot create the output folder: {}", a.output,
                                  ec ? ec.message() : "not a folder"));
  const bool povray = a.to == to_string(RendererKind::kPovray);
  // A folder that takes no files fails here, before the mesh is built.
  check_writable(
      (fs::path(a.output) / (povray ? std::string("scene.pov") : std::string(kBlenderJobFile)))
          .string());
  return povray ? write_povray_job(scene, a.output, out) : write_blender_job(scene, a.output, out);
}

}  // namespace

Command add_export_command(CLI::App& app, SharedOptions&) {
  auto a = std::make_shared<ExportArgs>();
  CLI::App* cmd =
      app.add_subcommand("export", "write a scene for POV-Ray (.pov) or Blender (job + mesh)");
  cmd->add_option("--to", a->to, "povray or blender")
      ->required()
      ->check(CLI::IsMember(external_renderer_ids()));
  cmd->add_option("scene", a->scene, "scene JSON file")->required();
  cmd->add_option("-o,--output", a->output, "output folder")->required();
  add_scene_options(cmd, a->scene_args);
  return {cmd, [a](const CommandContext& c) { return export_scene(*a, c.out); }};
}

}  // namespace penumbra
