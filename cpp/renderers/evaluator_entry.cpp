// The evaluator's row and entry. Its render is render_evaluator
// (renderers/renderers.h); nothing here is in a cache key's code digest
// but the digest itself.
#include "renderers/evaluator_entry.h"

#include "renderers/code_digest.h"
#include "renderers/renderers.h"
#include "util/version.h"

namespace penumbra {

namespace {

std::string evaluator_version(const RendererInfo&, const RenderSettings&) {
  return std::string("penumbra ") + kPenumbraVersion;
}

std::string evaluator_code_digest(const RenderSettings&) {
  return build_code_digests().evaluator;
}

ResourceEstimate evaluator_resources(const Scene& scene) {
  return estimate_render_resources(scene, 0.0, false);
}

}  // namespace

const RendererEntry& evaluator_entry() {
  static const RendererEntry entry{
      .info = {.id = "evaluator",
               .name = "Penumbra's reference evaluator",
               .version_marker = "penumbra",
               .note = "reference evaluator: analytic shapes, exact displaced normals",
               .all_methods = true,
               .all_offsets = true,
               .props = true,
               .specular = true,
               .height_maps = true,
               .normal_maps = true,
               .plane = true,
               .consistent_normals = true,
               .mesh_bump = true},
      .render = render_evaluator,
      .version = evaluator_version,
      .pixel_code_digest = evaluator_code_digest,
      .estimate_resources = evaluator_resources,
      // Measured as study/cost.cpp says.
      .costs = {{Representation::kSmooth, false, {0.01, 0.144, 0.0}},  // as bump
                {Representation::kSmooth, true, {0.01, 0.248, 0.0}},
                {Representation::kBump, false, {0.01, 0.144, 0.0}},
                {Representation::kBump, true, {0.01, 0.248, 0.0}},  // as smooth
                {Representation::kDisplacement, false, {0.05, 0.8, 0.12}},
                {Representation::kDisplacement, true, {0.05, 0.8, 0.12}}}};
  return entry;
}

}  // namespace penumbra
