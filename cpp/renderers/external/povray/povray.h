// POV-Ray 3.7: its exporter (the scene as SDL), its driver (run POV-Ray,
// box-filter its supersampled image) and its entry (renderers/renderer.h).
// Nothing from the scene file is pasted into source text: SDL is assembled
// from numbers the exporter formats itself and from fixed keywords; the
// scene's name only appears in a comment, reduced to a safe character set.
#pragma once

#include <string>
#include <vector>

#include "image/image.h"
#include "renderers/renderer.h"
#include "scene/scene.h"

namespace penumbra {

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
// with its exact vertex normals. Normal maps are refused (its row).
PovrayExport export_povray(const Scene& scene);
// The image file the SDL of a height-mapped scene reads (a fixed name).
inline constexpr const char* kPovrayMapFile = "map.exr";
// The SDL file the driver and `penumbra export` write.
inline constexpr const char* kPovraySceneFile = "scene.pov";
// Writes kPovraySceneFile (and kPovrayMapFile where the export has a map)
// into `folder`, which must exist.
void write_povray_files(const PovrayExport& job, const std::string& folder);

// A scene name reduced to [A-Za-z0-9 _.+-], at most 80 characters, for comments.
std::string comment_safe(const std::string& text);

// Exports `scene`, runs POV-Ray on it and box-filters its image: the entry's render.
RendererRun render_povray(const Scene& scene, const RenderSettings& settings);

const RendererEntry& povray_entry();

}  // namespace penumbra
