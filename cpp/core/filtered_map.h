// An image map filtered for the footprint a camera sample covers: the bump
// and roughness pyramids (bump_pyramid.h) of the map's slopes, looked up
// at the level the footprint selects, and a roughness filter
// (roughness_filter.h) turning the footprint's slope covariance into the
// specular lobe. Pure math; the scene layer builds it, the evaluator asks
// it for each sample's normal and lobe.
#pragma once

#include <vector>

#include "core/bump_pyramid.h"
#include "core/roughness_filter.h"
#include "core/shape.h"
#include "core/surface_map.h"
#include "core/vec.h"

namespace penumbra {

struct FilteredMap {
  FilterSettings settings;
  // Slopes in height per scene unit along unit dP/du and dP/dv (on the
  // sphere: at the equator, rescaled by latitude at lookup).
  std::vector<PyramidLevel> pyramid;
  // < 0: the level follows each sample's footprint; >= 0: every lookup
  // reads this (fractional) level, a footprint of 2^level finest texels.
  double fixed_level = -1.0;
  int width = 0, height = 0;
  double tiles_u = 1.0, tiles_v = 1.0;
  MapEdge edge = MapEdge::kWrap;
};

// The pyramids of a height map displaced by `amplitude` (scene units per
// texel value), by central differences over the texel pitch of the shape's
// parameterisation; or of a normal map's slopes (-n_x / n_z, -n_y / n_z).
FilteredMap make_filtered_map(const SurfaceMap& map, double amplitude, const Shape& shape,
                              const FilterSettings& settings, double fixed_level);

// What one sample shades with.
struct FilteredSample {
  Vec3 ns;       // the footprint's mean normal, n - f_u t_u - f_v t_v normalised
  Vec3 tangent;  // unit dP/du: the lobe's first axis (K's u)
  FilteredLobe lobe;
  double footprint = 0.0;  // finest texels across
};

// dpdx, dpdy: how the sample's surface point moves per pixel step (ray
// differentials on the tangent plane). `alpha`: the material's base GGX
// roughness. The normal is the first-order bump of the mean slope: the
// curvature terms of displaced_normal (1 + A h kappa) are left out, since
// the pyramid keeps slopes, not heights.
FilteredSample filtered_sample(const FilteredMap& map, const Shape& shape, const SurfaceGeometry& g,
                               const Vec3& dpdx, const Vec3& dpdy, double alpha);

}  // namespace penumbra
