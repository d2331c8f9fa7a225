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
#include "image/image_io.h"
#include "renderers/code_digest.h"
#include "renderers/external.h"
#include "util/files.h"
#include "util/hash.h"
#include "util/process.h"
#include "util/strict_json.h"

namespace penumbra {
namespace fs = std::filesystem;
using namespace external;

namespace external {

int thread_count(const RenderSettings& s) {
  return s.threads > 0 ? s.threads : std::max(1u, std::thread::hardware_concurrency());
}

std::string executable_for(RendererKind r, const RenderSettings& s) {
  const RendererInfo& info = renderer_info(r);
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

WorkDir::WorkDir(const std::string& log_path, RendererKind r) {
  fs::path dir = fs::path(log_path).parent_path();
  if (dir.empty()) dir = ".";
  // Named after host and process, so a later run can remove it if this
  // process is killed (remove_stale_temporaries).
  std::string pattern = (dir / work_folder_pattern(to_string(r))).string();
  if (!::mkdtemp(pattern.data()))
    throw RendererError(fmt::format("cannot create a work folder in {}", dir.string()));
  path = fs::absolute(pattern);
}

WorkDir::~WorkDir() {
  std::error_code ec;
  if (!keep) fs::remove_all(path, ec);
}

// A renderer's output file; unreadable or garbage is the renderer's failure.
Image read_renderer_image(RendererKind r, const std::string& path) {
  try {
    return read_image(path);
  } catch (const std::exception& e) {
    throw RendererError(fmt::format("{} wrote an image that cannot be read: {}", to_string(r),
                                    printable(e.what(), 300)));
  }
}

}  // namespace external

namespace {

void check_process(RendererKind r, const ProcessResult& p, const RenderSettings& s, WorkDir& work) {
  if (p.ok()) return;
  if (p.cancelled) {
    work.keep = false;  // nothing to rerun by hand: the user stopped it
    throw RenderCancelled(fmt::format("{} was stopped (interrupted)", to_string(r)));
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
  throw RendererError(fmt::format("{} {}; log {} (work files kept in {}), last lines:\n{}",
                                  to_string(r), what, s.log_path, work.path.string(),
                                  tail_lines(s.log_path, 12)));
}

// What every renderer must return before it is used or cached: the scene's
// size, R G B A, and finite values in every channel.
void check_output(RendererKind r, const Image& image, const Scene& scene) {
  if (image.width != scene.camera.width || image.height != scene.camera.height)
    throw RendererError(fmt::format("{} returned a {}x{} image, expected {}x{}", to_string(r),
                                    image.width, image.height, scene.camera.width,
                                    scene.camera.height));
  for (const char* name : {"R", "G", "B", "A"})
    if (image.channel_index(name) < 0)
      throw RendererError(fmt::format("{} returned no {} channel", to_string(r), name));
  const std::size_t bad = count_nonfinite(image);
  if (bad > 0)
    throw RendererError(
        fmt::format("{} returned {} NaN or Inf values (of {}); the image is not used or cached",
                    to_string(r), bad, image.pixels.size()));
}

// Alpha and colour from the renderer, analysis channels from the evaluator.
// Renderers store colour premultiplied over a black background.
Image merge_with_geometry(const Image& colour, const Image& geometry, RendererKind r) {
  try {
    return with_channels_from(geometry, colour, rgba_channels());
  } catch (const ImageMismatch& e) {
    throw RendererError(fmt::format("{} output: {}", to_string(r), e.what()));
  }
}

RendererRun geometry_pass(const Scene& scene, const RenderSettings& settings) {
  RendererRun run;
  run.image = render(scene, settings.progress, &run.stats);
  run.seconds = run.stats.seconds;
  return run;
}

}  // namespace

namespace external {

ExternalRun run_external(RendererKind r, const std::vector<std::string>& argv, WorkDir& work,
                         const std::string& output, const RenderSettings& settings) {
  const ProcessResult p =
      run_process(argv, work.path.string(), settings.log_path, settings.timeout_s);
  check_process(r, p, settings, work);
  if (!fs::exists(work.path / output))
    throw RendererError(fmt::format("{} exited 0 but wrote no image; log {}:\n{}", to_string(r),
                                    settings.log_path, tail_lines(settings.log_path, 12)));
  return {read_renderer_image(r, (work.path / output).string()), p.seconds};
}

// The renderer's colour on the evaluator's analysis channels of the same camera.
RendererRun with_geometry(RendererKind r, const Image& colour, double seconds, const Scene& scene,
                          const RenderSettings& settings, WorkDir& work) {
  RendererRun run = geometry_pass(scene, settings);
  run.geometry_seconds = run.seconds;
  run.seconds = seconds;
  run.image = merge_with_geometry(colour, run.image, r);
  work.keep = false;
  return run;
}

}  // namespace external

namespace {

RendererRun render_dispatch(RendererKind renderer, const Scene& scene,
                            const RenderSettings& settings) {
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

}  // namespace

RendererRun render_with(RendererKind renderer, const Scene& scene, const RenderSettings& settings) {
  if (processes_cancelled()) throw RenderCancelled("not started (interrupted)");
  RendererRun run = render_dispatch(renderer, scene, settings);
  check_output(renderer, run.image, scene);
  return run;
}

MethodsRun render_evaluator_methods(const Scene& scene,
                                    const std::vector<TerminatorSettings>& methods,
                                    const RenderSettings& settings) {
  if (processes_cancelled()) throw RenderCancelled("not started (interrupted)");
  MethodsRun run;
  RenderStats stats;
  run.images = render_methods(scene, methods, settings.progress, &stats);
  run.seconds = stats.seconds;
  run.errors.resize(run.images.size());
  for (std::size_t k = 0; k < run.images.size(); ++k) {
    try {
      check_output(RendererKind::kEvaluator, run.images[k], scene);
    } catch (const RendererError& e) {
      run.errors[k] = e.what();
    }
  }
  return run;
}

namespace {

// Bytes per pixel of an evaluator image (7 float channels) held while it is
// rendered, written as EXR and previewed: image, OpenImageIO's write buffer,
// the preview's copies.
constexpr double kBytesPerPixel = 7 * 4 * 4;
// Bytes per triangle of a mesh with its Embree BVH (measured: about 100).
constexpr double kBytesPerTriangle = 120.0;

std::string gib(double bytes) {
  return fmt::format("{:.2f} GiB", bytes / kGiB);
}

}  // namespace

ResourceEstimate estimate_resources(RendererKind renderer, const Scene& scene) {
  ResourceEstimate e;
  const double pixels = double(scene.camera.width) * double(scene.camera.height);
  double image_bytes = pixels * kBytesPerPixel;
  if (renderer == RendererKind::kPovray) {
    // The supersampled RGBA image POV-Ray writes and Penumbra reads back (the
    // export's strata, without building its SDL: a displaced grid is large).
    int sx = 1, sy = 1;
    strata(scene.camera.spp, &sx, &sy);
    image_bytes += pixels * sx * sy * 4 * 4 * 2;
  }
  double triangles = 0.0;
  std::string mesh_pointer;
  if (scene.tessellation) {
    triangles = double(tessellated_triangle_count(scene.shape, *scene.tessellation));
    mesh_pointer = "/shape/tessellation";
  } else if (scene.representation == Representation::kDisplacement ||
             renderer == RendererKind::kBlender) {
    const double reach =
        scene.height.amplitude *
        height_bounds(scene.height.function, scene.height.height_map(), scene.shape).max_abs;
    const GridResolution r = grid_resolution(scene.shape, scene.displacement.edge_length, reach);
    triangles = 2.0 * double(r.nu) * double(r.nv);
    mesh_pointer = "/displacement/edge_length";
  }
  const double mesh_bytes = triangles * kBytesPerTriangle;
  e.memory_bytes = image_bytes + mesh_bytes;
  e.triangles = triangles;
  // Every channel a cache entry can hold (the evaluator's 8 floats), plus a
  // header with the scene JSON and attributes: about 2 KiB measured on the
  // shipped scenes; 16 KiB leaves room for long scene files.
  e.output_bytes = pixels * double(evaluator_channels().size()) * 4 + 16384.0;
  e.pointer = mesh_bytes > image_bytes ? mesh_pointer : std::string("/camera/width");
  e.detail = fmt::format("{}x{} px: {}", scene.camera.width, scene.camera.height, gib(image_bytes));
  if (triangles > 0)
    e.detail += fmt::format(", {:.2f} M triangles: {}", triangles / 1e6, gib(mesh_bytes));
  return e;
}

void check_resources(const ResourceEstimate& estimate, double max_memory_bytes,
                     const std::string& origin, const std::string& output_folder) {
  if (estimate.memory_bytes > max_memory_bytes)
    throw InputError(
        origin, estimate.pointer,
        fmt::format("expected a render within --max-memory {:.3g} GiB, this one "
                    "needs about {} ({}); lower the resolution or raise the limit",
                    max_memory_bytes / kGiB, gib(estimate.memory_bytes), estimate.detail));
  if (output_folder.empty()) return;
  std::error_code ec;
  const fs::space_info space = fs::space(output_folder, ec);
  if (!ec && double(space.available) < estimate.output_bytes)
    throw OutputError(fmt::format("{}: {} free, the output may take up to {}", output_folder,
                                  gib(double(space.available)), gib(estimate.output_bytes)));
}

std::string pixel_code_digest(RendererKind renderer, const RenderSettings& settings) {
  const CodeDigests& d = build_code_digests();
  switch (renderer) {
    case RendererKind::kEvaluator:
      return d.evaluator;
    case RendererKind::kPovray:
      return fmt::format("{}-{}", d.evaluator, d.povray);
    case RendererKind::kBlender: {
      const std::string script = blender_script(settings);
      std::ifstream in(script, std::ios::binary);
      const std::string text((std::istreambuf_iterator<char>(in)),
                             std::istreambuf_iterator<char>());
      if (!in && !in.eof()) throw RendererError(fmt::format("blender: cannot read {}", script));
      return fmt::format("{}-{}-{:016x}", d.evaluator, d.blender, fnv1a(text));
    }
  }
  throw std::logic_error("unknown renderer");
}

std::string renderer_executable(RendererKind renderer, const RenderSettings& settings) {
  return renderer == RendererKind::kEvaluator ? std::string() : executable_for(renderer, settings);
}

std::string renderer_version(RendererKind renderer, const RenderSettings& settings) {
  if (renderer == RendererKind::kEvaluator) return std::string("penumbra ") + kPenumbraVersion;
  const std::string exe = executable_for(renderer, settings);
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
      if (l.find(renderer_info(renderer).version_marker) != std::string::npos) {
        line = l;
        break;
      }
  }
  ::unlink(pattern);
  if (p.cancelled) throw RenderCancelled("interrupted");
  if (!p.ok() || line.empty())
    throw RendererError(fmt::format(
        "{}: `{} --version` {}", to_string(renderer), exe,
        p.timed_out ? fmt::format("timed out after {:.0f} s", std::min(60.0, settings.timeout_s))
                    : std::string("failed")));
  return line;
}

}  // namespace penumbra
