// Blender's row of the renderer table and its entry. Not in Blender's part
// of the cache key: nothing here changes a pixel.
#include <filesystem>
#include <fstream>
#include <iterator>

#include <fmt/format.h>

#include "renderers/code_digest.h"
#include "renderers/external/blender/blender.h"
#include "renderers/external/external.h"
#include "util/data_files.h"
#include "util/hash.h"

namespace penumbra {

namespace {

// The script is read when it is used, so that editing it makes exactly the
// Blender entries stale.
std::string blender_code_digest(const RenderSettings& settings) {
  const std::string script = blender_script(settings);
  std::ifstream in(script, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in && !in.eof()) throw RendererError(fmt::format("blender: cannot read {}", script));
  return fmt::format("{}-{}-{:016x}", build_code_digests().evaluator,
                     external_code_digest("blender"), fnv1a(text));
}

// Blender renders even the analytic shapes as meshes (fine grids).
ResourceEstimate blender_resources(const Scene& scene) {
  return estimate_render_resources(scene, 0.0, true);
}

std::string export_blender_files(const Scene& scene, const std::string& folder) {
  const BlenderExport job = export_blender(scene);
  const std::filesystem::path dir(folder);
  const TriangleMesh& m = job.mesh;
  write_blender_files(job, dir.string());
  return fmt::format(
      "wrote {} and its mesh ({} vertices, {} triangles); render with\n  blender -b -t 1 "
      "--factory-startup -noaudio --python-exit-code 1 --python {} -- "
      "{} out.exr\n",
      (dir / kBlenderJobFile).string(), m.vertex_count(), m.triangle_count(),
      data_file("harness/blender_render.py"), (dir / kBlenderJobFile).string());
}

}  // namespace

const RendererEntry& blender_entry() {
  static const RendererEntry entry{
      .info =
          {.id = "blender",
           .name = "Blender 3.4 Cycles",
           .debian_package = "blender",
           .executable = "blender",
           .executable_variable = "PENUMBRA_BLENDER",
           .version_marker = "Blender ",
           .note =
               "Blender 3.4 Cycles: bump via ray-differential finite differences, ground "
               "truth via a displaced mesh (a mesh shape's: the evaluator's subdivision; "
               "a mesh's bump differentiates h over the flat triangle, as the evaluator's does, "
               "and its normal maps are the Normal Map node in Blender's MikkTSpace frame); its "
               "chiang2019 is the Bump node, which is "
               "cycles34 (Chiang's term against Ni after ensure_valid_reflection turns "
               "the bumped normal towards Ng at grazing views); both ids render the same "
               "Blender scene",
           .bump_methods = {TerminatorMethod::kNone, TerminatorMethod::kChiang2019,
                            TerminatorMethod::kCycles34, TerminatorMethod::kShadingOffset},
           .other_methods = {TerminatorMethod::kNone, TerminatorMethod::kShadingOffset},
           .methods_why_not = "Blender Cycles 3.4 offers only none, chiang2019 and cycles34 "
                              "(both the Bump node: Cycles 3.4's own term) and "
                              "shading-offset",
           .offsets = {OffsetMethod::kNone, OffsetMethod::kCyclesGeometryOffset},
           .offsets_why_not = "Blender Cycles 3.4 offers only its geometry offset",
           .props_why_not = "props (extra spheres) are evaluator-only",
           .specular_why_not = "the GGX lobe is evaluator-only: the Blender export is "
                               "Lambertian (Cycles' Glossy BSDF uses Fresnel and "
                               "multiple-scattering options the evaluator does not model)",
           .height_maps = true,
           .normal_maps = true,
           .plane = true,
           .consistent_normals_why_not = "Cycles interpolates a smooth mesh's normals "
                                         "linearly; it has no consistent normal interpolation",
           .mesh_bump = true,
           .reference_ni_methods = {TerminatorMethod::kChiang2019}},
      .render = render_blender,
      .version = external::probe_version,
      .pixel_code_digest = blender_code_digest,
      .estimate_resources = blender_resources,
      .export_files = export_blender_files,
      .export_file = kBlenderJobFile,
      // Measured as study/cost.cpp says.
      .costs = {{Representation::kSmooth, false, {0.3, 2.42, 0.0}},  // as bump
                {Representation::kSmooth, true, {0.3, 1.08, 0.0}},
                {Representation::kBump, false, {0.3, 2.42, 0.0}},
                {Representation::kBump, true, {0.3, 2.42, 0.0}},  // as bump
                {Representation::kDisplacement, false, {1.0, 2.0, 1.5}},
                {Representation::kDisplacement, true, {1.0, 2.0, 1.5}}},
      // A serving Blender (blender_sessions.h), started once per worker.
      .start_seconds = 5.0};
  return entry;
}

}  // namespace penumbra
