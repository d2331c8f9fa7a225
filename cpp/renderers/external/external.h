// What the drivers of the external renderers (renderers/external/<id>/)
// share: finding the executable, a work folder, running the process, reading
// its image and putting it on the evaluator's analysis channels, and the
// version probe. Each driver is a file of its own so that it enters only its
// renderer's part of the cache key (CMakeLists.txt, code_digest.h): a change
// to how Blender is run does not make the evaluator's cached renders stale.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/grid_mesh.h"
#include "renderers/renderer.h"

namespace penumbra::external {

// Worker threads of one render: settings.threads, or all cores.
int thread_count(const RenderSettings& s);

// The renderer's executable (settings, then its environment variable, then
// its default name on PATH); RendererError naming the Debian package if none.
std::string executable_for(const RendererInfo& info, const RenderSettings& s);

// The first line of `EXECUTABLE --version` with the row's version marker
// (RendererEntry::version of every external renderer). The probe is killed
// after min(60 s, settings.timeout_s).
std::string probe_version(const RendererInfo& info, const RenderSettings& settings);

// A fresh folder beside the log; removed on success, kept on failure so the
// user can rerun the exact command by hand.
struct WorkDir {
  std::filesystem::path path;
  bool keep = true;
  WorkDir(const std::string& log_path, const RendererInfo& info);
  ~WorkDir();
  WorkDir(const WorkDir&) = delete;
  WorkDir& operator=(const WorkDir&) = delete;
};

// A renderer's output file; unreadable or garbage is the renderer's failure.
Image read_renderer_image(const RendererInfo& info, const std::string& path);

// Runs an external renderer in `work` and reads the image it leaves there
// (`output`); RendererError when it fails or writes nothing readable.
struct ExternalRun {
  Image image;
  double seconds = 0.0;
};
ExternalRun run_external(const RendererInfo& info, const std::vector<std::string>& argv,
                         WorkDir& work, const std::string& output, const RenderSettings& settings);

// The renderer's colour on the evaluator's analysis channels of the same
// camera; marks `work` for removal.
RendererRun with_geometry(const RendererInfo& info, const Image& colour, double seconds,
                          const Scene& scene, const RenderSettings& settings, WorkDir& work);

// A mesh shape's triangles as an external renderer is given them, in scene
// coordinates: its own vertices and normals, or (`truth`) its displaced
// truth at the scene's edge length, split as the evaluator splits it and
// shaded with the truth's exact normals (displaced_mesh_for_export,
// core/mesh_surface.h).
TriangleMesh mesh_shape_triangles(const Scene& scene, bool truth);

// The triangles Blender is given for a scene, in scene coordinates (and
// what `penumbra mesh` writes): a mesh shape's (mesh_shape_triangles), a
// tessellation's own, or the analytic shape as a grid, displaced by the
// height (`displaced`) at the scene's edge length or, undisplaced, fine
// enough that its chords stay within 2e-5 of the radius.
TriangleMesh scene_triangles(const Scene& scene, bool displaced);

}  // namespace penumbra::external
