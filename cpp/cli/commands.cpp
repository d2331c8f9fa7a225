#include "cli/commands.h"

#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <nlohmann/json.hpp>

#include "analysis/contour.h"
#include "analysis/filtering.h"
#include "analysis/intervals.h"
#include "analysis/metrics.h"
#include "analysis/metrics_json.h"
#include "core/ray_packet.h"
#include "core/roughness_filter.h"
#include "export/export.h"
#include "image/bump_maps.h"
#include "image/image_io.h"
#include "render/evaluator.h"
#include "renderers/renderers.h"
#include "scene/scene_json.h"
#include "study/calibration.h"
#include "study/execute.h"
#include "study/figures.h"
#include "study/study.h"
#include "util/data_files.h"
#include "util/files.h"
#include "util/process.h"

namespace penumbra {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

std::atomic<bool> g_interrupted{false};
std::atomic<int> g_signal{0};
extern "C" void on_stop_signal(int signal) {
  g_signal.store(signal);
  g_interrupted.store(true);
  cancel_processes();  // ends running renderers and everything they started
}

constexpr std::array<int, 3> kStopSignals{SIGINT, SIGTERM, SIGHUP};

}  // namespace

StopSignals::StopSignals() {
  g_interrupted.store(false);
  g_signal.store(0);
  reset_cancel_processes();
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  for (std::size_t i = 0; i < kStopSignals.size(); ++i)
    ::sigaction(kStopSignals[i], &action, &previous_[i]);
}

StopSignals::~StopSignals() {
  for (std::size_t i = 0; i < kStopSignals.size(); ++i)
    ::sigaction(kStopSignals[i], &previous_[i], nullptr);
  reset_cancel_processes();
}

int StopSignals::exit_code() {
  return 128 + (g_signal.load() ? g_signal.load() : SIGINT);
}

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
          {"bump_methods", method_ids(methods_offered(info.kind, Representation::kBump))},
          {"smooth_and_displacement_methods",
           method_ids(methods_offered(info.kind, Representation::kDisplacement))},
          {"methods_why_not", info.methods_why_not},
          {"offsets", offset_ids(offsets_offered(info.kind))},
          {"offsets_why_not", info.offsets_why_not},
          {"props", info.props},
          {"height_maps", info.height_maps},
          {"height_maps_why_not", info.height_maps_why_not},
          {"normal_maps", info.normal_maps},
          {"normal_maps_why_not", info.normal_maps_why_not},
          {"plane", info.plane},
          {"plane_why_not", info.plane_why_not}};
}

}  // namespace

int command_renderers(bool as_json, std::ostream& out) {
  if (as_json) {
    json list = json::array();
    for (const RendererInfo& info : renderer_table()) list.push_back(renderer_json(info));
    out << list.dump(2) << "\n";
    return kExitOk;
  }
  for (const RendererInfo& info : renderer_table()) {
    const json j = renderer_json(info);
    auto join = [](const json& ids) {
      std::string text;
      for (const json& id : ids) text += (text.empty() ? "" : ", ") + id.get<std::string>();
      return text;
    };
    out << fmt::format("{} ({})\n  {}\n", info.id, info.name, info.note);
    if (*info.debian_package)
      out << fmt::format("  Debian package {}, executable `{}` (or ${})\n", info.debian_package,
                         info.executable, info.executable_variable);
    out << fmt::format("  bump methods: {}\n", join(j["bump_methods"]));
    out << fmt::format("  smooth/displacement methods: {}\n",
                       join(j["smooth_and_displacement_methods"]));
    out << fmt::format("  shadow-ray offsets: {}\n", join(j["offsets"]));
    if (*info.methods_why_not) out << fmt::format("  why not more: {}\n", info.methods_why_not);
    if (*info.props_why_not) out << fmt::format("  props: {}\n", info.props_why_not);
    if (*info.specular_why_not) out << fmt::format("  glossy: {}\n", info.specular_why_not);
    if (*info.height_maps_why_not)
      out << fmt::format("  height maps: {}\n", info.height_maps_why_not);
    if (*info.normal_maps_why_not)
      out << fmt::format("  normal maps: {}\n", info.normal_maps_why_not);
    if (*info.plane_why_not) out << fmt::format("  plane: {}\n", info.plane_why_not);
  }
  return kExitOk;
}

int command_report(const std::string& folder, bool self_contained, std::ostream& out,
                   std::ostream& err) {
  const fs::path report = fs::path(folder) / "report.json";
  if (!fs::is_regular_file(report))
    throw UsageError(fmt::format("{}: no such file (give a study output folder)", report.string()));
  read_json_file(report.string());  // strict: a damaged report is bad input, named here
  const std::string html =
      draw_report(folder, self_contained, "", kFiguresTimeoutS, [&err](const std::string& line) {
        err << "penumbra report: " << line << "\n" << std::flush;
      });
  out << fmt::format("report: {}\n", html);
  return kExitOk;
}

namespace {

// The output formats, from the extension: only OpenEXR holds float radiance
// and the analysis channels; the preview is a PNG. `why` says so in the error.
void check_extension(const std::string& path, const char* extension, const char* option,
                     const char* why = "") {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  if (ext != extension)
    throw UsageError(fmt::format("{} {}: expected a file name ending in {} (got \"{}\"){}", option,
                                 path, extension, ext, why));
}

// Refuses, before anything runs, a method or offset the renderer does not ship
// (the exporters refuse them too, but only after the mesh is built).
void check_offered(RendererKind renderer, const Scene& scene) {
  const auto methods = methods_offered(renderer, scene.representation);
  const TerminatorMethod method = scene.terminator.method.method;
  if (std::find(methods.begin(), methods.end(), method) == methods.end()) {
    std::string ids;
    for (TerminatorMethod m : methods)
      ids += (ids.empty() ? "" : ", ") + std::string(method_info(m).id);
    throw ExportError(fmt::format(
        "{} does not offer the method \"{}\" for the {} representation "
        "(it offers: {})",
        to_string(renderer), method_info(method).id, to_string(scene.representation), ids));
  }
  const auto offsets = offsets_offered(renderer);
  if (std::find(offsets.begin(), offsets.end(), scene.offset.method) == offsets.end())
    throw ExportError(fmt::format("{} does not offer the shadow-ray offset \"{}\"",
                                  to_string(renderer), offset_method_info(scene.offset.method).id));
}

std::string parameter_domain(const MethodParameter& p) {
  return fmt::format("{} in [{}, {}] {}, default {}", p.name, p.min_value, p.max_value, p.unit,
                     p.default_value);
}

json parameters_json(std::span<const MethodParameter> list) {
  json parameters = json::array();
  for (const MethodParameter& p : list)
    parameters.push_back({{"name", p.name},
                          {"unit", p.unit},
                          {"min", p.min_value},
                          {"max", p.max_value},
                          {"default", p.default_value},
                          {"description", p.description}});
  return parameters;
}

const char* family_name(MethodKind kind) {
  switch (kind) {
    case MethodKind::kFactor:
      return "factor";
    case MethodKind::kFactorAndAdjustment:
      return "factor+adjustment";
    case MethodKind::kAdjustment:
      return "adjustment";
    case MethodKind::kMicrofacet:
      return "microfacet";
  }
  return "?";
}

const char* factor_lobes_name(FactorLobes lobes) {
  switch (lobes) {
    case FactorLobes::kScene:
      return "scene";
    case FactorLobes::kDiffuse:
      return "diffuse";
    case FactorLobes::kAll:
      return "all";
  }
  return "?";
}

// One line saying how the method acts, for the text listing.
std::string method_family_text(const MethodInfo& m) {
  const std::string adjustment(normal_adjustment_info(m.adjustment).id);
  const std::string lobes =
      m.lobes == FactorLobes::kScene
          ? "the lobes of /terminator/lobes"
          : (m.lobes == FactorLobes::kDiffuse ? "the diffuse lobe" : "every lobe");
  const std::string reference = m.reference_is_ni ? ", reference Ni" : "";
  switch (m.kind) {
    case MethodKind::kFactor:
      return fmt::format("factor on {}", lobes);
    case MethodKind::kFactorAndAdjustment:
      return fmt::format("factor on {}{} + normal adjustment {}", lobes, reference, adjustment);
    case MethodKind::kAdjustment:
      return fmt::format("normal adjustment {}{}", adjustment, reference);
    case MethodKind::kMicrofacet:
      return "microfacet model: replaces the BSDF (both lobes)";
  }
  return "";
}

}  // namespace

const char* distribution_name(FilteredDistribution d) {
  switch (d) {
    case FilteredDistribution::kGgx:
      return "ggx";
    case FilteredDistribution::kBeckmann:
      return "beckmann";
    case FilteredDistribution::kSchillingBlinnPhong:
      return "schilling-blinn-phong";
  }
  return "?";
}

void add_roughness_filters(json& list) {
  for (const RoughnessFilterInfo& f : all_roughness_filters())
    list.push_back({{"id", f.id},
                    {"kind", "roughness_filter"},
                    {"source", f.source},
                    {"summary", f.summary},
                    {"parameters", parameters_json(f.parameters)},
                    {"distribution", distribution_name(f.distribution)},
                    {"input", f.needs_normal_derivatives ? "normal screen-space derivatives"
                                                         : "bump and roughness pyramid"}});
}

void print_roughness_filters(std::ostream& out) {
  out << fmt::format(
      "\nRoughness filters (bump-map filtering: a scene's /height/filter and `penumbra "
      "filtering`; `penumbra pyramid` builds their input; the lobe they give is a slope-space "
      "alpha^2 tensor A on the named distribution):\n{:<24} "
      "{:<40} {}\n",
      "id", "distribution", "source");
  for (const RoughnessFilterInfo& f : all_roughness_filters()) {
    out << fmt::format("{:<24} {:<40} {}\n", f.id, distribution_name(f.distribution), f.source);
    out << fmt::format("{:<24} {}\n", "", f.summary);
    for (const FilterParameter& p : f.parameters)
      out << fmt::format("{:<24} parameter {}: {}\n", "", parameter_domain(p), p.description);
  }
}

int command_methods(bool as_json, std::ostream& out) {
  if (as_json) {
    json list = json::array();
    for (const MethodInfo& m : all_methods()) {
      const json parameters = parameters_json(m.parameters);
      list.push_back({{"id", m.id},
                      {"kind", "terminator"},
                      {"source", m.source},
                      {"summary", m.summary},
                      {"parameters", parameters},
                      {"family", family_name(m.kind)},
                      {"normal_adjustment", normal_adjustment_info(m.adjustment).id},
                      {"factor_lobes", factor_lobes_name(m.lobes)},
                      {"reference_normal", m.reference_is_ni ? "Ni" : "scene"},
                      {"identity_without_deviation", m.identity_without_deviation},
                      {"note", m.identity_note}});
    }
    for (const NormalAdjustmentInfo& a : all_normal_adjustments())
      list.push_back({{"id", a.id},
                      {"kind", "normal_adjustment"},
                      {"source", a.source},
                      {"summary", a.summary},
                      {"touches_diffuse", a.touches_diffuse}});
    for (const OffsetMethodInfo& m : all_offset_methods()) {
      const json parameters = parameters_json(m.parameters);
      list.push_back({{"id", m.id},
                      {"kind", "offset"},
                      {"source", m.source},
                      {"summary", m.summary},
                      {"parameters", parameters}});
    }
    add_roughness_filters(list);
    out << list.dump(2) << "\n";
    return kExitOk;
  }
  out << fmt::format("{:<24} {:<40} {}\n", "id", "parameters", "source");
  for (const MethodInfo& m : all_methods()) {
    std::string parameters = "-";
    for (const MethodParameter& p : m.parameters) parameters = parameter_domain(p);
    out << fmt::format("{:<24} {:<40} {}\n", m.id, parameters, m.source);
    out << fmt::format("{:<24} {}\n", "", m.summary);
    out << fmt::format("{:<24} ({})\n", "", method_family_text(m));
    if (!m.identity_without_deviation) out << fmt::format("{:<24} note: {}\n", "", m.identity_note);
  }
  out << "\nFactors lie in [0,1] and multiply the light's contribution (BSDF times <Ns,wi>) of "
         "their lobes; adjustments change Ns; microfacet models replace the BSDF.\n";
  out << fmt::format(
      "\nNormal adjustments (/terminator/normal_adjustment, at most one besides the method's "
      "own):\n{:<24} {}\n",
      "id", "source");
  for (const NormalAdjustmentInfo& a : all_normal_adjustments()) {
    out << fmt::format("{:<24} {}\n", a.id, a.source);
    out << fmt::format("{:<24} {}\n", "", a.summary);
  }
  out << fmt::format(
      "\nShadow-ray origin methods (/offset/method; low-poly meshes only):\n{:<24} "
      "{:<40} {}\n",
      "id", "parameters", "source");
  for (const OffsetMethodInfo& m : all_offset_methods()) {
    std::string parameters = "-";
    for (const MethodParameter& p : m.parameters) parameters = parameter_domain(p);
    out << fmt::format("{:<24} {:<40} {}\n", m.id, parameters, m.source);
    out << fmt::format("{:<24} {}\n", "", m.summary);
  }
  print_roughness_filters(out);
  return kExitOk;
}

namespace {

std::vector<Override> collect_overrides(const SceneArgs& a) {
  std::vector<Override> overrides;
  if (!a.method.empty()) overrides.push_back({"/terminator/method", a.method});
  if (!a.offset.empty()) overrides.push_back({"/offset/method", a.offset});
  if (a.segments > 0) overrides.push_back({"/shape/tessellation/segments", a.segments});
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

// The log of an external render sits beside its output: out.exr -> out.povray.log.
std::string log_path_for(const std::string& output, RendererKind renderer) {
  fs::path p(output);
  p.replace_extension(std::string(".") + to_string(renderer) + ".log");
  return p.string();
}

}  // namespace

int command_render(const RenderArgs& a, std::ostream& out, std::ostream& err) {
  const std::optional<RendererKind> renderer = renderer_from_id(a.renderer);
  if (!renderer)
    throw UsageError(
        fmt::format("--renderer: expected evaluator, povray or blender, got \"{}\"", a.renderer));
  const std::vector<Override> overrides = collect_overrides(a.scene_args);
  json document = read_json_file(a.scene);
  resolve_map_files(document, a.scene);
  const std::string origin = overrides.empty() ? a.scene : a.scene + " (after --set)";
  apply_overrides(document, overrides, origin);
  const Scene scene = scene_from_json(document, origin);
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
  check_resources(estimate_resources(*renderer, scene), a.max_memory_gib * kGiB, origin,
                  folder.string());
  remove_stale_temporaries(folder.string());

  const StopSignals stop;
  const ProgressLine progress(err, !a.quiet, "rendering " + a.output);
  RenderSettings settings;
  settings.timeout_s = a.timeout;
  settings.log_path = log_path_for(a.output, *renderer);
  settings.progress.progress = [&](double f) {
    if (g_interrupted.load()) throw RenderCancelled("interrupted");
    progress(f);
  };
  if (*renderer != RendererKind::kEvaluator) check_offered(*renderer, scene);
  if (*renderer != RendererKind::kEvaluator && !a.quiet)
    err << fmt::format("running {} (log {}) ...\n", to_string(*renderer), settings.log_path);
  const RendererRun run = render_with(*renderer, scene, settings);
  progress.finish();
  const Image& image = run.image;
  const RenderStats& stats = run.stats;

  write_exr(image, a.output,
            {{"penumbra:version", kPenumbraVersion},
             {"penumbra:renderer", to_string(*renderer)},
             {"penumbra:scene", document.dump()},
             {"penumbra:method", std::string(method_info(scene.terminator.method.method).id)},
             {"penumbra:offset", std::string(offset_method_info(scene.offset.method).id)},
             {"penumbra:representation", to_string(scene.representation)},
             {"penumbra:radiance_unit", "W m^-2 sr^-1"}});
  if (!a.preview.empty()) write_preview_png(image, a.preview);
  if (!a.quiet && *renderer != RendererKind::kEvaluator) {
    out << fmt::format(
        "wrote {} ({}x{}, {} spp, {}, method {}, {}): {} {:.2f} s wall, evaluator geometry pass "
        "{:.2f} s\n",
        a.output, image.width, image.height, scene.camera.spp, to_string(scene.representation),
        method_info(scene.terminator.method.method).id, to_string(*renderer), to_string(*renderer),
        run.seconds, run.geometry_seconds);
  } else if (!a.quiet) {
    out << fmt::format(
        "wrote {} ({}x{}, {} spp, {}, method {}): {:.3f} s, {:.2f} M camera samples/s", a.output,
        image.width, image.height, scene.camera.spp, to_string(scene.representation),
        method_info(scene.terminator.method.method).id, stats.seconds,
        double(stats.camera_samples) / stats.seconds / 1e6);
    if (stats.triangles)
      out << fmt::format(", {} triangles built in {:.3f} s", stats.triangles, stats.build_seconds);
    if (scene.tessellation)
      out << fmt::format(", offset {}", offset_method_info(scene.offset.method).id);
    out << "\n";
    if (!a.preview.empty()) out << "wrote " << a.preview << "\n";
  }
  return kExitOk;
}

int command_export(const ExportArgs& a, std::ostream& out) {
  const std::vector<Override> overrides = collect_overrides(a.scene_args);
  json document = read_json_file(a.scene);
  resolve_map_files(document, a.scene);
  const std::string origin = overrides.empty() ? a.scene : a.scene + " (after --set)";
  apply_overrides(document, overrides, origin);
  const Scene scene = scene_from_json(document, origin);
  const std::optional<RendererKind> renderer = renderer_from_id(a.to);
  if (renderer) check_offered(*renderer, scene);  // before a folder is made
  std::error_code ec;
  fs::create_directories(a.output, ec);
  if (ec || !fs::is_directory(a.output))
    throw OutputError(fmt::format("{}: cannot create the output folder: {}", a.output,
                                  ec ? ec.message() : "not a folder"));
  // A folder that takes no files fails here, before the mesh is built.
  check_writable((fs::path(a.output) / (a.to == to_string(RendererKind::kPovray)
                                            ? std::string("scene.pov")
                                            : std::string(kBlenderJobFile)))
                     .string());
  if (a.to == to_string(RendererKind::kPovray)) {
    const PovrayExport job = export_povray(scene);
    const std::string path = (fs::path(a.output) / "scene.pov").string();
    write_povray_files(job, a.output);
    out << fmt::format(
        "wrote {}{} (render {}x{} without anti-aliasing, box-filter {}x{} down to "
        "{}x{}; the command line is in its first lines)\n",
        path, job.map.pixels.empty() ? "" : std::string(" and its ") + kPovrayMapFile,
        job.width * job.supersample_x, job.height * job.supersample_y, job.supersample_x,
        job.supersample_y, job.width, job.height);
    return kExitOk;
  }
  const BlenderExport job = export_blender(scene);
  const fs::path dir(a.output);
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

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Image read_image_checked(const std::string& path) {
  if (!fs::is_regular_file(path)) throw UsageError(fmt::format("{}: no such file", path));
  return read_image(path);
}

// R, G, B and A of `image` on a copy of `geometry` (same size): the analysis
// channels of one render lent to an image that has none.
Image with_channels_of(const Image& image, const Image& geometry) {
  Image out = geometry;
  const std::size_t nc = out.channels.size();
  const char* names[4] = {"R", "G", "B", "A"};
  for (int c = 0; c < 4; ++c) {
    const int from = image.channel_index(names[c]), to = out.channel_index(names[c]);
    for (int y = 0; y < out.height; ++y)
      for (int x = 0; x < out.width; ++x)
        out.pixels[(std::size_t(y) * out.width + x) * nc + to] = image.at(x, y, from);
  }
  return out;
}

// albedo * E / pi of the first of `paths` whose penumbra:scene gives one; NaN
// when none carries the metadata (an image from another renderer).
double radiance_scale_of(const std::vector<std::string>& paths) {
  for (const std::string& path : paths) {
    const std::string text = read_image_attribute(path, "penumbra:scene");
    if (text.empty()) continue;
    const std::string origin = path + " (penumbra:scene metadata)";
    return radiance_scale(scene_from_json(parse_json_text(text, origin), origin));
  }
  return kNaN;
}

void require_rgb(const Image& image, const std::string& path) {
  for (const char* name : {"R", "G", "B"})
    if (image.channel_index(name) < 0)
      throw UsageError(fmt::format("{}: no {} channel (compare needs R, G and B; it has {})", path,
                                   name, fmt::join(image.channels, ", ")));
}

// `image` with its A channel set to alpha(x, y), appended when it has none.
template <class Alpha>
Image with_alpha(const Image& image, Alpha alpha) {
  Image out = image;
  int a = image.channel_index("A");
  if (a < 0) {
    const std::size_t nc = image.channels.size(), n = std::size_t(image.width) * image.height;
    out.channels.push_back("A");
    out.pixels.assign(n * (nc + 1), 0.0f);
    for (std::size_t p = 0; p < n; ++p)
      std::copy_n(&image.pixels[p * nc], nc, &out.pixels[p * (nc + 1)]);
    a = static_cast<int>(nc);
  }
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) out.at(x, y, a) = alpha(x, y);
  return out;
}

// One side of a comparison; `coverage` says where its A channel came from.
struct CompareImage {
  std::string path;
  Image image;
  std::string coverage = "A channel";
};

// The coverage a --mask image gives: its A channel, else its first channel.
Image mask_coverage(const CompareImage& side, const std::string& mask_path, const Image& mask) {
  if (mask.width != side.image.width || mask.height != side.image.height)
    throw UsageError(fmt::format("--mask {} is {}x{} but {} is {}x{}", mask_path, mask.width,
                                 mask.height, side.path, side.image.width, side.image.height));
  if (mask.channels.empty()) throw UsageError(fmt::format("--mask {}: no channels", mask_path));
  const int c = std::max(0, mask.channel_index("A"));
  return with_alpha(side.image, [&](int x, int y) { return mask.at(x, y, c); });
}

// Gives an image without an A channel one, from --mask or --threshold, or
// says what it lacks. --no-mask needs none (the image metrics then count
// every pixel, the profile is not computed).
void resolve_coverage(CompareImage& side, const CompareArgs& a, const Image* mask, double scale) {
  if (side.image.channel_index("A") >= 0) return;
  if (mask) {
    side.image = mask_coverage(side, a.mask, *mask);
    side.coverage = "--mask " + a.mask;
  } else if (a.threshold) {
    if (!std::isfinite(scale))
      throw UsageError(fmt::format(
          "--threshold is a fraction of albedo*E/pi, which neither image's penumbra:scene "
          "gives ({} has none): add --scale",
          side.path));
    const double level = *a.threshold * scale;
    const int rgb[3] = {side.image.channel_index("R"), side.image.channel_index("G"),
                        side.image.channel_index("B")};
    const Image& im = side.image;
    side.image = with_alpha(im, [&](int x, int y) {
      const double v = (im.at(x, y, rgb[0]) + im.at(x, y, rgb[1]) + im.at(x, y, rgb[2])) / 3.0;
      return v >= level ? 1.0f : 0.0f;
    });
    side.coverage = fmt::format("--threshold {}: lit where radiance >= {:.6g} W m^-2 sr^-1",
                                *a.threshold, level);
  } else if (a.no_mask) {
    side.coverage = "none (--no-mask)";
  } else {
    throw UsageError(fmt::format(
        "{}: no A (coverage) channel and no --mask FILE or --threshold given (or --no-mask for "
        "image metrics over every pixel)",
        side.path));
  }
}

// What must match for two renders to be comparable: the same camera, light,
// shape and height function (representation, method and sampling may
// differ). Returns the differing pointers, none when they match or either
// image lacks the metadata.
std::vector<std::string> scene_differences(const std::string& reference, const std::string& test) {
  const std::string a = read_image_attribute(reference, "penumbra:scene");
  const std::string b = read_image_attribute(test, "penumbra:scene");
  if (a.empty() || b.empty()) return {};
  auto comparable = [](const json& scene) {
    json out = json::object();
    for (const char* key : {"camera", "light", "shape", "height"})
      if (scene.is_object() && scene.contains(key)) out[key] = scene[key];
    if (out.contains("shape") && out["shape"].is_object()) out["shape"].erase("tessellation");
    // A filter changes how the bumps are shaded, not which surface it is.
    if (out.contains("height") && out["height"].is_object()) out["height"].erase("filter");
    if (out.contains("camera") && out["camera"].is_object())
      for (const char* key : {"spp", "seed"}) out["camera"].erase(key);
    return out;
  };
  const json diff = json::diff(comparable(parse_json_text(a, reference + " (penumbra:scene)")),
                               comparable(parse_json_text(b, test + " (penumbra:scene)")));
  // Named two levels deep (/camera/right, not /camera/right/0), the shape first.
  std::vector<std::string> where;
  for (const char* key : {"/shape", "/camera", "/light", "/height"})
    for (const json& op : diff) {
      const std::string path = op.at("path").get<std::string>();
      if (path.rfind(key, 0) != 0 ||
          (path.size() > std::strlen(key) && path[std::strlen(key)] != '/'))
        continue;
      const std::string named = printable(path.substr(0, path.find('/', std::strlen(key) + 1)), 60);
      if (std::find(where.begin(), where.end(), named) == where.end()) where.push_back(named);
    }
  return where;
}

// Warns (or, with --same-scene, refuses) when the two images show different
// scenes: their metrics would compare unrelated images.
void check_same_scene(const CompareArgs& a, std::ostream& err) {
  const std::vector<std::string> where = scene_differences(a.reference, a.test);
  if (where.empty()) return;
  const std::size_t shown = std::min<std::size_t>(where.size(), 8);
  const std::string list =
      fmt::format("{}{}", fmt::join(where.begin(), where.begin() + long(shown), ", "),
                  where.size() > shown ? fmt::format(" and {} more", where.size() - shown) : "");
  const std::string message = fmt::format(
      "{} and {} show different scenes (penumbra:scene differs at {})", a.reference, a.test, list);
  if (a.same_scene) throw UsageError(message + "; --same-scene");
  err << "penumbra: warning: " << message << "; the metrics compare unrelated images\n";
}

// R, G, B: test - reference (W m^-2 sr^-1); A: the smaller coverage (1 for
// an image without one, --no-mask).
Image difference_image(const Image& test, const Image& reference) {
  Image out;
  out.width = test.width, out.height = test.height;
  out.channels = {"R", "G", "B", "A"};
  out.pixels.resize(std::size_t(out.width) * out.height * 4);
  int t[4], r[4];
  const char* names[4] = {"R", "G", "B", "A"};
  for (int c = 0; c < 4; ++c)
    t[c] = test.channel_index(names[c]), r[c] = reference.channel_index(names[c]);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) {
      float* p = &out.pixels[(std::size_t(y) * out.width + x) * 4];
      for (int c = 0; c < 3; ++c) p[c] = test.at(x, y, t[c]) - reference.at(x, y, r[c]);
      p[3] = std::min(t[3] < 0 ? 1.0f : test.at(x, y, t[3]),
                      r[3] < 0 ? 1.0f : reference.at(x, y, r[3]));
    }
  return out;
}

// -o: OpenEXR, writable, and not one of the images compared.
void check_difference_output(const CompareArgs& a) {
  if (a.difference.empty()) return;
  check_extension(a.difference, ".exr", "-o", ": the difference is signed float radiance");
  for (const std::string& input : {a.reference, a.test, a.mask}) {
    std::error_code ec;
    if (!input.empty() && fs::equivalent(a.difference, input, ec))
      throw UsageError(fmt::format("-o {}: is {}, an input of the comparison", a.difference,
                                   input == a.mask ? "the --mask image" : input));
  }
  check_writable(a.difference);
}

}  // namespace

namespace {

// Everything `penumbra compare` reports.
struct CompareResult {
  double scale = kNaN;
  std::string coverage[2];  // reference, test
  std::string skipped;      // why the profile and viewer metrics are missing ("" if not)
  ProfileMetrics pm;
  ImageMetrics im;
  ViewMetrics vm;
  ComparisonIntervals ci;
};

// Why the profile and viewer metrics cannot be computed, "" when they can.
std::string why_no_profile(const Image& reference, const Image& test, double scale) {
  if (reference.channel_index("A") < 0 || test.channel_index("A") < 0)
    return "an image has no coverage (--no-mask without --mask or --threshold)";
  if (reference.channel_index("analysis.theta") < 0 && test.channel_index("analysis.theta") < 0)
    return "neither image has the analysis.theta channel of a Penumbra render";
  if (!std::isfinite(scale))
    return "no albedo*E/pi: neither image carries penumbra:scene metadata (give --scale)";
  return "";
}

ComparisonIntervals nan_intervals() {
  ComparisonIntervals ci;
  for (Interval* i : {&ci.rmse_terminator, &ci.image_rmse, &ci.view_rmse_grazing,
                      &ci.view_bias_grazing, &ci.max_error, &ci.position_error, &ci.lit_bias})
    *i = {kNaN, kNaN};
  ci.rmse_terminator_bias = kNaN;
  return ci;
}

ProfileMetrics nan_profile_metrics() {
  ProfileMetrics m;
  for (double* v : {&m.rmse_terminator, &m.rmse_overall, &m.max_error, &m.max_step,
                    &m.reference_max_step, &m.position, &m.reference_position, &m.position_error,
                    &m.width, &m.reference_width, &m.lit_bias})
    *v = kNaN;
  return m;
}

// Image metrics over the covered pixels or, --no-mask, over every pixel with
// the usual SSIM (analysis/metrics.h, ssim_unmasked).
ImageMetrics image_metrics(const Image& test, const Image& reference, bool no_mask) {
  if (!no_mask) return compare_images(test, reference);
  const auto full = [](const Image& image) {
    return with_alpha(image, [](int, int) { return 1.0f; });
  };
  ImageMetrics m = compare_images(full(test), full(reference));
  m.mask_iou = kNaN;
  m.ssim = m.pixels ? ssim_unmasked(test, reference, m.peak) : kNaN;
  return m;
}

CompareResult compare_sides(const CompareImage& reference, const CompareImage& test, double scale,
                            bool no_mask) {
  CompareResult r;
  r.scale = scale;
  r.coverage[0] = reference.coverage, r.coverage[1] = test.coverage;
  r.im = image_metrics(test.image, reference.image, no_mask);
  r.skipped = why_no_profile(reference.image, test.image, scale);
  if (!r.skipped.empty()) {
    r.pm = nan_profile_metrics();
    r.vm = {kNaN, kNaN, 0};
    r.ci = nan_intervals();
    return r;
  }
  // theta comes from whichever image has it (the reference first): both show
  // the same base points.
  const bool from_reference = reference.image.channel_index("analysis.theta") >= 0;
  const Image ref =
      from_reference ? reference.image : with_channels_of(reference.image, test.image);
  const Image tst = test.image.channel_index("analysis.theta") >= 0
                        ? test.image
                        : with_channels_of(test.image, reference.image);
  const ProfileOptions options;
  r.pm = compare_profiles(terminator_profile(tst, scale, options),
                          terminator_profile(ref, scale, options), options);
  r.vm = view_metrics(view_error_profile(tst, ref, scale));
  r.ci = comparison_intervals(tst, ref, scale, options);
  if (no_mask) r.ci.image_rmse = {kNaN, kNaN};  // its bands count covered pixels only
  return r;
}

}  // namespace

namespace {

json with_interval(json metrics, const char* key, const Interval& i) {
  auto bound = [](double v) { return std::isfinite(v) ? json(v) : json(); };
  metrics[key] = {bound(i.low), bound(i.high)};
  return metrics;
}

json profile_json_with_intervals(const ProfileMetrics& pm, const ComparisonIntervals& ci) {
  json j = with_interval(profile_metrics_json(pm), "rmse_terminator_ci", ci.rmse_terminator);
  j = with_interval(std::move(j), "max_error_terminator_ci", ci.max_error);
  j = with_interval(std::move(j), "position_error_deg_ci", ci.position_error);
  j = with_interval(std::move(j), "lit_bias_ci", ci.lit_bias);
  j["rmse_terminator_bootstrap_bias"] =
      std::isfinite(ci.rmse_terminator_bias) ? json(ci.rmse_terminator_bias) : json();
  return j;
}

std::string interval_note(const ComparisonIntervals& ci) {
  return fmt::format(
      "intervals: 95 %, paired block bootstrap over {} bands of rows, {} resamples (seed 1), "
      "centred on the estimate: the spread over image regions, not a bias both images share",
      ci.bands, ci.resamples);
}

const char* ssim_kind(bool no_mask) {
  return no_mask ? "usual SSIM over every pixel (--no-mask): Gaussian 11x11, sigma 1.5, mean "
                   "over windows inside the image, L = reference peak"
                 : "masked SSIM: Gaussian 11x11, sigma 1.5, windows renormalised over pixels "
                   "fully covered in both, L = reference peak";
}

json comparison_json(const CompareArgs& a, const CompareResult& r, bool pass) {
  const bool profiled = r.skipped.empty();
  json image = with_interval(image_metrics_json(r.im), "rmse_ci", r.ci.image_rmse);
  image["ssim_kind"] = ssim_kind(a.no_mask);
  json doc = {
      {"reference", a.reference},
      {"test", a.test},
      {"coverage", {{"reference", r.coverage[0]}, {"test", r.coverage[1]}}},
      {"radiance_scale", std::isfinite(r.scale) ? json(r.scale) : json()},
      {"radiance_scale_unit", "W m^-2 sr^-1 (albedo * E / pi)"},
      {"profile", profiled ? profile_json_with_intervals(r.pm, r.ci) : json()},
      {"image", image},
      {"view", profiled ? with_interval(with_interval(view_metrics_json(r.vm), "rmse_grazing_ci",
                                                      r.ci.view_rmse_grazing),
                                        "bias_grazing_ci", r.ci.view_bias_grazing)
                        : json()},
      {"intervals", profiled ? json(interval_note(r.ci)) : json()},
      {"pass", pass}};
  if (!profiled) doc["profile_skipped"] = r.skipped;
  return doc;
}

void print_profile(const ProfileMetrics& pm, const ComparisonIntervals& ci, double scale,
                   std::ostream& out) {
  out << fmt::format(
      "profile (1-degree theta bins, fraction of albedo*E/pi = {:.6g} W m^-2 "
      "sr^-1; {} common bins):\n",
      scale, pm.common_bins);
  out << fmt::format("  RMSE terminator [60,100) deg  {:.6f} [{:.6f}, {:.6f}] (95 % CI)\n",
                     pm.rmse_terminator, ci.rmse_terminator.low, ci.rmse_terminator.high);
  out << fmt::format("  (bootstrap bias of that RMSE  {:+.6f})\n", ci.rmse_terminator_bias);
  out << fmt::format("  RMSE overall                  {:.6f}\n", pm.rmse_overall);
  out << fmt::format("  max error terminator          {:.6f} [{:.6f}, {:.6f}]\n", pm.max_error,
                     ci.max_error.low, ci.max_error.high);
  out << fmt::format("  largest bin step              {:.6f} (reference {:.6f})\n", pm.max_step,
                     pm.reference_max_step);
  out << fmt::format(
      "  terminator position (L<{})  {:.3f} deg (reference {:.3f}, error {:+.3f} [{:+.3f}, "
      "{:+.3f}])\n",
      kDarkLevel, pm.position, pm.reference_position, pm.position_error, ci.position_error.low,
      ci.position_error.high);
  out << fmt::format("  transition width 90%->10%     {:.3f} deg (reference {:.3f})\n", pm.width,
                     pm.reference_width);
  out << fmt::format("  lit-region bias (<60 deg)     {:+.6f} [{:+.6f}, {:+.6f}]\n", pm.lit_bias,
                     ci.lit_bias.low, ci.lit_bias.high);
}

void print_image(const ImageMetrics& im, const ComparisonIntervals& ci, bool no_mask,
                 std::ostream& out) {
  out << fmt::format("image ({}: {}):\n",
                     no_mask ? "every pixel, --no-mask" : "pixels fully covered in both",
                     im.pixels);
  out << fmt::format("  mask IoU (alpha>=0.5)         {:.6f}\n", im.mask_iou);
  out << fmt::format(
      "  RMSE                          {:.6g} [{:.6g}, {:.6g}] W m^-2 sr^-1 (95 % CI)\n", im.rmse,
      ci.image_rmse.low, ci.image_rmse.high);
  out << fmt::format("  max error                     {:.6g} W m^-2 sr^-1\n", im.max_error);
  out << fmt::format("  mean error (test-reference)   {:+.6g} W m^-2 sr^-1\n", im.mean_error);
  out << fmt::format("  reference mean                {:.6g} W m^-2 sr^-1\n", im.reference_mean);
  out << fmt::format("  reference peak (SSIM's L)     {:.6g} W m^-2 sr^-1\n", im.peak);
  out << fmt::format("  SSIM                          {:.6f} ({})\n", im.ssim, ssim_kind(no_mask));
  out << fmt::format("  NaN/Inf values                {}\n", im.nonfinite);
}

void print_view(const ViewMetrics& vm, const ComparisonIntervals& ci, std::ostream& out) {
  out << fmt::format(
      "viewer (lit pixels, theta < {} deg, binned by view angle; {} pixels at [{}, {}) deg):\n",
      kLitEnd, vm.pixels, kGrazingBegin, kGrazingEnd);
  out << fmt::format("  RMSE grazing views            {:.6f} [{:.6f}, {:.6f}] (95 % CI)\n",
                     vm.rmse_grazing, ci.view_rmse_grazing.low, ci.view_rmse_grazing.high);
  out << fmt::format(
      "  bias grazing views            {:+.6f} [{:+.6f}, {:+.6f}] (negative: test darker)\n",
      vm.bias_grazing, ci.view_bias_grazing.low, ci.view_bias_grazing.high);
}

// The text form of `penumbra compare`: every metric of --json, with units
// and intervals.
void print_comparison(const CompareArgs& a, const CompareResult& r, bool over, bool pass,
                      std::ostream& out) {
  out << fmt::format("reference {} (coverage: {})\ntest      {} (coverage: {})\n", a.reference,
                     r.coverage[0], a.test, r.coverage[1]);
  if (r.skipped.empty())
    print_profile(r.pm, r.ci, r.scale, out);
  else
    out << fmt::format("profile and viewer metrics: not computed: {}\n", r.skipped);
  print_image(r.im, r.ci, a.no_mask, out);
  if (r.skipped.empty()) {
    print_view(r.vm, r.ci, out);
    out << interval_note(r.ci) << "\n";
  }
  if (over)
    out << fmt::format("FAIL: profile RMSE {:.6f} above --max-profile-rmse {}\n", r.pm.rmse_overall,
                       a.max_rmse);
  out << (pass ? "pass\n" : "FAIL\n");
}

// Reads both images (and --mask), checks that they fit, gives each a coverage.
std::pair<CompareImage, CompareImage> load_sides(const CompareArgs& a, double& scale) {
  CompareImage reference{a.reference, read_image_checked(a.reference)};
  CompareImage test{a.test, read_image_checked(a.test)};
  require_rgb(reference.image, a.reference);
  require_rgb(test.image, a.test);
  if (reference.image.width != test.image.width || reference.image.height != test.image.height)
    throw UsageError(fmt::format("{} is {}x{} but {} is {}x{}", a.reference, reference.image.width,
                                 reference.image.height, a.test, test.image.width,
                                 test.image.height));
  scale = a.scale > 0.0 ? a.scale : radiance_scale_of({a.reference, a.test});
  std::optional<Image> mask;
  if (!a.mask.empty()) mask = read_image_checked(a.mask);
  resolve_coverage(reference, a, mask ? &*mask : nullptr, scale);
  resolve_coverage(test, a, mask ? &*mask : nullptr, scale);
  return {std::move(reference), std::move(test)};
}

}  // namespace

int command_compare(const CompareArgs& a, std::ostream& out, std::ostream& err) {
  check_difference_output(a);
  double scale = kNaN;
  const auto [reference, test] = load_sides(a, scale);
  check_same_scene(a, err);
  const CompareResult r = compare_sides(reference, test, scale, a.no_mask);
  if (a.max_rmse >= 0.0 && !r.skipped.empty())
    throw UsageError(fmt::format("--max-profile-rmse: no profile to check: {}", r.skipped));
  const bool nonfinite = r.im.nonfinite > 0;
  const bool over = a.max_rmse >= 0.0 && !(r.pm.rmse_overall <= a.max_rmse);
  const bool pass = !nonfinite && !over;
  if (!a.difference.empty())
    write_exr(difference_image(test.image, reference.image), a.difference,
              {{"penumbra:difference", a.test + " - " + a.reference},
               {"penumbra:radiance_unit", "W m^-2 sr^-1"}});
  if (a.json)
    out << comparison_json(a, r, pass).dump(2) << "\n";
  else
    print_comparison(a, r, over, pass, out);
  return pass ? kExitOk : kExitThreshold;
}

int command_calibrate(const CalibrationOptions& options, bool quiet, std::ostream& out,
                      std::ostream& err) {
  CalibrationOptions o = options;
  if (!quiet) o.log = [&](const std::string& line) { err << line << "\n" << std::flush; };
  const CalibrationResult result = run_calibration(o);
  write_calibration_reports(result, o.output_dir);
  out << calibration_table(result);
  out << fmt::format("wrote {0}/calibration.md, {0}/calibration.json, {0}/calibration.csv\n",
                     o.output_dir);
  if (!result.all_rendered()) {
    err << "penumbra: failed: some renders did not finish (see above and the logs in "
        << o.output_dir << "/renders)\n";
    return kExitFailure;
  }
  if (!result.all_pass()) {
    err << "penumbra: calibration bounds missed (FAIL rows above)\n";
    return kExitThreshold;
  }
  return kExitOk;
}

namespace {

std::string duration_text(double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  const long t = std::lround(s);
  return t >= 60 ? fmt::format("{}m{:02d}s", t / 60, t % 60) : fmt::format("{}s", t);
}

// One line per kind of render still to do, with where its rate comes from.
void print_cost(const CostEstimate& cost, std::ostream& out) {
  if (cost.lines.empty()) return;
  out << fmt::format(
      "estimated cost of the renders to do: {:.3f} core-hours (cores x wall time; {} on {} "
      "cores), at the samples planned now: the convergence checks come on top, and a truth "
      "that needs more samples raises its variant's bump renders with it:\n",
      cost.core_seconds / 3600.0,
      duration_text(cost.core_seconds / std::max(1u, std::thread::hardware_concurrency())),
      std::max(1u, std::thread::hardware_concurrency()));
  for (const CostLine& line : cost.lines) {
    const std::string kind =
        fmt::format("{} {}{}", to_string(line.renderer), to_string(line.representation),
                    line.tessellated ? " (low-poly)" : "");
    const std::string basis =
        line.measured > 0
            ? fmt::format(
                  "median of {} cached renders of this study; their range {:.4f} to "
                  "{:.4f} core-h",
                  line.measured, line.core_seconds_low / 3600.0, line.core_seconds_high / 3600.0)
            : "built-in rate measured on a 2-core machine, no spread known; none cached yet";
    out << fmt::format(
        "  {:<32} {:>7} renders {:>10.4f} core-h  ({:.3g} core-s per 10^6 "
        "pixel samples: {})\n",
        kind, line.renders, line.core_seconds / 3600.0, line.core_seconds_per_msample, basis);
  }
}

int print_dry_run(const Study& study, const StudyRunStats& stats, const std::string& dir,
                  double max_memory_gib, std::ostream& out) {
  std::string per;
  for (const auto& [renderer, count] : stats.planned)
    per += fmt::format("{}{} {}", per.empty() ? "" : ", ", count, renderer);
  out << fmt::format(
      "study {}: {} renders ({}); {} found in {}/cache, {} to render; nothing written (dry run)\n",
      study.name, stats.renders, per, stats.cached, dir, stats.renders - stats.cached);
  const std::string checks =
      stats.planned_checks == 0
          ? std::string("every ground-truth convergence check is cached")
          : fmt::format(
                "{} ground-truth convergence checks to render first (more may follow, up to 3 "
                "renders per variant and round)",
                stats.planned_checks);
  out << fmt::format(
      "cache: the renders to do write at most {:.3f} GiB (uncompressed EXR); the largest needs "
      "about {:.3f} GiB of memory (--max-memory {:.3g} GiB); {}\n",
      stats.planned_output_bytes / kGiB, stats.planned_peak_memory_bytes / kGiB, max_memory_gib,
      checks);
  print_cost(stats.cost, out);
  if (study.filtering) {
    const FilteringSection& f = *study.filtering;
    out << fmt::format(
        "filtering: {} maps x {} runs, each {} footprints per level over levels 0 to {} x {} "
        "filters x {} base alphas (measured after the renders; unchanged entries in {}/filtering "
        "are reused; about 25 s per entry of a 1024^2 map at the defaults on 2 cores)\n",
        f.maps.size(), f.runs.size(), f.options.footprints, f.options.max_level,
        f.options.filters.size(), f.options.alphas.size(), dir);
  }
  if (study.interplay) {
    const InterplaySection& ip = *study.interplay;
    out << fmt::format(
        "interplay: {} baked at {} texels around, {} bump renders ({} levels x {} methods) and 2 "
        "displacement truths (the evaluator, after the renders; cached in {}/cache)\n",
        ip.scene, ip.size, ip.levels.size() * ip.methods.size(), ip.levels.size(),
        ip.methods.size(), dir);
  }
  return kExitOk;
}

// The Slurm options of `penumbra run`, with the command its report job runs:
// this run again, by absolute paths, so that it runs from any folder.
SlurmOptions slurm_options(const RunArgs& a, const std::string& output_dir) {
  SlurmOptions s = a.slurm;
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot find the penumbra executable (/proc/self/exe)");
  s.continue_argv = {self.string(),
                     "run",
                     fs::absolute(a.study).string(),
                     "-o",
                     fs::absolute(output_dir).string(),
                     "--executor",
                     "slurm",
                     "--timeout",
                     fmt::format("{}", a.timeout),
                     "--max-memory",
                     fmt::format("{}", a.max_memory_gib),
                     "--array-limit",
                     std::to_string(s.array_limit),
                     "--renders-per-task",
                     std::to_string(s.renders_per_task)};
  if (a.no_figures) s.continue_argv.push_back("--no-figures");
  if (a.self_contained) s.continue_argv.push_back("--self-contained");
  if (!s.partition.empty())
    s.continue_argv.insert(s.continue_argv.end(), {"--partition", s.partition});
  for (const std::string& arg : s.sbatch_args) s.continue_argv.push_back("--sbatch-arg=" + arg);
  return s;
}

int print_submission(const SlurmSubmission& sub, const std::string& dir, std::ostream& out) {
  if (sub.submitted > 0)
    out << fmt::format(
        "submitted {} renders to Slurm as array job {} ({} tasks{}); job {} writes the report "
        "when they end (or submits what is still missing); `penumbra status {}` shows progress\n",
        sub.submitted - sub.chains, sub.array_job, sub.tasks,
        sub.chains > 0 ? fmt::format(", with {} ground-truth convergence chains, each in a task of "
                                     "its own with its variant's evaluator renders",
                                     sub.chains)
                       : "",
        sub.report_job, dir);
  if (sub.still_queued > 0)
    out << fmt::format(
        "{} renders are still queued or running in an earlier submission; nothing submitted "
        "twice\n",
        sub.still_queued);
  return kExitOk;
}

}  // namespace

int command_run_batch(const RunBatchArgs& a, std::ostream& out, std::ostream& err) {
  int task = a.task;
  if (task < 0) {
    const char* env = std::getenv("SLURM_ARRAY_TASK_ID");
    if (!env) throw UsageError("run-batch: no --task and no SLURM_ARRAY_TASK_ID");
    task = std::atoi(env);
  }
  const char* cpus = std::getenv("SLURM_CPUS_PER_TASK");
  const int threads = cpus && std::atoi(cpus) > 0 ? std::atoi(cpus) : 1;
  const StopSignals stop;
  SlurmTaskResult r;
  try {
    r = run_slurm_task(a.batch, task, threads, [&](const std::string& line) {
      err << "penumbra run-batch: " << line << "\n" << std::flush;
    });
  } catch (const TaskCancelled&) {
    err << "penumbra run-batch: stopped; unfinished renders are submitted again by the report "
           "job\n";
    return StopSignals::exit_code();
  }
  out << fmt::format(
      "task {}: {} rendered, {} already cached, {} failed (recorded beside the "
      "cache entries)\n",
      task, r.rendered, r.cached, r.failed);
  return r.failed > 0 ? kExitFailure : kExitOk;
}

int command_status(const std::string& folder, std::ostream& out) {
  if (!fs::is_directory(folder)) throw InputError(folder, "", "expected a study output folder");
  const SlurmStatus status = slurm_status(folder);
  if (status.batches.empty()) out << fmt::format("{}: no Slurm submissions\n", folder);
  for (const SlurmStatus::Batch& b : status.batches)
    out << fmt::format(
        "array job {} (report job {}): {} renders: {} done, {} failed, {} not yet{}\n",
        b.array_job.empty() ? "?" : b.array_job, b.report_job.empty() ? "?" : b.report_job,
        b.renders, b.done, b.failed, b.renders - b.done - b.failed,
        b.chains > 0 ? fmt::format("; and {} ground-truth convergence chains (their renders are "
                                   "counted by the report job)",
                                   b.chains)
                     : "");
  out << (status.report_written ? fmt::format("report: {}/report.json\n", folder)
                                : std::string("report: not written yet\n"));
  return kExitOk;
}

int command_run(const RunArgs& a, std::ostream& out, std::ostream& err) {
  const Study study = load_study(a.study);
  StudyOptions o;
  o.output_dir = a.output.empty() ? "results/" + study.name : a.output;
  o.jobs =
      a.jobs > 0 ? a.jobs : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  o.timeout_s = a.timeout;
  o.max_new_renders = a.max_renders;
  o.figures = !a.no_figures;
  o.self_contained_html = a.self_contained;
  o.interrupted = &g_interrupted;
  o.dry_run = a.dry_run;
  o.max_memory_bytes = a.max_memory_gib * kGiB;
  if (a.executor == "slurm") o.slurm = slurm_options(a, o.output_dir);
  const bool tty = ::isatty(STDERR_FILENO);
  std::mutex mutex;
  if (!a.quiet && tty) {
    o.progress = [&](std::size_t done, std::size_t total, double eta) {
      std::lock_guard<std::mutex> lock(mutex);
      const int width = 30;
      const int fill =
          static_cast<int>(width * double(done) / double(std::max<std::size_t>(total, 1)));
      err << fmt::format("\r[{}{}] {}/{} renders, ETA {}   ", std::string(fill, '#'),
                         std::string(width - fill, '.'), done, total, duration_text(eta))
          << std::flush;
    };
    o.log = [&](const std::string& line) {
      if (line.find("FAILED") != std::string::npos || line.find("renders:") != std::string::npos ||
          line.find("WARNING") != std::string::npos || line.rfind("figures:", 0) == 0) {
        std::lock_guard<std::mutex> lock(mutex);
        err << "\r" << line << "\n" << std::flush;
      }
    };
  } else if (!a.quiet) {
    o.log = [&](const std::string& line) {
      std::lock_guard<std::mutex> lock(mutex);
      err << "penumbra run: " << line << "\n" << std::flush;
    };
  }
  const StopSignals stop;
  const StudyRunStats stats = run_study(study, o);
  if (a.dry_run) return print_dry_run(study, stats, o.output_dir, a.max_memory_gib, out);
  if (!a.quiet && tty) err << "\n";
  out << fmt::format(
      "study {}: {} renders ({} rendered now, {} from the cache, {} failed, {} not started) in "
      "{:.1f} s\n",
      study.name, stats.renders, stats.rendered, stats.cached, stats.failed, stats.not_started,
      stats.seconds);
  for (const std::string& f : stats.failures) out << "  failed: " << f << "\n";
  if (stats.slurm && stats.not_started > 0)
    return print_submission(*stats.slurm, o.output_dir, out);
  if (stats.not_started > 0) {
    out << fmt::format(
        "stopped before the end; run the same command again to resume (finished "
        "renders are cached in {}/cache)\n",
        o.output_dir);
    return g_interrupted.load() ? StopSignals::exit_code() : kExitFailure;
  }
  out << fmt::format("wrote {0}/report.json, {0}/metrics.csv{1}\n", o.output_dir,
                     stats.report_html.empty() ? "" : ", figures/ and report.html");
  if (!stats.report_html.empty()) out << "report: " << stats.report_html << "\n";
  return stats.failed > 0 ? kExitFailure : kExitOk;
}

int command_contour(const std::vector<std::string>& ids, double step, const std::string& output,
                    std::ostream& out) {
  std::vector<MethodSettings> methods;
  for (const std::string& id : ids) {
    const auto m = method_from_id(id);
    if (!m)
      throw UsageError(fmt::format("--method: unknown method \"{}\" (see penumbra methods)", id));
    methods.push_back({*m, 0.0});
  }
  std::error_code ec;
  fs::create_directories(output, ec);
  if (ec || !fs::is_directory(output))
    throw OutputError(fmt::format("{}: cannot create the output folder", output));
  const ContourGrid grid = make_contour_grid(methods, step);
  json methods_json = json::array();
  std::string csv = "method,light_deg,deviation_deg,G\n";
  for (std::size_t k = 0; k < methods.size(); ++k) {
    // JSON has no NaN: an undefined effective factor is null (empty in CSV).
    json rows = json::array();
    for (const auto& row : grid.g[k]) {
      json r = json::array();
      for (double g : row) r.push_back(std::isfinite(g) ? json(g) : json(nullptr));
      rows.push_back(std::move(r));
    }
    methods_json.push_back(
        {{"id", ids[k]},
         {"effective", method_info(methods[k].method).kind != MethodKind::kFactor},
         {"G", std::move(rows)}});
    for (std::size_t i = 0; i < grid.deviation_deg.size(); ++i)
      for (std::size_t j = 0; j < grid.light_deg.size(); ++j) {
        const double g = grid.g[k][i][j];
        csv += fmt::format("{},{},{},{}\n", ids[k], grid.light_deg[j], grid.deviation_deg[i],
                           std::isfinite(g) ? fmt::format("{}", g) : std::string());
      }
  }
  const json doc = {{"format", "penumbra-contour"},
                    {"version", 1},
                    {"geometry",
                     "Ng = z, wi = (sin light, 0, cos light), Ns = (sin deviation, 0, "
                     "cos deviation), wo = Ng; angles in degrees; G dimensionless; methods with "
                     "effective = true: radiance / raw bump's radiance on a white Lambertian "
                     "base, null where raw bump receives no light"},
                    {"light_deg", grid.light_deg},
                    {"deviation_deg", grid.deviation_deg},
                    {"methods", methods_json}};
  const fs::path dir(output);
  write_text_file((dir / "contour.json").string(), doc.dump(1) + "\n");
  write_text_file((dir / "contour.csv").string(), csv);
  run_plot_script(
      {"contour", fs::absolute(dir / "contour.json").string(), fs::absolute(dir).string()},
      (dir / "contour.log").string());
  out << fmt::format(
      "wrote {0}/contour.json, {0}/contour.csv and contour plots (PNG, SVG, PDF) "
      "in {0}\n",
      output);
  return kExitOk;
}

namespace {

double peak_rss_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) / 1024.0;  // Linux reports KiB
}

// User and system CPU time so far of this process (all threads), or of
// the children it waited for (RUSAGE_CHILDREN).
double cpu_seconds(int who = RUSAGE_SELF) {
  rusage usage{};
  getrusage(who, &usage);
  const auto seconds = [](const timeval& t) { return double(t.tv_sec) + 1e-6 * double(t.tv_usec); };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
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

// One line of the table: wall and CPU seconds, samples per second.
void bench_line(std::string_view label, double seconds, double cpu, double msamples, bool packets,
                std::ostream& out) {
  out << fmt::format("{:<30} {:>8} {:>8.3f} {:>8.3f} {:>14.2f} {:>17.2f}\n", label,
                     packets ? "packets" : "scalar", seconds, cpu, msamples / seconds,
                     msamples / cpu);
}

// Every method that shares its samples, rendered in one pass
// (render_methods), as a study renders the methods of a variant.
void bench_shared_pass(int size, int spp, bool packets, std::ostream& out) {
  const Scene scene = scene_from_json(bench_scene(size, spp), "<bench>");
  std::vector<TerminatorSettings> methods;
  for (const MethodInfo& m : all_methods()) {
    TerminatorSettings t = scene.terminator;
    t.method.method = m.method;
    if (shares_samples(t)) methods.push_back(t);
  }
  RenderStats stats;
  RenderOptions options;
  options.packets = packets;
  const double cpu_before = cpu_seconds();
  render_methods(scene, methods, options, &stats);
  const double cpu = cpu_seconds() - cpu_before;
  bench_line(fmt::format("{} methods, one pass", methods.size()), stats.seconds, cpu,
             double(stats.camera_samples) * double(methods.size()) / 1e6, stats.packets, out);
}

// One method's render, through the packets where they apply or the scalar path.
void bench_method(const MethodInfo& m, int size, int spp, bool packets, std::ostream& out) {
  json document = bench_scene(size, spp);
  document["terminator"] = {{"method", m.id}};
  const Scene scene = scene_from_json(document, "<bench>");
  RenderStats stats;
  RenderOptions options;
  options.packets = packets;
  const double cpu_before = cpu_seconds();
  render(scene, options, &stats);
  const double cpu = cpu_seconds() - cpu_before;
  bench_line(m.id, stats.seconds, cpu, double(stats.camera_samples) / 1e6, stats.packets, out);
}

// CPU seconds of this process and of the children it waited for (an
// external renderer's processes), so far.
double cpu_seconds_with_children() {
  return cpu_seconds() + cpu_seconds(RUSAGE_CHILDREN);
}

// One render of the bench scene as `penumbra render` makes it (render_with,
// then the EXR with the scene in its header) into `folder`: the CPU seconds
// it took, an external renderer's own processes included.
double render_cpu_seconds(RendererKind renderer, const json& document, const fs::path& folder) {
  const Scene scene = scene_from_json(document, "<bench>");
  const std::string name = to_string(renderer);
  RenderSettings settings;
  settings.log_path = (folder / (name + ".log")).string();
  settings.progress.progress = [](double) {
    if (g_interrupted.load()) throw RenderCancelled("interrupted");
  };
  const double before = cpu_seconds_with_children();
  const RendererRun run = render_with(renderer, scene, settings);
  write_exr(run.image, (folder / (name + ".exr")).string(),
            {{"penumbra:renderer", name}, {"penumbra:scene", document.dump()}});
  return cpu_seconds_with_children() - before;
}

// The evaluator against POV-Ray on the bench scene, a render of each per
// round, the two alternating so that both see the machine alike.
int bench_povray(int size, int spp, int rounds, std::ostream& out) {
  const StopSignals stop;  // Ctrl-C ends POV-Ray too; the folder is removed below
  const json document = bench_scene(size, spp);
  const fs::path folder = fs::temp_directory_path() / fmt::format("penumbra-bench-{}", ::getpid());
  fs::create_directories(folder);
  out << fmt::format(
      "penumbra bench --povray: {0}x{0}, {1} spp, bump cylinder (grating, A = 0.01), method none; "
      "CPU seconds per render, the EXR written (POV-Ray: its processes too, parsing included), {2} "
      "threads\n{3:<6} {4:>10} {5:>10} {6:>8}\n",
      size, spp, tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism),
      "round", "evaluator", "povray", "ratio");
  std::vector<double> ratios;
  try {
    for (int r = 1; r <= rounds; ++r) {
      const double evaluator = render_cpu_seconds(RendererKind::kEvaluator, document, folder);
      if (!(evaluator > 0.0))
        throw UsageError(fmt::format(
            "bench --povray: the evaluator's render took no measurable CPU time at {0}x{0}, {1} "
            "spp; give a larger --size or --spp",
            size, spp));
      const double povray = render_cpu_seconds(RendererKind::kPovray, document, folder);
      ratios.push_back(povray / evaluator);
      out << fmt::format("{:<6} {:>10.3f} {:>10.3f} {:>7.1f}x\n", r, evaluator, povray,
                         ratios.back());
    }
  } catch (...) {
    fs::remove_all(folder);
    throw;
  }
  fs::remove_all(folder);
  std::sort(ratios.begin(), ratios.end());
  const std::size_t n = ratios.size();
  const double median = n % 2 ? ratios[n / 2] : 0.5 * (ratios[n / 2 - 1] + ratios[n / 2]);
  out << fmt::format(
      "POV-Ray's CPU time over the evaluator's: {:.1f}x to {:.1f}x, median {:.1f}x\n",
      ratios.front(), ratios.back(), median);
  return kExitOk;
}

}  // namespace

int command_bench(int size, int spp, int povray_rounds, std::ostream& out) {
  if (povray_rounds > 0) return bench_povray(size, spp, povray_rounds, out);
  out << fmt::format(
      "penumbra bench: {}x{}, {} spp, bump cylinder (grating, A = 0.01), {} threads, packets on "
      "{}\n",
      size, size, spp,
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism),
      packet_target());
  out << fmt::format("{:<30} {:>8} {:>8} {:>8} {:>14} {:>17}\n", "method", "path", "wall s",
                     "CPU s", "M samples/s", "M samples/CPU-s");
  for (const MethodInfo& m : all_methods()) bench_method(m, size, spp, true, out);
  bench_shared_pass(size, spp, true, out);
  out << "  (one pass: each camera sample counted once per method, as separate renders would "
         "count it)\nthe scalar path, for comparison (same bits):\n";
  bench_method(all_methods().front(), size, spp, false, out);
  bench_shared_pass(size, spp, false, out);
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

namespace {

MapEdge parse_edge(const PyramidArgs& a) {
  for (const EnumName<MapEdge>& e : kMapEdgeNames)
    if (a.edge == e.name) return e.value;
  throw UsageError(fmt::format("--edge: expected wrap or clamp, got \"{}\"", a.edge));
}

// The edge mode, after checking the map options CLI11 cannot.
MapEdge check_map_args(const PyramidArgs& a) {
  const MapEdge edge = parse_edge(a);
  if (!std::isfinite(a.height_scale))
    throw UsageError(
        fmt::format("--height-scale: expected a finite number, got {}", a.height_scale));
  return edge;
}

}  // namespace

int command_pyramid(const PyramidArgs& a, std::ostream& out) {
  const MapEdge edge = check_map_args(a);
  const auto start = std::chrono::steady_clock::now();
  const HeightMap map = read_height_map(a.heights, a.channel);
  const double texel_size = a.texel_size > 0.0 ? a.texel_size : 1.0 / map.width;
  const auto read = std::chrono::steady_clock::now();
  const std::vector<PyramidLevel> levels = build_bump_pyramid(
      offsets_from_heights(map.heights, map.width, map.height, texel_size, a.height_scale, edge));
  const auto built = std::chrono::steady_clock::now();
  write_pyramid(levels, {a.heights, map.channel, texel_size, a.height_scale, edge}, a.output);
  const auto written = std::chrono::steady_clock::now();
  if (a.quiet) return kExitOk;
  const auto seconds = [](auto from, auto to) {
    return std::chrono::duration<double>(to - from).count();
  };
  const PyramidLevel& top = levels.back();
  const Covariance2 k = top.covariance(0, 0);
  out << fmt::format(
      "{} (channel {}, {}x{} texels, texel {:.6g} scene units, heights x {:.6g}, edge {}): "
      "{} levels in {}\n",
      a.heights, map.channel, map.width, map.height, texel_size, a.height_scale, a.edge,
      levels.size(), a.output);
  out << fmt::format(
      "whole map (level {}): mean offset ({:.6g}, {:.6g}), slope standard deviations "
      "sqrt(K_uu) {:.6g}, sqrt(K_vv) {:.6g}, lambda1 {:.6g} (slopes, dimensionless); "
      "mean normal length {:.6f}\n",
      levels.size() - 1, top.f_u[0], top.f_v[0], std::sqrt(k.a), std::sqrt(k.c),
      isotropic_roughness(k), length(top.mean_normal(0, 0)));
  out << fmt::format(
      "read {:.3f} s, built {:.3f} s (1 thread), written {:.3f} s; peak RSS {:.0f} MiB\n",
      seconds(start, read), seconds(read, built), seconds(built, written), peak_rss_mib());
  return kExitOk;
}

namespace {

FilteringOptions filtering_options(const FilteringArgs& a) {
  FilteringOptions o;
  if (!a.alphas.empty()) o.alphas = a.alphas;
  for (const std::string& id : a.filters) {
    const auto f = roughness_filter_from_id(id);
    if (!f)
      throw UsageError(
          fmt::format("--filter: unknown roughness filter \"{}\" (see penumbra methods)", id));
    if (!is_measurable(*f))
      throw UsageError(fmt::format(
          "--filter: {} has no normalised BRDF in its source, so it cannot be measured", id));
    o.filters.push_back(*f);
  }
  for (double alpha : o.alphas)
    if (!(alpha > 0.0 && alpha <= 1.0))
      throw UsageError(fmt::format("--alpha: expected a GGX alpha in (0, 1], got {}", alpha));
  o.max_level = a.max_level;
  o.footprints = a.footprints;
  o.view_deg = a.view_deg;
  o.sweep_step_deg = a.sweep_step_deg;
  if (a.shift == "random") {
    o.random_shift = true;
  } else {
    std::size_t used = 0;
    double shift = -1.0;
    try {
      shift = std::stod(a.shift, &used);
    } catch (const std::exception&) {
    }
    if (used != a.shift.size() || !(shift >= 0.0 && shift < 1.0))
      throw UsageError(fmt::format(
          "--shift: expected a number of pixels in [0, 1) or \"random\", got \"{}\"", a.shift));
    o.shift = shift;
  }
  o.lookup = a.lookup == "trilinear" ? FilteringOptions::Lookup::kTrilinear
                                     : FilteringOptions::Lookup::kBox;
  o.jobs = a.jobs > 0 ? a.jobs : int(std::max(1u, std::thread::hardware_concurrency()));
  return o;
}

}  // namespace

int command_filtering(const FilteringArgs& a, std::ostream& out, std::ostream& err) {
  const MapEdge edge = check_map_args(a.map);
  const FilteringOptions options = filtering_options(a);
  const HeightMap map = read_height_map(a.map.heights, a.map.channel);
  std::error_code ec;
  fs::create_directories(a.map.output, ec);
  check_writable((fs::path(a.map.output) / "filtering.json").string());
  const double texel_size = a.map.texel_size > 0.0 ? a.map.texel_size : 1.0 / map.width;
  const std::vector<PyramidLevel> pyramid = build_bump_pyramid(offsets_from_heights(
      map.heights, map.width, map.height, texel_size, a.map.height_scale, edge));
  const auto start = std::chrono::steady_clock::now();
  std::size_t reported = 0;
  const FilteringResult result =
      run_filtering_experiment(pyramid, options, [&](std::size_t done, std::size_t total) {
        if (a.map.quiet || done * 10 / total == reported) return;
        reported = done * 10 / total;
        err << fmt::format("filtering: {}/{} footprints measured\n", done, total);
      });
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const FilteringSource source{a.map.heights, map.channel,        map.width, map.height,
                               texel_size,    a.map.height_scale, a.map.edge};
  write_text_file((fs::path(a.map.output) / "filtering.csv").string(), filtering_csv(result));
  const std::string json_path = (fs::path(a.map.output) / "filtering.json").string();
  write_text_file(json_path, filtering_json(result, options, source) + "\n");
  run_plot_script(
      {"filtering", fs::absolute(json_path).string(), fs::absolute(a.map.output).string()},
      (fs::path(a.map.output) / "filtering.log").string());
  if (a.map.quiet) return kExitOk;
  out << fmt::format("{} footprints over {} levels, {} filters x {} alphas, in {:.1f} s\n",
                     result.footprints, result.levels, result.filters.size(), options.alphas.size(),
                     seconds);
  for (const std::string& line : filtering_findings(result)) out << line << "\n";
  out << fmt::format(
      "wrote {0}/filtering.json, {0}/filtering.csv and {0}/filtering-*.{{png,svg,pdf}}\n",
      a.map.output);
  return kExitOk;
}

namespace {

// --on shape: the map over the shape's (u, v), texels as square as the
// parameterisation allows (on the sphere, at the equator).
int bake_on_shape(const BakeArgs& a, const Scene& scene, std::ostream& out) {
  const Shape& s = scene.shape;
  const int rows = shape_map_rows(s, a.size, kMaxImageSize);
  const MapKind kind = a.kind == "normal" ? MapKind::kNormal : MapKind::kHeight;
  const Image map =
      bake_surface_map(s, scene.height.function, scene.height.amplitude, a.size, rows, kind);
  write_exr(map, a.output, {{"penumbra:baked_from", a.scene}});
  const std::string use =
      kind == MapKind::kHeight
          ? fmt::format(R"({{"type": "height-map", "file": "{}", "amplitude": 1}})", a.output)
          : fmt::format(R"({{"type": "normal-map", "file": "{}"}})", a.output);
  out << fmt::format("wrote {} ({}x{} over the {}'s (u, v)): use it as /height = {}\n", a.output,
                     a.size, rows, name_of<ShapeType>(kShapeTypeNames, s.type), use);
  return kExitOk;
}

}  // namespace

int command_bake(const BakeArgs& a, std::ostream& out) {
  SceneArgs scene_args;
  scene_args.sets = a.sets;
  const std::vector<Override> overrides = collect_overrides(scene_args);
  json document = read_json_file(a.scene);
  resolve_map_files(document, a.scene);
  const std::string origin = overrides.empty() ? a.scene : a.scene + " (after --set)";
  apply_overrides(document, overrides, origin);
  const Scene scene = scene_from_json(document, origin);
  if (scene.height.family == HeightFamily::kNone || scene.height.map)
    throw InputError(origin, "/height",
                     fmt::format("expected an analytic height function to bake, got \"{}\"",
                                 to_string(scene.height.family)));
  check_extension(a.output, ".exr", "-o", ": a baked map is float OpenEXR");
  if (a.kind == "normal" && a.on != "shape")
    throw InputError("--kind", "", "a normal map is baked over a shape: add --on shape");
  check_writable(a.output);
  if (a.on == "shape") return bake_on_shape(a, scene, out);
  const Image map =
      bake_height_map(scene.height.function, scene.height.amplitude, a.size, a.extent);
  write_exr(map, a.output, {{"penumbra:baked_from", a.scene}});
  const double texel = a.extent / a.size;
  out << fmt::format(
      "wrote {} ({}x{}, heights in scene units, texel {:.6g} scene units): use penumbra pyramid "
      "{} --texel-size {:.6g} --edge {}\n",
      a.output, a.size, a.size, texel, a.output, texel,
      "wrap (if the extent holds whole periods) or clamp");
  return kExitOk;
}

}  // namespace penumbra
