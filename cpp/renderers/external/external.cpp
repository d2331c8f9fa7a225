#include "renderers/external/external.h"

#include <stdlib.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <thread>

#include <fmt/format.h>

#include "core/mesh_surface.h"
#include "core/surface_map.h"
#include "core/tessellation.h"
#include "image/image_io.h"
#include "renderers/renderers.h"
#include "util/files.h"
#include "util/process.h"
#include "util/strict_json.h"

namespace penumbra::external {

namespace fs = std::filesystem;

int thread_count(const RenderSettings& s) {
  return s.threads > 0 ? s.threads : std::max(1u, std::thread::hardware_concurrency());
}

std::string executable_for(const RendererInfo& info, const RenderSettings& s) {
  std::string name = s.executable;
  const char* env = std::getenv(info.executable_variable);
  if (name.empty() && env) name = env;
  if (name.empty()) name = info.executable;
  const std::optional<std::string> found = find_executable(name);
  if (!found)
    throw RendererError(fmt::format(
        "{}: `{}` not found (install the Debian package `{}`: apt-get install {}; or set {})",
        info.id, name, info.debian_package, info.debian_package, info.executable_variable));
  return *found;
}

std::string probe_version(const RendererInfo& info, const RenderSettings& settings) {
  const std::string exe = executable_for(info, settings);
  char pattern[] = "/tmp/penumbra-version-XXXXXX";
  const int fd = ::mkstemp(pattern);
  if (fd < 0) throw RendererError("cannot create a temporary file");
  ::close(fd);
  // The probe obeys the render timeout too (a hanging --version must not
  // hold a study longer than a hanging render would).
  const ProcessResult p =
      run_process({exe, "--version"}, "/tmp", pattern, std::min(60.0, settings.timeout_s));
  std::string line;
  {
    std::ifstream in(pattern);
    std::string l;
    while (std::getline(in, l))
      if (l.find(info.version_marker) != std::string::npos) {
        line = l;
        break;
      }
  }
  ::unlink(pattern);
  if (p.cancelled) throw RenderCancelled("interrupted");
  if (!p.ok() || line.empty())
    throw RendererError(fmt::format(
        "{}: `{} --version` {}", info.id, exe,
        p.timed_out ? fmt::format("timed out after {:.0f} s", std::min(60.0, settings.timeout_s))
                    : std::string("failed")));
  return line;
}

WorkDir::WorkDir(const std::string& log_path, const RendererInfo& info) {
  fs::path dir = fs::path(log_path).parent_path();
  if (dir.empty()) dir = ".";
  // Named after host and process, so a later run can remove it if this
  // process is killed (remove_stale_temporaries).
  std::string pattern = (dir / work_folder_pattern(info.id)).string();
  if (!::mkdtemp(pattern.data()))
    throw RendererError(fmt::format("cannot create a work folder in {}", dir.string()));
  path = fs::absolute(pattern);
}

WorkDir::~WorkDir() {
  std::error_code ec;
  if (!keep) fs::remove_all(path, ec);
}

Image read_renderer_image(const RendererInfo& info, const std::string& path) {
  try {
    return read_image(path);
  } catch (const std::exception& e) {
    throw RendererError(fmt::format("{} wrote an image that cannot be read: {}", info.id,
                                    printable(e.what(), 300)));
  }
}

namespace {

void check_process(const RendererInfo& info, const ProcessResult& p, const RenderSettings& s,
                   WorkDir& work) {
  if (p.ok()) return;
  if (p.cancelled) {
    work.keep = false;  // nothing to rerun by hand: the user stopped it
    throw RenderCancelled(fmt::format("{} was stopped (interrupted)", info.id));
  }
  std::string what;
  if (p.timed_out)
    what =
        fmt::format("timed out after {:.0f} s (the limit; raise it with --timeout)", s.timeout_s);
  else if (p.signal != 0)
    what = fmt::format("was killed by signal {}", p.signal);
  else if (p.exit_code == 127)
    what = "could not be executed (exit 127)";
  else
    what = fmt::format("exited with status {}", p.exit_code);
  throw RendererError(fmt::format("{} {}; log {} (work files kept in {}), last lines:\n{}", info.id,
                                  what, s.log_path, work.path.string(),
                                  tail_lines(s.log_path, 12)));
}

// Alpha and colour from the renderer, analysis channels from the evaluator.
// Renderers store colour premultiplied over a black background.
Image merge_with_geometry(const Image& colour, const Image& geometry, const RendererInfo& info) {
  try {
    return with_channels_from(geometry, colour, rgba_channels());
  } catch (const ImageMismatch& e) {
    throw RendererError(fmt::format("{} output: {}", info.id, e.what()));
  }
}

}  // namespace

ExternalRun run_external(const RendererInfo& info, const std::vector<std::string>& argv,
                         WorkDir& work, const std::string& output, const RenderSettings& settings) {
  const ProcessResult p =
      run_process(argv, work.path.string(), settings.log_path, settings.timeout_s);
  check_process(info, p, settings, work);
  if (!fs::exists(work.path / output))
    throw RendererError(fmt::format("{} exited 0 but wrote no image; log {}:\n{}", info.id,
                                    settings.log_path, tail_lines(settings.log_path, 12)));
  return {read_renderer_image(info, (work.path / output).string()), p.seconds};
}

RendererRun with_geometry(const RendererInfo& info, const Image& colour, double seconds,
                          const Scene& scene, const RenderSettings& settings, WorkDir& work) {
  RendererRun run = render_evaluator(scene, settings);
  run.geometry_seconds = run.seconds;
  run.seconds = seconds;
  run.image = merge_with_geometry(colour, run.image, info);
  work.keep = false;
  return run;
}

TriangleMesh mesh_shape_triangles(const Scene& scene, bool truth) {
  const MeshSurface& base = *scene.shape.mesh;
  if (!truth) return base.mesh;
  return displaced_mesh_for_export(
      base, plan_subdivision(base.mesh, scene.displacement.edge_length),
      {scene.height.function, scene.height.height_map()}, scene.height.amplitude);
}

TriangleMesh scene_triangles(const Scene& scene, bool displaced) {
  // A mesh shape's truth is its subdivision whatever the height, as the
  // evaluator's is: with no height it shows the mesh's facets.
  if (scene.shape.type == ShapeType::kMesh)
    return external::mesh_shape_triangles(scene,
                                          scene.representation == Representation::kDisplacement);
  const HeightFunction& hf = scene.height.function;
  const double amplitude = scene.height.amplitude;
  const SurfaceMap* height_map = scene.height.height_map();
  const double reach =
      displaced ? amplitude * height_bounds(hf, height_map, scene.shape).max_abs : 0.0;
  // The ground truth needs the fine grid; the base surface of smooth and bump
  // renders does not: 512 segments around keep the chord within
  // (2 pi / 512)^2 / 8 = 1.9e-5 R of the circle (0.001 px at 128 px), and a
  // cylinder's side is straight along its axis. A sphere then loads 262k
  // triangles instead of 1M: a 128 px, 32 spp sphere bump job falls from
  // 13.3 s to 4.6 s (mean over the default study's 36).
  GridResolution res = grid_resolution(scene.shape, scene.displacement.edge_length, reach);
  if (!displaced)
    res = scene.shape.type == ShapeType::kPlane
              ? GridResolution{1, 1}
              : GridResolution{512, scene.shape.type == ShapeType::kCylinder ? 1u : 256u};
  // A tessellated shape is sent as the evaluator's own triangles (its normals
  // are the exact ones at the vertices), through the same coordinate change.
  return scene.tessellation
             ? tessellate(scene.shape, *scene.tessellation)
             : make_grid_mesh(scene.shape, hf, displaced ? amplitude : 0.0, res, height_map);
}

}  // namespace penumbra::external
