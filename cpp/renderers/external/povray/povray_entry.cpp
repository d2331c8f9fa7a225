// POV-Ray's row of the renderer table and its entry. Not in POV-Ray's part
// of the cache key: nothing here changes a pixel.
#include <filesystem>

#include <fmt/format.h>

#include "renderers/code_digest.h"
#include "renderers/external/external.h"
#include "renderers/external/povray/povray.h"

namespace penumbra {

namespace {

std::string povray_code_digest(const RenderSettings&) {
  return fmt::format("{}-{}", build_code_digests().evaluator, external_code_digest("povray"));
}

// The supersampled RGBA image POV-Ray writes and Penumbra reads back (the
// export's strata, without building its SDL: a displaced grid is large).
ResourceEstimate povray_resources(const Scene& scene) {
  int sx = 1, sy = 1;
  strata(scene.camera.spp, &sx, &sy);
  const double pixels = double(scene.camera.width) * double(scene.camera.height);
  return estimate_render_resources(scene, pixels * sx * sy * 4 * 4 * 2, false);
}

std::string export_povray_files(const Scene& scene, const std::string& folder) {
  const PovrayExport job = export_povray(scene);
  const std::string path = (std::filesystem::path(folder) / kPovraySceneFile).string();
  write_povray_files(job, folder);
  return fmt::format(
      "wrote {}{} (render {}x{} without anti-aliasing, box-filter {}x{} down to "
      "{}x{}; the command line is in its first lines)\n",
      path, job.map.pixels.empty() ? "" : std::string(" and its ") + kPovrayMapFile,
      job.width * job.supersample_x, job.height * job.supersample_y, job.supersample_x,
      job.supersample_y, job.width, job.height);
}

}  // namespace

const RendererEntry& povray_entry() {
  static const RendererEntry entry{
      .info = {.id = "povray",
               .name = "POV-Ray 3.7",
               .debian_package = "povray",
               .executable = "povray",
               .executable_variable = "PENUMBRA_POVRAY",
               .version_marker = "POV-Ray 3",
               .note = "POV-Ray 3.7: bump via normal{function} (image height maps: the same cubic "
                       "B-spline as SDL functions over nearest-texel lookups), ground truth via "
                       "isosurface (image maps, the plane and mesh shapes: the evaluator's "
                       "displaced mesh as a mesh2; no bump on a mesh shape)",
               .bump_methods = {TerminatorMethod::kNone},
               .other_methods = {TerminatorMethod::kNone},
               .methods_why_not = "POV-Ray has no shadow-terminator method (raw bump only)",
               .offsets = {OffsetMethod::kNone},
               .offsets_why_not = "POV-Ray 3.7 has no shadow-ray offset: mesh2 with "
                                  "normal_vectors shows the artifact (shadow line artifact, "
                                  "FS#242)",
               .props_why_not = "props (extra spheres) are evaluator-only",
               .specular_why_not = "the GGX lobe is evaluator-only: the POV-Ray export is "
                                   "Lambertian (its specular and phong highlights are other "
                                   "models)",
               .height_maps = true,
               .normal_maps_why_not = "POV-Ray 3.7 has no tangent-space normal-map input: its "
                                      "normal patterns perturb the normal by the gradient of a "
                                      "scalar function, which a normal map does not give",
               .plane = true,
               .consistent_normals_why_not = "POV-Ray 3.7 interpolates mesh2 normal_vectors "
                                             "linearly; it has no view-dependent shading normal",
               .mesh_bump_why_not = "POV-Ray's bump pattern differentiates h in 3D around the "
                                    "hit, where the evaluator and Cycles differentiate it over "
                                    "a mesh's flat triangle; a mesh shape's smooth and "
                                    "displacement representations are exported"},
      .render = render_povray,
      .version = external::probe_version,
      .pixel_code_digest = povray_code_digest,
      .estimate_resources = povray_resources,
      .export_files = export_povray_files,
      .export_file = kPovraySceneFile,
      // Measured as study/cost.cpp says.
      .costs = {{Representation::kSmooth, false, {0.5, 4.55, 0.0}},  // as bump
                {Representation::kSmooth, true, {0.5, 3.78, 0.0}},
                {Representation::kBump, false, {0.5, 4.55, 0.0}},
                {Representation::kBump, true, {0.5, 4.55, 0.0}},  // as bump
                {Representation::kDisplacement, false, {0.8, 54.3, 0.0}},
                {Representation::kDisplacement, true, {0.8, 54.3, 0.0}}}};
  return entry;
}

}  // namespace penumbra
