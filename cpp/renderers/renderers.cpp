#include "renderers/renderers.h"

#include <fmt/format.h>

#include "renderers/evaluator_entry.h"
#include "renderers/external/external.h"
#include "util/process.h"

namespace penumbra {

namespace {

// What every renderer must return before it is used or cached: the scene's
// size, R G B A, and finite values in every channel.
void check_output(const RendererInfo& info, const Image& image, const Scene& scene) {
  if (image.width != scene.camera.width || image.height != scene.camera.height)
    throw RendererError(fmt::format("{} returned a {}x{} image, expected {}x{}", info.id,
                                    image.width, image.height, scene.camera.width,
                                    scene.camera.height));
  for (const char* name : {"R", "G", "B", "A"})
    if (image.channel_index(name) < 0)
      throw RendererError(fmt::format("{} returned no {} channel", info.id, name));
  const std::size_t bad = count_nonfinite(image);
  if (bad > 0)
    throw RendererError(
        fmt::format("{} returned {} NaN or Inf values (of {}); the image is not used or cached",
                    info.id, bad, image.pixels.size()));
}

// A pass's images, each checked as render_with checks one: errors[k] says
// why image k cannot be used (its scene: scene_of(k)).
template <typename SceneOf>
MethodsRun checked_pass(std::vector<Image> images, const RenderStats& stats, SceneOf scene_of) {
  MethodsRun run;
  run.images = std::move(images);
  run.seconds = stats.seconds;
  run.stats = stats;
  run.errors.resize(run.images.size());
  for (std::size_t k = 0; k < run.images.size(); ++k) {
    try {
      check_output(evaluator_entry().info, run.images[k], scene_of(k));
    } catch (const RendererError& e) {
      run.errors[k] = e.what();
    }
  }
  return run;
}

}  // namespace

RendererRun render_with(RendererKind r, const Scene& scene, const RenderSettings& settings) {
  if (processes_cancelled()) throw RenderCancelled("not started (interrupted)");
  const RendererEntry& entry = renderer(r);
  RendererRun run = entry.render(scene, settings);
  check_output(entry.info, run.image, scene);
  return run;
}

RendererRun render_evaluator(const Scene& scene, const RenderSettings& settings) {
  RendererRun run;
  run.image = render(scene, settings.progress, &run.stats);
  run.seconds = run.stats.seconds;
  return run;
}

MethodsRun render_evaluator_methods(const Scene& scene,
                                    const std::vector<TerminatorSettings>& methods,
                                    const RenderSettings& settings) {
  if (processes_cancelled()) throw RenderCancelled("not started (interrupted)");
  RenderStats stats;
  std::vector<Image> images = render_methods(scene, methods, settings.progress, &stats);
  return checked_pass(std::move(images), stats, [&](std::size_t) -> const Scene& { return scene; });
}

MethodsRun render_evaluator_lightings(const std::vector<Scene>& scenes,
                                      const RenderSettings& settings) {
  if (processes_cancelled()) throw RenderCancelled("not started (interrupted)");
  RenderStats stats;
  std::vector<Image> images = render_lightings(scenes, settings.progress, &stats);
  return checked_pass(std::move(images), stats,
                      [&](std::size_t k) -> const Scene& { return scenes[k]; });
}

std::string pixel_code_digest(RendererKind r, const RenderSettings& settings) {
  return renderer(r).pixel_code_digest(settings);
}

std::string renderer_version(RendererKind r, const RenderSettings& settings) {
  return renderer(r).version(renderer_info(r), settings);
}

std::string renderer_executable(RendererKind r, const RenderSettings& settings) {
  const RendererInfo& info = renderer_info(r);
  return info.external() ? external::executable_for(info, settings) : std::string();
}

ResourceEstimate estimate_resources(RendererKind r, const Scene& scene) {
  return renderer(r).estimate_resources(scene);
}

}  // namespace penumbra
