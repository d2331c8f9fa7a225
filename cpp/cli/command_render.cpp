// `penumbra render`: one scene with the evaluator, POV-Ray or Blender, into
// an OpenEXR with the scene in its header (and an optional PNG preview).
#include <unistd.h>

#include <filesystem>

#include <fmt/format.h>

#include "cli/command.h"
#include "cli/stop_signals.h"
#include "core/shadow_origin.h"
#include "image/image_io.h"
#include "renderers/renderers.h"
#include "util/files.h"
#include "util/strict_json.h"
#include "util/version.h"

namespace penumbra {

namespace fs = std::filesystem;

namespace {

struct RenderArgs {
  std::string scene;
  std::string output;
  std::string preview;
  SceneArgs scene_args;
  bool quiet = false;
  std::string renderer = "evaluator";
  double timeout = 600.0;
  double max_memory_gib = kDefaultMaxMemoryBytes / kGiB;
};

class ProgressLine {
 public:
  ProgressLine(std::ostream& err, bool enabled, std::string label)
      : err_(err), enabled_(enabled && ::isatty(STDERR_FILENO)), label_(std::move(label)) {}
  void operator()(double fraction) const {
    if (enabled_) err_ << fmt::format("\r{} {:5.1f}%", label_, 100.0 * fraction) << std::flush;
  }
  void finish() const {
    if (enabled_) err_ << "\r" << std::string(label_.size() + 8, ' ') << "\r" << std::flush;
  }

 private:
  std::ostream& err_;
  bool enabled_;
  std::string label_;
};

// The log of an external render sits beside its output: out.exr -> out.povray.log.
std::string log_path_for(const std::string& output, RendererKind renderer) {
  fs::path p(output);
  p.replace_extension(std::string(".") + to_string(renderer) + ".log");
  return p.string();
}

// The scene's map file (/height/file, already made absolute) is an input:
// an output of the same file would replace it, as compare refuses too.
void check_not_an_input(const std::string& output, const char* option, const LoadedScene& loaded) {
  const nlohmann::json::json_pointer file("/height/file");
  if (output.empty() || !loaded.document.contains(file) || !loaded.document[file].is_string())
    return;
  const std::string map = loaded.document[file].get<std::string>();
  std::error_code ec;
  if (fs::equivalent(output, map, ec))
    throw UsageError(fmt::format("{} {}: is the scene's /height/file {}, an input of the render",
                                 option, printable(output, 240), printable(map, 240)));
}

// Everything that can be refused is refused before the render starts.
void check_outputs(const RenderArgs& a, RendererKind renderer, const LoadedScene& loaded) {
  check_not_an_input(a.output, "-o", loaded);
  check_not_an_input(a.preview, "--preview", loaded);
  check_extension(a.output, ".exr", "-o",
                  ": only OpenEXR holds the float R G B A and analysis channels of a render "
                  "(--preview FILE.png writes an 8-bit picture)");
  if (!a.preview.empty()) check_extension(a.preview, ".png", "--preview");
  check_writable(a.output);
  if (!a.preview.empty()) {
    check_writable(a.preview);
    load_image_formats();  // before rendering, not after
  }
  const fs::path folder =
      fs::path(a.output).parent_path().empty() ? fs::path(".") : fs::path(a.output).parent_path();
  check_resources(estimate_resources(renderer, loaded.scene), a.max_memory_gib * kGiB,
                  loaded.origin, folder.string());
  remove_stale_temporaries(folder.string());
}

void print_summary(const RenderArgs& a, RendererKind renderer, const Scene& scene,
                   const RendererRun& run, std::ostream& out) {
  const Image& image = run.image;
  const RenderStats& stats = run.stats;
  if (renderer_info(renderer).external()) {
    out << fmt::format(
        "wrote {} ({}x{}, {} spp, {}, method {}, {}): {} {:.2f} s wall, evaluator geometry pass "
        "{:.2f} s\n",
        a.output, image.width, image.height, scene.camera.spp, to_string(scene.representation),
        method_info(scene.terminator.method.method).id, to_string(renderer), to_string(renderer),
        run.seconds, run.geometry_seconds);
    return;
  }
  out << fmt::format("wrote {} ({}x{}, {} spp, {}, method {}): {:.3f} s, {:.2f} M camera samples/s",
                     a.output, image.width, image.height, scene.camera.spp,
                     to_string(scene.representation),
                     method_info(scene.terminator.method.method).id, stats.seconds,
                     double(stats.camera_samples) / stats.seconds / 1e6);
  if (stats.triangles)
    out << fmt::format(", {} triangles built in {:.3f} s", stats.triangles, stats.build_seconds);
  if (scene.tessellation)
    out << fmt::format(", offset {}", offset_method_info(scene.offset.method).id);
  out << "\n";
  if (!a.preview.empty()) out << "wrote " << a.preview << "\n";
}

int render(const RenderArgs& a, const CommandContext& c) {
  const std::optional<RendererKind> renderer = renderer_from_id(a.renderer);
  if (!renderer)
    throw UsageError(
        fmt::format("--renderer: expected {}, got \"{}\"", renderer_choices(""), a.renderer));
  const ImageReadLimit image_limit(a.max_memory_gib * kGiB);  // the scene's map
  const LoadedScene loaded = read_scene(a.scene, a.scene_args);
  const Scene& scene = loaded.scene;
  check_outputs(a, *renderer, loaded);

  const StopSignals stop;
  const ProgressLine progress(c.err, !a.quiet, "rendering " + a.output);
  RenderSettings settings;
  settings.timeout_s = a.timeout;
  settings.threads = c.parallelism.threads();  // one render: all of --threads
  settings.log_path = log_path_for(a.output, *renderer);
  settings.progress.progress = [&](double f) {
    if (StopSignals::interrupted().load()) throw RenderCancelled("interrupted");
    progress(f);
  };
  check_offered(*renderer, scene);  // the evaluator offers everything
  if (renderer_info(*renderer).external() && !a.quiet)
    c.err << fmt::format("running {} (log {}) ...\n", to_string(*renderer), settings.log_path);
  const RendererRun run = render_with(*renderer, scene, settings);
  progress.finish();

  write_exr(run.image, a.output, render_attributes(loaded, *renderer));
  if (!a.preview.empty()) write_preview_png(run.image, a.preview);
  if (!a.quiet) print_summary(a, *renderer, scene, run, c.out);
  return kExitOk;
}

}  // namespace

std::vector<std::pair<std::string, std::string>> render_attributes(const LoadedScene& loaded,
                                                                   RendererKind renderer) {
  const Scene& scene = loaded.scene;
  return {{"penumbra:version", kPenumbraVersion},
          {"penumbra:renderer", to_string(renderer)},
          {"penumbra:scene", loaded.document.dump()},
          {"penumbra:method", std::string(method_info(scene.terminator.method.method).id)},
          {"penumbra:offset", std::string(offset_method_info(scene.offset.method).id)},
          {"penumbra:representation", to_string(scene.representation)},
          {"penumbra:radiance_unit", "W m^-2 sr^-1"}};
}

Command add_render_command(CLI::App& app, SharedOptions&) {
  auto a = std::make_shared<RenderArgs>();
  CLI::App* cmd = app.add_subcommand(
      "render", "render a scene with the evaluator, POV-Ray or Blender Cycles (--renderer)");
  cmd->add_option("scene", a->scene,
                  "scene JSON file, or a mesh file (OBJ, PLY, glTF, ...) framed by a default "
                  "scene")
      ->required();
  cmd->add_option("-o,--output", a->output, "output OpenEXR file")->required();
  cmd->add_option("--preview", a->preview, "also write an sRGB PNG preview");
  add_scene_options(cmd, a->scene_args);
  cmd->add_flag("-q,--quiet", a->quiet, "no progress or summary");
  cmd->add_option("--renderer", a->renderer,
                  "renderer id: " + renderer_choices() +
                      " (default evaluator; see "
                      "`penumbra renderers`)");
  cmd->add_option("--timeout", a->timeout, "seconds an external renderer may run")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--max-memory", a->max_memory_gib,
                  "refuse a render estimated to need more memory (GiB)")
      ->check(CLI::Range(0.001, 1e6))
      ->capture_default_str();
  return {cmd, [a](const CommandContext& c) { return render(*a, c); }};
}

}  // namespace penumbra
