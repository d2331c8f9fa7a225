#include "cli/cli.h"

#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>

#include <fmt/format.h>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "render/evaluator.h"
#include "render/image_io.h"
#include "scene/scene_json.h"

namespace penumbra {
namespace {

using nlohmann::json;

constexpr const char* kVersion = "0.1.0";

struct RenderArgs {
  std::string scene;
  std::string output;
  std::string preview;
  std::string method;
  std::string representation;
  int width = 0, height = 0, spp = 0;
  std::vector<std::string> sets;
  bool quiet = false;
};

std::string parameter_domain(const MethodParameter& p) {
  return fmt::format("{} in [{}, {}] {}, default {}", p.name, p.min_value, p.max_value, p.unit,
                     p.default_value);
}

int command_methods(bool as_json, std::ostream& out) {
  if (as_json) {
    json list = json::array();
    for (const MethodInfo& m : all_methods()) {
      json parameters = json::array();
      for (const MethodParameter& p : m.parameters)
        parameters.push_back({{"name", p.name},
                              {"unit", p.unit},
                              {"min", p.min_value},
                              {"max", p.max_value},
                              {"default", p.default_value},
                              {"description", p.description}});
      list.push_back({{"id", m.id},
                      {"source", m.source},
                      {"summary", m.summary},
                      {"parameters", parameters},
                      {"identity_without_deviation", m.identity_without_deviation},
                      {"note", m.identity_note}});
    }
    out << list.dump(2) << "\n";
    return kExitOk;
  }
  out << fmt::format("{:<24} {:<40} {}\n", "id", "parameters", "source");
  for (const MethodInfo& m : all_methods()) {
    std::string parameters = "-";
    for (const MethodParameter& p : m.parameters) parameters = parameter_domain(p);
    out << fmt::format("{:<24} {:<40} {}\n", m.id, parameters, m.source);
    out << fmt::format("{:<24} {}\n", "", m.summary);
    if (!m.identity_without_deviation) out << fmt::format("{:<24} note: {}\n", "", m.identity_note);
  }
  out << "\nAll factors lie in [0,1] and multiply the light's contribution to the lobes chosen by "
         "/terminator/lobes.\n";
  return kExitOk;
}

std::vector<Override> collect_overrides(const RenderArgs& a) {
  std::vector<Override> overrides;
  if (!a.method.empty()) overrides.push_back({"/terminator/method", a.method});
  if (!a.representation.empty()) overrides.push_back({"/representation", a.representation});
  if (a.width > 0) overrides.push_back({"/camera/width", a.width});
  if (a.height > 0) overrides.push_back({"/camera/height", a.height});
  if (a.spp > 0) overrides.push_back({"/camera/spp", a.spp});
  for (const std::string& s : a.sets) overrides.push_back(parse_override(s));
  return overrides;
}

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

int command_render(const RenderArgs& a, std::ostream& out, std::ostream& err) {
  const std::vector<Override> overrides = collect_overrides(a);
  json document = read_json_file(a.scene);
  const std::string origin = overrides.empty() ? a.scene : a.scene + " (after --set)";
  apply_overrides(document, overrides, origin);
  const Scene scene = scene_from_json(document, origin);
  check_writable(a.output);
  if (!a.preview.empty()) check_writable(a.preview);

  const ProgressLine progress(err, !a.quiet, "rendering " + a.output);
  RenderOptions options;
  options.progress = [&](double f) { progress(f); };
  RenderStats stats;
  const Image image = render(scene, options, &stats);
  progress.finish();

  write_exr(image, a.output,
            {{"penumbra:version", kVersion},
             {"penumbra:renderer", "evaluator"},
             {"penumbra:scene", document.dump()},
             {"penumbra:method", std::string(method_info(scene.terminator.method.method).id)},
             {"penumbra:representation", to_string(scene.representation)},
             {"penumbra:radiance_unit", "W m^-2 sr^-1"}});
  if (!a.preview.empty()) write_preview_png(image, a.preview);
  if (!a.quiet) {
    out << fmt::format(
        "wrote {} ({}x{}, {} spp, {}, method {}): {:.3f} s, {:.2f} M camera samples/s", a.output,
        image.width, image.height, scene.camera.spp, to_string(scene.representation),
        method_info(scene.terminator.method.method).id, stats.seconds,
        double(stats.camera_samples) / stats.seconds / 1e6);
    if (stats.triangles)
      out << fmt::format(", {} triangles built in {:.3f} s", stats.triangles, stats.build_seconds);
    out << "\n";
    if (!a.preview.empty()) out << "wrote " << a.preview << "\n";
  }
  return kExitOk;
}

double peak_rss_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) / 1024.0;  // Linux reports KiB
}

// The benchmark scene of the evaluator issue: a 512x512, 16 spp bump cylinder.
json bench_scene(int size, int spp) {
  return {
      {"version", 1},
      {"name", "bench-cylinder-grating"},
      {"camera",
       {{"position", {0, 0, -5}},
        {"direction", {0, 0, 1}},
        {"right", {2.5, 0, 0}},
        {"up", {0, 2.5, 0}},
        {"width", size},
        {"height", size},
        {"spp", spp},
        {"seed", 1}}},
      {"light", {{"type", "distant"}, {"direction", {-1, 0, -0.2}}, {"irradiance", kPi}}},
      {"shape", {{"type", "cylinder"}, {"radius", 1.0}, {"height", 2.0}}},
      {"material", {{"albedo", 0.8}}},
      {"height",
       {{"type", "grating"}, {"amplitude", 0.01}, {"frequency", 8.0}, {"direction", {1, 0, 0}}}},
      {"representation", "bump"}};
}

int command_bench(int size, int spp, std::ostream& out) {
  out << fmt::format(
      "penumbra bench: {}x{}, {} spp, bump cylinder (grating, A = 0.01), {} threads\n", size, size,
      spp, tbb::info::default_concurrency());
  out << fmt::format("{:<24} {:>10} {:>16}\n", "method", "wall s", "M samples/s");
  for (const MethodInfo& m : all_methods()) {
    json document = bench_scene(size, spp);
    document["terminator"] = {{"method", m.id}};
    const Scene scene = scene_from_json(document, "<bench>");
    RenderStats stats;
    render(scene, {}, &stats);
    out << fmt::format("{:<24} {:>10.3f} {:>16.2f}\n", m.id, stats.seconds,
                       double(stats.camera_samples) / stats.seconds / 1e6);
  }
  const double rss_before = peak_rss_mib();
  json document = bench_scene(size, spp);
  document["representation"] = "displacement";
  const Scene scene = scene_from_json(document, "<bench>");
  RenderStats stats;
  render(scene, {}, &stats);
  out << fmt::format(
      "displacement (edge {:.5f}): {} triangles, build {:.3f} s, total {:.3f} s wall, {:.2f} M "
      "samples/s; peak RSS {:.0f} MiB (before: {:.0f} MiB)\n",
      scene.displacement.edge_length, stats.triangles, stats.build_seconds, stats.seconds,
      double(stats.camera_samples) / stats.seconds / 1e6, peak_rss_mib(), rss_before);
  return kExitOk;
}

}  // namespace

int run_cli(int argc, const char* const* argv, std::ostream& out, std::ostream& err) {
  CLI::App app{"Penumbra: shadow-terminator laboratory (reference evaluator)", "penumbra"};
  app.require_subcommand(1);
  app.set_version_flag("--version", kVersion);
  app.footer(
      "Exit status: 0 success; 1 a run failed (renderer or internal error); 2 bad input "
      "(usage, scene file, output path).");
  int threads = 0;
  app.add_option("--threads", threads, "worker threads (default: all cores)")
      ->check(CLI::Range(1, 1024));

  bool methods_json = false;
  CLI::App* methods = app.add_subcommand("methods", "list the terminator methods");
  methods->add_flag("--json", methods_json, "print a JSON array");

  RenderArgs r;
  CLI::App* render_cmd = app.add_subcommand("render", "render a scene with the evaluator");
  render_cmd->add_option("scene", r.scene, "scene JSON file")->required();
  render_cmd->add_option("-o,--output", r.output, "output OpenEXR file")->required();
  render_cmd->add_option("--preview", r.preview, "also write an sRGB PNG preview");
  render_cmd->add_option("--method", r.method, "terminator method id (see `penumbra methods`)");
  render_cmd->add_option("--representation", r.representation, "smooth, bump or displacement");
  render_cmd->add_option("--width", r.width, "image width in pixels")->check(CLI::PositiveNumber);
  render_cmd->add_option("--height", r.height, "image height in pixels")
      ->check(CLI::PositiveNumber);
  render_cmd->add_option("--spp", r.spp, "samples per pixel")->check(CLI::PositiveNumber);
  render_cmd->add_option("--set", r.sets,
                         "override a scene value: /json/pointer=VALUE (repeatable)");
  render_cmd->add_flag("-q,--quiet", r.quiet, "no progress or summary");

  int bench_size = 512, bench_spp = 16;
  CLI::App* bench = app.add_subcommand("bench", "print evaluator throughput figures");
  bench->add_option("--size", bench_size, "image size in pixels")->check(CLI::Range(16, 4096));
  bench->add_option("--spp", bench_spp, "samples per pixel")->check(CLI::Range(1, 1024));

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e, out, err);  // --help, --version
    err << "penumbra: error: " << e.what() << " (see penumbra --help)\n";
    return kExitBadInput;
  }

  std::unique_ptr<tbb::global_control> limit;
  if (threads > 0)
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                  threads);
  try {
    if (*methods) return command_methods(methods_json, out);
    if (*render_cmd) return command_render(r, out, err);
    if (*bench) return command_bench(bench_size, bench_spp, out);
  } catch (const InputError& e) {
    err << "penumbra: error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const OutputError& e) {
    err << "penumbra: error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::exception& e) {
    err << "penumbra: failed: " << e.what() << "\n";
    return kExitFailure;
  }
  return kExitBadInput;
}

}  // namespace penumbra
