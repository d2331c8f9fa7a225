// Exporters: the same scene for POV-Ray (SDL) and Blender Cycles (a JSON job
// read by the fixed script harness/blender_render.py). Nothing from the scene
// file is pasted into source text: SDL is assembled from numbers the exporter
// formats itself and from fixed keywords; the scene's name only appears in a
// comment, reduced to a safe character set.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "core/grid_mesh.h"
#include "image/image.h"
#include "scene/renderer_table.h"
#include "scene/scene.h"

namespace penumbra {

// The scene uses something the target renderer cannot express (a method it
// does not implement, a point light, a glossy lobe...). Bad input.
class ExportError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Refuses, with the renderer table's reason, the scene features the table
// says renderer `r` (exported as `name`) cannot render: height or normal
// maps, the plane.
inline void refuse_unoffered(const Scene& scene, RendererKind r, const char* name) {
  const RendererInfo& info = renderer_info(r);
  if (scene.height.height_map() && !info.height_maps)
    throw ExportError(std::string(name) + " export: " + info.height_maps_why_not);
  if (scene.height.normal_map() && !info.normal_maps)
    throw ExportError(std::string(name) + " export: " + info.normal_maps_why_not);
  if (scene.shape.type == ShapeType::kPlane && !info.plane)
    throw ExportError(std::string(name) + " export: " + info.plane_why_not);
}

// ---- POV-Ray 3.7 ----------------------------------------------------------

// POV-Ray renders supersample_x * supersample_y samples per pixel as an
// image that many times larger, without anti-aliasing, at the evaluator's
// stratum centres; the driver box-filters it back to width x height.
struct PovrayExport {
  std::string sdl;            // a self-contained .pov file
  int width = 0, height = 0;  // final image, pixels
  int supersample_x = 1, supersample_y = 1;
  bool single_thread = false;  // isosurfaces: +WT1 keeps them deterministic
  // An image height map in bump: its texels rescaled to [0, 1] (R = G = B),
  // which the SDL reads back as kPovrayMapFile beside it; empty otherwise.
  Image map;
  // Arguments after the executable, for input and output file names that the
  // caller chose (plain names, POV-Ray runs in their folder).
  std::vector<std::string> arguments(const std::string& input, const std::string& output,
                                     int threads) const;
};

// POV-Ray has no shadow-terminator method: only `none` is accepted, and no
// shadow-ray offset: only offset `none`. A tessellated shape becomes a mesh2
// (normal_vectors for smooth shading). Distant lights only: POV-Ray's
// fade_power 2 is 2/(1+(d/D)^2), not 1/d^2. No props (evaluator-only).
// Image height maps in bump: the evaluator's cubic B-spline of the texels as
// SDL functions over nearest-texel lookups of kPovrayMapFile; displaced
// image maps and displaced planes: the evaluator's displaced grid as a mesh2
// with its exact vertex normals. Normal maps are refused (renderer table).
PovrayExport export_povray(const Scene& scene);
// The image file the SDL of a height-mapped scene reads (a fixed name).
inline constexpr const char* kPovrayMapFile = "map.exr";
// Writes scene.pov (and kPovrayMapFile where the export has a map) into
// `folder`, which must exist.
void write_povray_files(const PovrayExport& job, const std::string& folder);

// ---- Blender 3.4 Cycles ---------------------------------------------------

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

// Writes an export's files into `folder` (which must exist): the job, the
// mesh, and for image maps the UVs and the map.
void write_blender_files(const BlenderExport& job, const std::string& folder);

// POV-Ray/Penumbra coordinates (left-handed, y up) to Blender's
// (right-handed, z up): swap y and z.
inline Vec3 to_blender(const Vec3& p) {
  return {p.x, p.z, p.y};
}

// A scene name reduced to [A-Za-z0-9 _.+-], at most 80 characters, for comments.
std::string comment_safe(const std::string& text);

}  // namespace penumbra
