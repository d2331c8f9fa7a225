#include "study/bench.h"

#include <chrono>
#include <filesystem>

#include <fmt/format.h>

#include "core/tessellation.h"
#include "core/vec.h"
#include "evaluator/evaluator.h"
#include "image/image_io.h"
#include "renderers/renderers.h"
#include "scene/mesh_file.h"
#include "scene/scene_json.h"
#include "util/resource_usage.h"

namespace penumbra {

namespace fs = std::filesystem;

nlohmann::json bench_scene(int size, int spp) {
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

BenchTiming bench_method(const MethodInfo& method, int size, int spp, bool packets) {
  nlohmann::json document = bench_scene(size, spp);
  document["terminator"] = {{"method", method.id}};
  const Scene scene = scene_from_json(document, "<bench>");
  RenderStats stats;
  RenderOptions options;
  options.packets = packets;
  const double cpu_before = cpu_seconds();
  render(scene, options, &stats);
  const double cpu = cpu_seconds() - cpu_before;
  return {std::string(method.id), stats.packets, stats.seconds, cpu,
          double(stats.camera_samples) / 1e6};
}

BenchTiming bench_shared_pass(int size, int spp, bool packets) {
  const Scene scene = scene_from_json(bench_scene(size, spp), "<bench>");
  std::vector<TerminatorSettings> methods;
  for (const MethodInfo& m : all_methods()) {
    TerminatorSettings t = scene.terminator;
    t.method.method = m.method;
    if (shares_samples(t) && !m.needs_table && !m.user_defined) methods.push_back(t);
  }
  RenderStats stats;
  RenderOptions options;
  options.packets = packets;
  const double cpu_before = cpu_seconds();
  render_methods(scene, methods, options, &stats);
  const double cpu = cpu_seconds() - cpu_before;
  return {fmt::format("{} methods, one pass", methods.size()), stats.packets, stats.seconds, cpu,
          double(stats.camera_samples) * double(methods.size()) / 1e6};
}

DisplacementTiming bench_displacement(int size, int spp) {
  DisplacementTiming t;
  t.peak_rss_mib_before = peak_rss_mib();
  nlohmann::json document = bench_scene(size, spp);
  document["representation"] = "displacement";
  const Scene scene = scene_from_json(document, "<bench>");
  RenderStats stats;
  render(scene, {}, &stats);
  t.edge_length = scene.displacement.edge_length;
  t.triangles = stats.triangles;
  t.build_seconds = stats.build_seconds;
  t.seconds = stats.seconds;
  t.msamples_per_second = double(stats.camera_samples) / stats.seconds / 1e6;
  t.peak_rss_mib = peak_rss_mib();
  return t;
}

SharedTruthTiming bench_shared_truths(int size, int spp) {
  SharedTruthTiming t;
  std::vector<Scene> scenes;
  for (const nlohmann::json& direction :
       {nlohmann::json{-1, 0, -1.2}, nlohmann::json{-1, 0, -0.2}, nlohmann::json{-1, 0, 0.4}})
    for (const double specular : {0.0, 0.4}) {
      nlohmann::json document = bench_scene(size, spp);
      document["representation"] = "displacement";
      document["light"]["direction"] = direction;
      document["material"]["specular"] = {{"weight", specular}, {"roughness", 0.3}};
      scenes.push_back(scene_from_json(document, "<bench>"));
    }
  t.lightings = scenes.size();
  // Both from the process's mesh cache (bench_displacement built the mesh),
  // so that the ratio is the rays', as in a study whose truths share a mesh.
  double cpu_before = cpu_seconds();
  for (const Scene& scene : scenes) {
    RenderStats stats;
    render(scene, {}, &stats);
    t.alone_seconds += stats.seconds;
  }
  t.alone_cpu_seconds = cpu_seconds() - cpu_before;
  cpu_before = cpu_seconds();
  RenderStats stats;
  render_lightings(scenes, {}, &stats);
  t.pass_seconds = stats.seconds;
  t.pass_cpu_seconds = cpu_seconds() - cpu_before;
  return t;
}

ExtendedTruthTiming bench_extended_truth(int size, int spp) {
  ExtendedTruthTiming t;
  t.spp = spp, t.extended_spp = 4 * spp;
  t.nested = nests(spp, t.extended_spp);
  if (!t.nested) return t;
  const auto truth = [&](int samples) {
    nlohmann::json document = bench_scene(size, samples);
    document["representation"] = "displacement";
    document["camera"]["jitter"] = true;  // a grid of stratum centres does not nest
    return scene_from_json(document, "<bench>");
  };
  std::vector<SampleSums> sums;
  RenderOptions keep;
  keep.sums = &sums;
  render(truth(spp), keep);
  double cpu_before = cpu_seconds();
  render(truth(t.extended_spp));
  t.scratch_cpu_seconds = cpu_seconds() - cpu_before;
  RenderOptions extend;
  extend.resume = &sums;
  cpu_before = cpu_seconds();
  render(truth(t.extended_spp), extend);
  t.extended_cpu_seconds = cpu_seconds() - cpu_before;
  return t;
}

MeshFileTiming bench_mesh_file(int size, int spp, const std::string& folder) {
  MeshFileTiming t;
  Shape sphere;
  sphere.type = ShapeType::kSphere;
  Tessellation uv;
  uv.segments = 1024;
  const std::string file = (fs::path(folder) / "sphere-1024.ply").string();
  write_mesh_file(tessellate(with_frame(sphere), uv), file, "penumbra bench: a 1M-triangle mesh");
  t.file_mib = double(fs::file_size(file)) / (1024.0 * 1024.0);
  t.rss_mib_before = current_rss_mib();
  const auto start = std::chrono::steady_clock::now();
  const LoadedMesh mesh = load_mesh_file(file, {}, MeshNormals::kFile);
  t.read_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  t.rss_mib_read = current_rss_mib();
  t.triangles = mesh.surface->mesh.triangle_count();
  nlohmann::json document = bench_scene(size, spp);
  document["shape"] = {{"type", "mesh"}, {"file", file}};
  RenderStats stats;
  render(scene_from_json(document, "<bench>"), {}, &stats);  // the mesh read above, from memory
  t.build_seconds = stats.build_seconds;
  t.seconds = stats.seconds;
  t.msamples_per_second = double(stats.camera_samples) / stats.seconds / 1e6;
  t.peak_rss_mib = peak_rss_mib();
  return t;
}

double render_cpu_seconds(RendererKind renderer, const nlohmann::json& document,
                          const std::string& folder, int threads,
                          const std::atomic<bool>& interrupted) {
  const Scene scene = scene_from_json(document, "<bench>");
  const std::string name = to_string(renderer);
  RenderSettings settings;
  settings.threads = threads;
  settings.log_path = (fs::path(folder) / (name + ".log")).string();
  settings.progress.progress = [&interrupted](double) {
    if (interrupted.load()) throw RenderCancelled("interrupted");
  };
  const double before = cpu_seconds_with_children();
  const RendererRun run = render_with(renderer, scene, settings);
  write_exr(run.image, (fs::path(folder) / (name + ".exr")).string(),
            {{"penumbra:renderer", name}, {"penumbra:scene", document.dump()}});
  return cpu_seconds_with_children() - before;
}

}  // namespace penumbra
