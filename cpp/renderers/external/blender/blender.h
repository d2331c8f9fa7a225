// Blender 3.4 Cycles: its exporter (a JSON job and a mesh, read by the fixed
// script harness/blender_render.py), its driver (render the job in a Blender
// process of its own or a serving one, blender_sessions.h) and its entry
// (renderers/renderer.h). No string from the scene file reaches the job.
#pragma once

#include <string>
#include <vector>

#include "core/grid_mesh.h"
#include "image/image.h"
#include "renderers/renderer.h"
#include "scene/scene.h"

namespace penumbra {

// What the fixed script is asked to build (see harness/blender_render.py).
enum class BlenderShading {
  kSmooth,            // base mesh, no height
  kBumpDisplacement,  // raw bump through the material's Displacement socket
  kBumpNode,          // Bump node into the BSDF normal: cycles34 (chiang2019 with Ni)
  kMesh,              // the mesh is already displaced (ground truth)
};

struct BlenderExport {
  std::string job_json;  // the job file's text
  TriangleMesh mesh;     // in Blender coordinates, written beside the job
  BlenderShading shading = BlenderShading::kSmooth;
  // Image maps: the map's (u, v) times its tiling at each triangle corner
  // (kBlenderUvsFile, 2 floats a corner) and the map itself (kBlenderMapFile).
  std::vector<float> uvs;
  Image map;  // empty without a map
  // An environment light's radiance as Blender's world reads it
  // (kBlenderEnvironmentFile, R = G = B), before its scale.
  Image environment;
};

// Methods Blender provides for each representation: smooth and displacement
// take `none` or `shading-offset`; bump takes `none`, `chiang2019` or `cycles34` (Bump
// node) and `shading-offset` (object setting, on raw bump). A tessellated
// shape is sent as its low-poly mesh, smooth or flat faces. The object's
// Geometry Offset is the scene's cycles-geometry-offset cutoff, else 0 (not
// Cycles' default 0.1): offset `none`, as on the fine grids that stand in for
// the analytic shapes.
BlenderExport export_blender(const Scene& scene);
// The most height terms the Blender script accepts (MAX_TERMS in
// harness/blender_render.py; a test checks the two agree).
inline constexpr std::size_t kBlenderMaxHeightTerms = 32;
// File names the job refers to (fixed: never derived from scene values).
inline constexpr const char* kBlenderJobFile = "job.json";
inline constexpr const char* kBlenderPositionsFile = "positions.f32";
inline constexpr const char* kBlenderNormalsFile = "normals.f32";
inline constexpr const char* kBlenderTrianglesFile = "triangles.u32";
inline constexpr const char* kBlenderUvsFile = "uvs.f32";
inline constexpr const char* kBlenderMapFile = "map.exr";
inline constexpr const char* kBlenderEnvironmentFile = "environment.exr";

// Writes an export's files into `folder` (which must exist): the job, the
// mesh, and for image maps the UVs and the map.
void write_blender_files(const BlenderExport& job, const std::string& folder);

// POV-Ray/Penumbra coordinates (left-handed, y up) to Blender's
// (right-handed, z up): swap y and z.
inline Vec3 to_blender(const Vec3& p) {
  return {p.x, p.z, p.y};
}

// The Blender harness script, absolute; RendererError if it is missing.
std::string blender_script(const RenderSettings& s);

// Exports `scene` and renders the job with the script: the entry's render.
RendererRun render_blender(const Scene& scene, const RenderSettings& settings);

const RendererEntry& blender_entry();

}  // namespace penumbra
