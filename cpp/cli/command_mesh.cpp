// `penumbra mesh`: the triangles a scene stands for, as an OBJ or PLY file:
// a tessellation, a mesh shape, or the displaced ground truth, exactly as
// Blender is given them (external::scene_triangles), for another renderer
// or as a mesh scene of its own (scenes/meshes/sphere-uv64.obj is one).
#include <cctype>
#include <filesystem>

#include <fmt/format.h>

#include "cli/command.h"
#include "image/image_io.h"
#include "renderers/external/external.h"
#include "scene/mesh_file.h"

namespace penumbra {

namespace fs = std::filesystem;

namespace {

struct MeshArgs {
  std::string scene, output;
  SceneArgs scene_args;
};

// What the triangles are, for the summary line and the file's comment.
std::string what_the_triangles_are(const Scene& scene, bool truth) {
  if (truth)
    return fmt::format("the displaced ground truth at edge length {:.6g} scene units",
                       scene.displacement.edge_length);
  if (scene.shape.type == ShapeType::kMesh) return "the mesh file's triangles";
  if (scene.tessellation)
    return fmt::format("the tessellation's triangles ({} segments around)",
                       scene.tessellation->segments);
  if (scene.shape.type == ShapeType::kPlane) return "the plane as two triangles";
  return "the analytic shape as a fine grid (chords within 2e-5 of the radius)";
}

int write_scene_mesh(const MeshArgs& a, std::ostream& out) {
  const LoadedScene loaded = read_scene(a.scene, a.scene_args);
  const Scene& scene = loaded.scene;
  std::string extension = fs::path(a.output).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (extension != ".obj" && extension != ".ply")
    throw UsageError(fmt::format("-o {}: expected a file name ending in .obj or .ply (got \"{}\")",
                                 a.output, extension));
  check_writable(a.output);
  const bool truth = scene.representation == Representation::kDisplacement;
  const TriangleMesh mesh = external::scene_triangles(scene, truth);
  const std::string what = what_the_triangles_are(scene, truth);
  write_mesh_file(mesh, a.output,
                  fmt::format("penumbra mesh {}: {}, scene units", loaded.origin, what));
  out << fmt::format("wrote {} ({} triangles, {} vertices with normals): {}\n", a.output,
                     mesh.triangle_count(), mesh.vertex_count(), what);
  return kExitOk;
}

}  // namespace

Command add_mesh_command(CLI::App& app, SharedOptions&) {
  auto a = std::make_shared<MeshArgs>();
  CLI::App* cmd = app.add_subcommand(
      "mesh",
      "write the triangles a scene stands for (its tessellation, mesh shape, or with "
      "--representation displacement its displaced ground truth) as OBJ or PLY");
  cmd->add_option("scene", a->scene,
                  "scene JSON file, or a mesh file (OBJ, PLY, glTF, ...) framed by a default "
                  "scene")
      ->required();
  cmd->add_option("-o,--output", a->output,
                  "mesh file: .obj (text, 9 significant digits) or .ply (binary, the floats' bits)")
      ->required();
  add_scene_options(cmd, a->scene_args);
  return {cmd, [a](const CommandContext& c) { return write_scene_mesh(*a, c.out); }};
}

}  // namespace penumbra
