#include "renderers/renderers.h"

#include <stdlib.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <thread>

#include <fmt/format.h>

#include "export/export.h"
#include "render/image_io.h"
#include "renderers/process.h"

namespace penumbra {
namespace fs = std::filesystem;

const char* to_string(RendererKind r) {
  switch (r) {
    case RendererKind::kEvaluator:
      return "evaluator";
    case RendererKind::kPovray:
      return "povray";
    case RendererKind::kBlender:
      return "blender";
  }
  return "?";
}

std::optional<RendererKind> renderer_from_id(const std::string& id) {
  for (RendererKind r : all_renderers())
    if (id == to_string(r)) return r;
  return std::nullopt;
}

const std::vector<RendererKind>& all_renderers() {
  static const std::vector<RendererKind> all{RendererKind::kEvaluator, RendererKind::kPovray,
                                             RendererKind::kBlender};
  return all;
}

const char* debian_package(RendererKind r) {
  switch (r) {
    case RendererKind::kPovray:
      return "povray";
    case RendererKind::kBlender:
      return "blender";
    case RendererKind::kEvaluator:
      break;
  }
  return "";
}

Image box_downsample(const Image& image, int nx, int ny) {
  if (nx == 1 && ny == 1) return image;
  Image out;
  out.width = image.width / nx;
  out.height = image.height / ny;
  out.channels = image.channels;
  const std::size_t nc = image.channels.size();
  out.pixels.assign(std::size_t(out.width) * out.height * nc, 0.0f);
  const double weight = 1.0 / (nx * ny);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      for (std::size_t c = 0; c < nc; ++c) {
        double sum = 0.0;  // fixed order: the same bits every time
        for (int sy = 0; sy < ny; ++sy)
          for (int sx = 0; sx < nx; ++sx)
            sum += image.at(x * nx + sx, y * ny + sy, static_cast<int>(c));
        out.pixels[(std::size_t(y) * out.width + x) * nc + c] = static_cast<float>(sum * weight);
      }
  return out;
}

namespace {

int thread_count(const RenderSettings& s) {
  return s.threads > 0 ? s.threads : std::max(1u, std::thread::hardware_concurrency());
}

std::string executable_for(RendererKind r, const RenderSettings& s) {
  std::string name = s.executable;
  const char* env = r == RendererKind::kPovray ? "PENUMBRA_POVRAY" : "PENUMBRA_BLENDER";
  if (name.empty() && std::getenv(env)) name = std::getenv(env);
  if (name.empty()) name = debian_package(r);
  const std::optional<std::string> found = find_executable(name);
  if (!found)
    throw RendererError(fmt::format(
        "{}: `{}` not found (install the Debian package `{}`: apt-get install {}; or set {})",
        to_string(r), name, debian_package(r), debian_package(r), env));
  return *found;
}

std::string blender_script(const RenderSettings& s) {
  std::string script = s.blender_script;
  if (script.empty() && std::getenv("PENUMBRA_BLENDER_SCRIPT"))
    script = std::getenv("PENUMBRA_BLENDER_SCRIPT");
  if (script.empty()) script = std::string(PENUMBRA_SOURCE_DIR) + "/harness/blender_render.py";
  if (!fs::is_regular_file(script))
    throw RendererError(fmt::format("blender: the harness script {} is missing", script));
  return fs::absolute(script).string();
}

// A fresh folder beside the log; removed on success, kept on failure so the
// user can rerun the exact command by hand.
struct WorkDir {
  fs::path path;
  bool keep = true;
  explicit WorkDir(const std::string& log_path, RendererKind r) {
    fs::path dir = fs::path(log_path).parent_path();
    if (dir.empty()) dir = ".";
    std::string pattern = (dir / fmt::format(".penumbra-{}-XXXXXX", to_string(r))).string();
    if (!::mkdtemp(pattern.data()))
      throw RendererError(fmt::format("cannot create a work folder in {}", dir.string()));
    path = fs::absolute(pattern);
  }
  ~WorkDir() {
    std::error_code ec;
    if (!keep) fs::remove_all(path, ec);
  }
};

void write_file(const fs::path& path, const void* data, std::size_t bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(static_cast<const char*>(data), static_cast<std::streamsize>(bytes));
  if (!out) throw RendererError(fmt::format("cannot write {}", path.string()));
}

void check_process(RendererKind r, const ProcessResult& p, const RenderSettings& s,
                   const fs::path& work) {
  if (p.ok()) return;
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
  throw RendererError(fmt::format("{} {}; log {} (work files kept in {}), last lines:\n{}",
                                  to_string(r), what, s.log_path, work.string(),
                                  tail_lines(s.log_path, 12)));
}

// Alpha and colour from the renderer, analysis channels from the evaluator.
Image merge_with_geometry(const Image& colour, const Image& geometry, RendererKind r) {
  if (colour.width != geometry.width || colour.height != geometry.height)
    throw RendererError(fmt::format("{} wrote a {}x{} image, expected {}x{}", to_string(r),
                                    colour.width, colour.height, geometry.width, geometry.height));
  int source[4];
  const char* names[4] = {"R", "G", "B", "A"};
  for (int c = 0; c < 4; ++c) {
    source[c] = colour.channel_index(names[c]);
    if (source[c] < 0)
      throw RendererError(fmt::format("{} output has no {} channel", to_string(r), names[c]));
  }
  Image out = geometry;
  const std::size_t nc = out.channels.size();
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      for (int c = 0; c < 4; ++c) {
        const float v = colour.at(x, y, source[c]);
        // Renderers store colour premultiplied and may leave junk where alpha
        // is 0; black background by definition.
        out.pixels[(std::size_t(y) * out.width + x) * nc + c] = v;
      }
  return out;
}

RendererRun geometry_pass(const Scene& scene, const RenderSettings& settings) {
  RendererRun run;
  run.image = render(scene, settings.progress, &run.stats);
  run.seconds = run.stats.seconds;
  return run;
}

RendererRun render_povray(const Scene& scene, const RenderSettings& settings) {
  const PovrayExport job = export_povray(scene);
  const std::string exe = executable_for(RendererKind::kPovray, settings);
  WorkDir work(settings.log_path, RendererKind::kPovray);
  write_file(work.path / "scene.pov", job.sdl.data(), job.sdl.size());
  std::vector<std::string> argv{exe};
  for (std::string& a : job.arguments("scene.pov", "scene.exr", thread_count(settings)))
    argv.push_back(std::move(a));
  const ProcessResult p =
      run_process(argv, work.path.string(), settings.log_path, settings.timeout_s);
  check_process(RendererKind::kPovray, p, settings, work.path);
  if (!fs::exists(work.path / "scene.exr"))
    throw RendererError(fmt::format("povray exited 0 but wrote no image; log {}:\n{}",
                                    settings.log_path, tail_lines(settings.log_path, 12)));
  const Image big = read_image((work.path / "scene.exr").string());
  if (big.width != job.width * job.supersample_x || big.height != job.height * job.supersample_y)
    throw RendererError(fmt::format("povray wrote {}x{}, expected {}x{}", big.width, big.height,
                                    job.width * job.supersample_x, job.height * job.supersample_y));
  const Image colour = box_downsample(big, job.supersample_x, job.supersample_y);
  RendererRun run = geometry_pass(scene, settings);
  run.geometry_seconds = run.seconds;
  run.seconds = p.seconds;
  run.image = merge_with_geometry(colour, run.image, RendererKind::kPovray);
  work.keep = false;
  return run;
}

RendererRun render_blender(const Scene& scene, const RenderSettings& settings) {
  const BlenderExport job = export_blender(scene);
  const std::string exe = executable_for(RendererKind::kBlender, settings);
  const std::string script = blender_script(settings);
  WorkDir work(settings.log_path, RendererKind::kBlender);
  write_file(work.path / kBlenderJobFile, job.job_json.data(), job.job_json.size());
  const TriangleMesh& m = job.mesh;
  write_file(work.path / kBlenderPositionsFile, m.positions.data(), m.positions.size() * 4);
  write_file(work.path / kBlenderNormalsFile, m.normals.data(), m.normals.size() * 4);
  write_file(work.path / kBlenderTrianglesFile, m.triangles.data(), m.triangles.size() * 4);
  const std::vector<std::string> argv{exe,
                                      "-b",
                                      "--factory-startup",
                                      "-noaudio",
                                      "--python-exit-code",
                                      "1",
                                      "--python",
                                      script,
                                      "--",
                                      kBlenderJobFile,
                                      "render.exr",
                                      "--threads",
                                      std::to_string(thread_count(settings))};
  const ProcessResult p =
      run_process(argv, work.path.string(), settings.log_path, settings.timeout_s);
  check_process(RendererKind::kBlender, p, settings, work.path);
  if (!fs::exists(work.path / "render.exr"))
    throw RendererError(fmt::format("blender exited 0 but wrote no image; log {}:\n{}",
                                    settings.log_path, tail_lines(settings.log_path, 12)));
  const Image colour = read_image((work.path / "render.exr").string());
  RendererRun run = geometry_pass(scene, settings);
  run.geometry_seconds = run.seconds;
  run.seconds = p.seconds;
  run.image = merge_with_geometry(colour, run.image, RendererKind::kBlender);
  work.keep = false;
  return run;
}

}  // namespace

RendererRun render_with(RendererKind renderer, const Scene& scene, const RenderSettings& settings) {
  switch (renderer) {
    case RendererKind::kEvaluator:
      return geometry_pass(scene, settings);
    case RendererKind::kPovray:
      return render_povray(scene, settings);
    case RendererKind::kBlender:
      return render_blender(scene, settings);
  }
  throw std::logic_error("unknown renderer");
}

std::string renderer_version(RendererKind renderer, const RenderSettings& settings) {
  if (renderer == RendererKind::kEvaluator) return std::string("penumbra ") + kPenumbraVersion;
  const std::string exe = executable_for(renderer, settings);
  char pattern[] = "/tmp/penumbra-version-XXXXXX";
  const int fd = ::mkstemp(pattern);
  if (fd < 0) throw RendererError("cannot create a temporary file");
  ::close(fd);
  const ProcessResult p = run_process({exe, "--version"}, "/tmp", pattern, 60.0);
  std::string line;
  {
    std::ifstream in(pattern);
    std::string l;
    while (std::getline(in, l))
      if (l.find("POV-Ray 3") != std::string::npos || l.rfind("Blender ", 0) == 0) {
        line = l;
        break;
      }
  }
  ::unlink(pattern);
  if (!p.ok() || line.empty())
    throw RendererError(fmt::format("{}: `{} --version` failed", to_string(renderer), exe));
  return line;
}

}  // namespace penumbra
