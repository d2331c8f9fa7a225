#include "core/filtered_map.h"

#include <algorithm>
#include <cmath>

namespace penumbra {
namespace {

// Slopes of the map's finest texels, per scene unit.
std::vector<Offset2> finest_slopes(const SurfaceMap& map, double amplitude, const Shape& shape) {
  const std::size_t count = std::size_t(map.width) * map.height;
  std::vector<Offset2> slopes(count);
  if (map.kind == MapKind::kNormal) {
    for (std::size_t i = 0; i < count; ++i) {
      const double x = 2.0 * map.texels[3 * i] - 1.0, y = 2.0 * map.texels[3 * i + 1] - 1.0;
      const double z = std::max(2.0 * map.texels[3 * i + 2] - 1.0, 1e-3);
      slopes[i] = {-x / z, -y / z};
    }
    return slopes;
  }
  // Height per texel first, then per scene unit along each axis.
  const PyramidLevel per_texel =
      offsets_from_heights(map.texels, map.width, map.height, 1.0, amplitude, map.edge);
  const MapLengths lengths = map_lengths(shape);
  const double texel_u = lengths.u / (map.width * map.tiles_u);
  const double texel_v = lengths.v / (map.height * map.tiles_v);
  for (std::size_t i = 0; i < count; ++i)
    slopes[i] = {per_texel.f_u[i] / texel_u, per_texel.f_v[i] / texel_v};
  return slopes;
}

// Finest texels a footprint spans: the longer of the two pixel steps in
// texel units (isotropic, as a mip level is).
double footprint_texels(const FilteredMap& m, const SurfaceParameters& q, const Vec3& dpdx,
                        const Vec3& dpdy) {
  const double pu2 = length_squared(q.dp_du), pv2 = length_squared(q.dp_dv);
  const auto texels = [&](const Vec3& d) {
    const double du = pu2 > 0.0 ? dot(d, q.dp_du) / pu2 * m.width * m.tiles_u : 0.0;
    const double dv = pv2 > 0.0 ? dot(d, q.dp_dv) / pv2 * m.height * m.tiles_v : 0.0;
    return std::hypot(du, dv);
  };
  return std::max(texels(dpdx), texels(dpdy));
}

Vec3 bumped(const Vec3& n, const Vec3& t_u, const Vec3& t_v, const Offset2& f) {
  return normalize(n - t_u * f.f_u - t_v * f.f_v);
}

}  // namespace

FilteredMap make_filtered_map(const SurfaceMap& map, double amplitude, const Shape& shape,
                              const FilterSettings& settings, double fixed_level) {
  FilteredMap out;
  out.settings = settings;
  out.fixed_level = fixed_level;
  out.width = map.width, out.height = map.height;
  out.tiles_u = map.tiles_u, out.tiles_v = map.tiles_v;
  out.edge = map.edge;
  out.pyramid = build_bump_pyramid(
      level_from_offsets(finest_slopes(map, amplitude, shape), map.width, map.height));
  return out;
}

FilteredSample filtered_sample(const FilteredMap& m, const Shape& shape, const SurfaceGeometry& g,
                               const Vec3& dpdx, const Vec3& dpdy, double alpha) {
  const SurfaceParameters q = surface_parameters(shape, g.p);
  FilteredSample out;
  out.footprint = m.fixed_level >= 0.0 ? std::exp2(m.fixed_level)
                                       : std::max(footprint_texels(m, q, dpdx, dpdy), 1e-9);
  // Finest-texel coordinates: texel i spans [i, i + 1), rows run down.
  const double x = q.u * m.tiles_u * m.width, y = (1.0 - q.v * m.tiles_v) * m.height;
  FilteredTexel texel = sample_pyramid(m.pyramid, x, y, out.footprint, m.edge);
  // Below a texel (magnification) the bilinear mixture's spread of means is
  // the reconstruction's, not the footprint's: a slope field interpolated
  // linearly varies over w texels by w times its variation over one, so its
  // variance scales by w^2.
  if (out.footprint < 1.0) {
    const double w2 = out.footprint * out.footprint;
    texel.covariance = {texel.covariance.a * w2, texel.covariance.b * w2, texel.covariance.c * w2};
  }
  // The sphere's u lines shrink with latitude: slopes along u grow by the
  // equator's length over the local one.
  const double pu = length(q.dp_du);
  const double k_u = pu > 1e-12 ? map_lengths(shape).u / pu : 1.0;
  texel.mean.f_u *= k_u;
  texel.covariance.a *= k_u * k_u;
  texel.covariance.b *= k_u;
  const Vec3 t_u = pu > 1e-12 ? q.dp_du / pu : g.t1;
  const Vec3 t_v = normalize(q.dp_dv);
  out.ns = bumped(g.n, t_u, t_v, texel.mean);
  out.tangent = t_u;
  FootprintStatistics stats{texel.covariance, std::min(1.0, length(texel.mean_normal)), 0.0};
  if (roughness_filter_info(m.settings.filter).needs_normal_derivatives) {
    // The change of the mean normal over one pixel step, by central
    // differences of the pyramid at the same level.
    const auto normal_at = [&](const Vec3& d) {
      const double pu2 = length_squared(q.dp_du), pv2 = length_squared(q.dp_dv);
      const double dx = pu2 > 0.0 ? dot(d, q.dp_du) / pu2 * m.tiles_u * m.width : 0.0;
      const double dy = -dot(d, q.dp_dv) / pv2 * m.tiles_v * m.height;
      FilteredTexel t = sample_pyramid(m.pyramid, x + dx, y + dy, out.footprint, m.edge);
      t.mean.f_u *= k_u;
      return bumped(g.n, t_u, t_v, t.mean);
    };
    const Vec3 ddx = (normal_at(dpdx) - normal_at(-dpdx)) * 0.5;
    const Vec3 ddy = (normal_at(dpdy) - normal_at(-dpdy)) * 0.5;
    stats.normal_derivative2 = length_squared(ddx) + length_squared(ddy);
  }
  out.lobe = filter_roughness(m.settings, stats, alpha);
  return out;
}

}  // namespace penumbra
