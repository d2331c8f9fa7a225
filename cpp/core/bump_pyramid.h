// Schilling's bump-map pyramid (A. Schilling 1997, "Toward Real-Time
// Photorealistic Rendering: Challenges and Solutions", SIGGRAPH/Eurographics
// Workshop on Graphics Hardware; docs/filtering.md): a bump map stored as
// offset vectors (precalculated derivatives f_u, f_v of the height), a bump
// pyramid that is the mip map of those offsets, and a roughness pyramid that
// keeps, per texel, the covariance K of every finest-level offset the texel
// covers, so that bumps filtered out of the bump pyramid come back as
// roughness. Pure math: no I/O (the CLI's `penumbra pyramid` writes levels).
//
// Texel conventions, shared with the scene's image maps: column x grows
// with u, row y grows downwards in the file while v grows upwards (as in
// Blender's and POV-Ray's image textures), so f_v = -dh/dy / texel_size.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "core/enum_names.h"
#include "core/vec.h"

namespace penumbra {

// Offset vector: the height's derivatives along the frame's two tangent
// directions. Dimensionless (height per scene unit) when the frame is
// normalised and the map's texel size is given in scene units.
struct Offset2 {
  double f_u = 0.0, f_v = 0.0;
};

// Covariance of offset vectors, K = [[a, b], [b, c]]; symmetric positive
// semi-definite; units: offset squared.
struct Covariance2 {
  double a = 0.0, b = 0.0, c = 0.0;
};

// Schilling's factor D = [[d1, d2], [0, d3]] with D D^T = K and d1, d3 >= 0:
// d1 = sqrt(a - b^2/c), d2 = b / sqrt(c), d3 = sqrt(c). Units: offset.
struct RoughnessFactor {
  double d1 = 0.0, d2 = 0.0, d3 = 0.0;
};

// The paper's factor. For c == 0 (then b == 0 for a PSD K) it returns
// d1 = sqrt(a), d2 = d3 = 0, which still satisfies D D^T = K; a - b^2/c is
// clamped at 0 where rounding makes a nearly singular K's Schur complement
// negative.
RoughnessFactor roughness_factor(const Covariance2& k);
Covariance2 covariance_from_factor(const RoughnessFactor& d);

// Isotropic roughness: lambda1 = square root of K's largest eigenvalue, the
// standard deviation of the offsets along their direction of largest
// variance (a conservative isotropic bound). Units: offset.
double isotropic_roughness(const Covariance2& k);

// The paper's three local frames, in which n' = n + f_u s_u + f_v s_v.
struct BumpFrame {
  Vec3 n, s_u, s_v;
};
// 1. Natural: n = p_u x p_v, s_u = n/|n| x p_v, s_v = p_u x n/|n| (Blinn's
//    bump mapping; the bump height does not scale with the map).
BumpFrame natural_frame(const Vec3& p_u, const Vec3& p_v);
// 2. Natural with unit vectors: n, s_u, s_v of (1) normalised (scale
//    invariant; offsets are slopes in scene units when the map's texel size
//    is in scene units).
BumpFrame normalized_natural_frame(const Vec3& p_u, const Vec3& p_v);
// 3. Orthonormal from a main direction m (e.g. a sphere's axis): n = nI/|nI|,
//    e1 = m x n / |m x n| (s_u), e2 = n x e1 (s_v). Undefined where n is
//    parallel to m (the poles of such a sphere).
BumpFrame main_direction_frame(const Vec3& n_interpolated, const Vec3& m);
// n + f_u s_u + f_v s_v, not normalised.
Vec3 bumped_normal(const BumpFrame& frame, const Offset2& f);

// How differences reach past the map's edge: kWrap for tiled maps (the
// default), kClamp uses one-sided differences there.
enum class MapEdge { kWrap, kClamp };
inline constexpr EnumName<MapEdge> kMapEdgeNames[] = {{"wrap", MapEdge::kWrap},
                                                      {"clamp", MapEdge::kClamp}};

// One level of both pyramids, structure of arrays, row-major from the top
// row, float storage (arithmetic is in double). Level 0 has zero
// covariance: a texel's own offset is its whole distribution.
struct PyramidLevel {
  int width = 0, height = 0;
  std::vector<float> f_u, f_v;       // bump pyramid: mean offset
  std::vector<float> k_a, k_b, k_c;  // roughness pyramid: covariance K
  // Mean of the covered unit bumped normals, in coordinates of the frame
  // (s_u, s_v, n), where a normalised frame's bumped normal is
  // (f_u, f_v, 1) / |.|; its length is what Toksvig's filter reads.
  std::vector<float> n_x, n_y, n_z;
  std::size_t index(int x, int y) const { return std::size_t(y) * width + x; }
  Offset2 offset(int x, int y) const;
  Covariance2 covariance(int x, int y) const;
  Vec3 mean_normal(int x, int y) const;
};

// Offsets from a height map by central differences (one-sided at a clamped
// edge). heights: width*height values, row-major from the top row;
// texel_size: scene units per texel (> 0); height_scale multiplies the
// values into scene units.
PyramidLevel offsets_from_heights(std::span<const float> heights, int width, int height,
                                  double texel_size, double height_scale, MapEdge edge);
// A level 0 from offsets given directly (e.g. decoded from a normal map).
PyramidLevel level_from_offsets(std::span<const Offset2> offsets, int width, int height);

// Both pyramids, level 0 first, down to 1x1. Level l has ceil(w / 2^l) x
// ceil(h / 2^l) texels; texel (x, y) of level l covers the finest texels
// [x 2^l, (x+1) 2^l) x [y 2^l, (y+1) 2^l) inside the map. Each level comes
// from the one below by the paper's recursion, K = mean of the children's K
// plus the covariance of the children's mean offsets, weighted by the
// number of finest texels each child covers (all equal for power-of-two
// sizes, where this is exactly the paper's 2x2 box filter); K at level l
// is then the covariance over every finest offset the texel covers.
std::vector<PyramidLevel> build_bump_pyramid(PyramidLevel finest);
// One step of that recursion; `level` is the index of `finer`, and
// finest_width/finest_height the size of level 0.
PyramidLevel coarser_level(const PyramidLevel& finer, int level, int finest_width,
                           int finest_height);

// What a footprint reads from the pyramids: the mixture of the texels a
// trilinear lookup blends, with the moments of a mixture (mean of the
// means; mean of K plus the spread of the means about their mean), so that
// a lookup at a texel's centre at its own level returns that texel.
struct FilteredTexel {
  Offset2 mean;
  Covariance2 covariance;
  Vec3 mean_normal;  // frame (s_u, s_v, n), as PyramidLevel::mean_normal
};
// Centre (x, y) in finest-texel units (texel i spans [i, i + 1); x along
// columns, y down the rows), footprint width in finest texels (>= 1 reads
// level log2(footprint), linear between the two nearest levels; below 1,
// level 0). Bilinear within a level between texel centres; `edge` decides
// past the map's edge (kWrap: tiled). Levels of non-power-of-two maps are
// addressed as if their last texel were whole.
FilteredTexel sample_pyramid(const std::vector<PyramidLevel>& levels, double x, double y,
                             double footprint, MapEdge edge);

// Schilling's modified Blinn-Phong (appendix A). h_local: the unit half
// vector in the frame (e1, e2, n); cos(alpha) = h_local.z and d = (h.x, h.y)
// (the projection of n - h onto the tangent plane, up to a sign that the
// quadratic form ignores). Returns cos^2(alpha') = cos^2 / (d^T K^-1 d +
// cos^2): the paper's |d|^4 / |D d|^2 term read as |d|^2 over the squared
// standard deviation of the offsets along d (the distance from the centre
// to the ellipse x^T K^-1 x = 1 in d's direction, as the paper defines it).
// The printed |D d| and this agree for isotropic K and along K's axes; this
// form does not depend on which factor D of K is chosen. Where K is
// singular and d leaves its range, cos^2(alpha') is 0 (no highlight).
double schilling_cos2_alpha(const Vec3& h_local, const Covariance2& k);
// The isotropic form: lambda1^2 cos^2 / (1 - cos^2 + lambda1^2 cos^2);
// equals cos^2 at lambda1 = 1, as the paper states.
double schilling_cos2_alpha_isotropic(double cos2_alpha, double lambda1);

}  // namespace penumbra
