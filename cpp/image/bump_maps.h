// Bump maps from image files: a height map read and checked, and the bump
// and roughness pyramids (core/bump_pyramid.h) written as one EXR per level
// with a manifest. Errors name the file (InputError); a pyramid folder is
// written under a temporary name and renamed into place, so a failed or
// interrupted build never leaves one that looks complete.
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "core/bump_pyramid.h"
#include "core/height.h"
#include "core/surface_map.h"
#include "image/image.h"

namespace penumbra {

// One channel of an image file as heights (the file's values, before any
// scale). `channel` "" takes the only channel, and is required when the file
// has several. Refuses a missing or unreadable file, an unknown channel, a
// zero-size image and any NaN or infinite value (naming the first texel).
struct HeightMap {
  int width = 0, height = 0;
  std::vector<float> heights;  // row-major from the top row
  std::string channel;         // the channel read
};
HeightMap read_height_map(const std::string& path, const std::string& channel = "");

// The steepest slope a height map may give, in scene units per scene unit:
// the pyramids square and sum slopes in 32-bit float (at most ~3.4e38), so
// a larger one makes every level Inf or NaN.
inline constexpr double kMaxMapSlope = 1e18;

// InputError naming `path` when the map's steepest difference between
// neighbouring texels, times `height_scale` / `texel_size`, exceeds
// kMaxMapSlope (or is not finite): a pyramid of it could not be finite.
void check_map_slopes(const HeightMap& map, const std::string& path, double texel_size,
                      double height_scale);

// A height map (one channel, chosen as read_height_map chooses it) or a
// tangent-space normal map (channels R, G, B, or the only three) as a
// SurfaceMap with its digest; tiling and edge are left at their defaults.
// The same refusals as read_height_map, plus a normal map without three
// colour channels. Maps already read in this process are shared while the
// file's size and modification time stay the same.
std::shared_ptr<const SurfaceMap> load_surface_map(const std::string& path, MapKind kind,
                                                   const std::string& channel = "");

// A shape's analytic height function baked over its map parameters (u, v)
// (core/surface_map.h) into a width x height image: kHeight gives channel
// "Y" = amplitude * h at each texel's centre (scene units: load it with
// amplitude 1); kNormal gives "R", "G", "B" = 0.5 n + 0.5, n the exact
// displaced normal in the tangent frame (dP/du, dP/dv, N).
Image bake_surface_map(const Shape& shape, const HeightFunction& f, double amplitude, int width,
                       int height, MapKind kind);
// Rows of a map `columns` texels around the shape whose texels are as square
// as its (u, v) allows (on the sphere, at the equator): what `penumbra bake
// --on shape` and a study's interplay section bake; at most `max_rows`.
inline int shape_map_rows(const Shape& shape, int columns, int max_rows) {
  const MapLengths lengths = map_lengths(shape);
  return std::clamp(static_cast<int>(std::lround(columns * lengths.v / lengths.u)), 1, max_rows);
}

// An analytic height function baked into a size x size single-channel
// ("Y") height map of the plane z = 0 over [0, extent)^2: texel (x, y) holds
// amplitude * h(u, v, 0) at its centre, u = (x + 0.5) t along the columns
// and v = (size - y - 0.5) t up the rows, t = extent / size (scene units),
// so that `penumbra pyramid --texel-size t` gives offsets that approximate
// amplitude * (dh/du, dh/dv) (central differences: a sine of k cycles per
// unit is scaled by sin(2 pi k t) / (2 pi k t)). The map tiles only where
// extent is a whole number of every term's periods.
Image bake_height_map(const HeightFunction& f, double amplitude, int size, double extent);

// How a pyramid was made, for its manifest.
struct PyramidSource {
  std::string path;       // the height map
  std::string channel;    // its channel
  double texel_size = 0;  // scene units per finest texel
  double height_scale = 1;
  MapEdge edge = MapEdge::kWrap;
};

// Level `level` of the pyramids as an image, channels "bump.f_u", "bump.f_v"
// (mean offset), "roughness.d1", "roughness.d2", "roughness.d3" (Schilling's
// D with D D^T = K), "roughness.lambda1" (isotropic), "normal.length" (of the
// mean unit normal, for Toksvig).
Image pyramid_level_image(const PyramidLevel& level);

// Writes `levels` into `folder`: level_NN.exr for each and pyramid.json
// (source, conventions, units, level sizes). Replaces a previous pyramid
// folder; refuses (OutputError) a non-empty folder that is not one.
void write_pyramid(const std::vector<PyramidLevel>& levels, const PyramidSource& source,
                   const std::string& folder);

}  // namespace penumbra
