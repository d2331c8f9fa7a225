// What the study and the command line call to render: each call goes to the
// renderer's entry (renderers/renderer.h) through the registry
// (renderers/registry.h), so no caller switches over renderers.
#pragma once

#include <string>
#include <vector>

#include "renderers/registry.h"
#include "renderers/renderer.h"

namespace penumbra {

// Renders `scene` with `renderer`. Throws ExportError (the scene cannot be
// expressed: bad input) or RendererError (the renderer failed, or returned an
// image of the wrong size, without R G B A, or with NaN or Inf values).
RendererRun render_with(RendererKind renderer, const Scene& scene, const RenderSettings& settings);

// The evaluator's render of `scene`: the evaluator's entry, and the geometry
// pass that gives an external renderer's image its analysis channels.
RendererRun render_evaluator(const Scene& scene, const RenderSettings& settings);

// The evaluator's renders of `scene` with each of `methods` in one pass
// (render_methods, evaluator/evaluator.h): images[k] has the bits render_with
// gives for methods[k]; errors[k] says why it cannot be used (NaN or Inf
// values, as render_with would throw), "" when it can.
struct MethodsRun {
  std::vector<Image> images;
  std::vector<std::string> errors;
  double seconds = 0.0;  // wall time of the whole pass
  RenderStats stats;     // the whole pass's (its mesh built once)
};
MethodsRun render_evaluator_methods(const Scene& scene,
                                    const std::vector<TerminatorSettings>& methods,
                                    const RenderSettings& settings);

// The evaluator's displacement truths of `scenes` in one pass
// (render_lightings, evaluator/evaluator.h): the scenes must differ only in
// their light, material and terminator, which the caller checks
// (study/rendering.h groups them by their JSON without those); images[k] has
// the bits render_with gives for scenes[k], errors[k] as above.
MethodsRun render_evaluator_lightings(const std::vector<Scene>& scenes,
                                      const RenderSettings& settings);

// A digest of the code and scripts that produce `renderer`'s pixels (see
// renderers/code_digest.h); part of cache keys. For Blender it covers the
// script that settings (or PENUMBRA_BLENDER_SCRIPT) select.
std::string pixel_code_digest(RendererKind renderer, const RenderSettings& settings);

// "POV-Ray 3.7.0.10" / "Blender 3.4.1" / "penumbra 0.3.0": the first line
// the renderer prints for --version; part of cache keys. The probe is killed
// after min(60 s, settings.timeout_s).
std::string renderer_version(RendererKind renderer, const RenderSettings& settings);

// The executable `renderer` runs (settings, the PENUMBRA_* variable, then
// PATH); RendererError naming the Debian package when there is none. Empty
// for the evaluator.
std::string renderer_executable(RendererKind renderer, const RenderSettings& settings);

ResourceEstimate estimate_resources(RendererKind renderer, const Scene& scene);

}  // namespace penumbra
