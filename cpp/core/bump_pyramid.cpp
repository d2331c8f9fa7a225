#include "core/bump_pyramid.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace penumbra {

RoughnessFactor roughness_factor(const Covariance2& k) {
  if (!(k.c > 0.0)) return {std::sqrt(std::max(k.a, 0.0)), 0.0, 0.0};
  const double d3 = std::sqrt(k.c);
  // a - b^2/c is K's Schur complement: >= 0 for PSD K, but rounding takes a
  // nearly singular one below 0, where sqrt would return NaN.
  return {std::sqrt(std::max(k.a - k.b * k.b / k.c, 0.0)), k.b / d3, d3};
}

Covariance2 covariance_from_factor(const RoughnessFactor& d) {
  return {d.d1 * d.d1 + d.d2 * d.d2, d.d2 * d.d3, d.d3 * d.d3};
}

double isotropic_roughness(const Covariance2& k) {
  const double mean = 0.5 * (k.a + k.c);
  const double half_difference = 0.5 * (k.a - k.c);
  return std::sqrt(std::max(mean + std::hypot(half_difference, k.b), 0.0));
}

BumpFrame natural_frame(const Vec3& p_u, const Vec3& p_v) {
  const Vec3 n = cross(p_u, p_v);
  const Vec3 n_unit = normalize(n);
  return {n, cross(n_unit, p_v), cross(p_u, n_unit)};
}

BumpFrame normalized_natural_frame(const Vec3& p_u, const Vec3& p_v) {
  const BumpFrame f = natural_frame(p_u, p_v);
  return {normalize(f.n), normalize(f.s_u), normalize(f.s_v)};
}

BumpFrame main_direction_frame(const Vec3& n_interpolated, const Vec3& m) {
  const Vec3 n = normalize(n_interpolated);
  const Vec3 e1 = normalize(cross(m, n));
  return {n, e1, cross(n, e1)};
}

Vec3 bumped_normal(const BumpFrame& frame, const Offset2& f) {
  return frame.n + frame.s_u * f.f_u + frame.s_v * f.f_v;
}

Offset2 PyramidLevel::offset(int x, int y) const {
  const std::size_t i = index(x, y);
  return {f_u[i], f_v[i]};
}

Covariance2 PyramidLevel::covariance(int x, int y) const {
  const std::size_t i = index(x, y);
  return {k_a[i], k_b[i], k_c[i]};
}

Vec3 PyramidLevel::mean_normal(int x, int y) const {
  const std::size_t i = index(x, y);
  return {n_x[i], n_y[i], n_z[i]};
}

namespace {

PyramidLevel empty_level(int width, int height) {
  if (width <= 0 || height <= 0)
    throw std::invalid_argument("a bump map needs at least 1x1 texels");
  PyramidLevel level;
  level.width = width;
  level.height = height;
  const std::size_t n = std::size_t(width) * height;
  for (std::vector<float>* channel : {&level.f_u, &level.f_v, &level.k_a, &level.k_b, &level.k_c,
                                      &level.n_x, &level.n_y, &level.n_z})
    channel->assign(n, 0.0f);
  return level;
}

// Level 0's own unit normals from its offsets.
void set_unit_normals(PyramidLevel& level) {
  for (std::size_t i = 0; i < level.f_u.size(); ++i) {
    const Vec3 n = normalize(Vec3(level.f_u[i], level.f_v[i], 1.0));
    level.n_x[i] = float(n.x);
    level.n_y[i] = float(n.y);
    level.n_z[i] = float(n.z);
  }
}

// d/di of the samples at (i - 1, i, i + 1) along an axis of `size` texels,
// in texels: central inside, wrapped or one-sided at the edges. A map one
// texel wide has no slope along that axis.
struct Neighbours {
  int before, after;
  double span;  // texels between them
};
Neighbours neighbours(int i, int size, MapEdge edge) {
  if (size == 1) return {i, i, 1.0};
  if (edge == MapEdge::kWrap) return {(i + size - 1) % size, (i + 1) % size, 2.0};
  const int before = std::max(i - 1, 0), after = std::min(i + 1, size - 1);
  return {before, after, double(after - before)};
}

// Number of finest texels that texel i of `level` covers along an axis of
// `finest` texels.
double covered(int i, int level, int finest) {
  const long first = long(i) << level;
  return double(std::min(first + (1L << level), long(finest)) - first);
}

}  // namespace

PyramidLevel offsets_from_heights(std::span<const float> heights, int width, int height,
                                  double texel_size, double height_scale, MapEdge edge) {
  if (heights.size() != std::size_t(width) * std::size_t(std::max(height, 0)))
    throw std::invalid_argument("height map size does not match its width and height");
  if (!(texel_size > 0.0) || !std::isfinite(texel_size))
    throw std::invalid_argument("texel size must be finite and > 0");
  PyramidLevel level = empty_level(width, height);
  const double scale = height_scale / texel_size;
  for (int y = 0; y < height; ++y) {
    const Neighbours ny = neighbours(y, height, edge);
    for (int x = 0; x < width; ++x) {
      const Neighbours nx = neighbours(x, width, edge);
      const auto h = [&](int xx, int yy) { return double(heights[std::size_t(yy) * width + xx]); };
      const std::size_t i = level.index(x, y);
      level.f_u[i] = float(scale * (h(nx.after, y) - h(nx.before, y)) / nx.span);
      // Rows grow downwards and v upwards.
      level.f_v[i] = float(-scale * (h(x, ny.after) - h(x, ny.before)) / ny.span);
    }
  }
  set_unit_normals(level);
  return level;
}

PyramidLevel level_from_offsets(std::span<const Offset2> offsets, int width, int height) {
  PyramidLevel level = empty_level(width, height);
  if (offsets.size() != level.f_u.size())
    throw std::invalid_argument("offset map size does not match its width and height");
  for (std::size_t i = 0; i < offsets.size(); ++i) {
    level.f_u[i] = float(offsets[i].f_u);
    level.f_v[i] = float(offsets[i].f_v);
  }
  set_unit_normals(level);
  return level;
}

PyramidLevel coarser_level(const PyramidLevel& finer, int level, int finest_width,
                           int finest_height) {
  PyramidLevel coarse = empty_level((finer.width + 1) / 2, (finer.height + 1) / 2);
  for (int y = 0; y < coarse.height; ++y) {
    for (int x = 0; x < coarse.width; ++x) {
      // Weighted mixture of the (up to four) children: mean of the means,
      // then mean of K plus the spread of the children's means about it.
      double w_sum = 0.0, mu_u = 0.0, mu_v = 0.0;
      Vec3 normal;
      for (int cy = 2 * y; cy < std::min(2 * y + 2, finer.height); ++cy)
        for (int cx = 2 * x; cx < std::min(2 * x + 2, finer.width); ++cx) {
          const double w = covered(cx, level, finest_width) * covered(cy, level, finest_height);
          const Offset2 f = finer.offset(cx, cy);
          w_sum += w;
          mu_u += w * f.f_u;
          mu_v += w * f.f_v;
          normal += finer.mean_normal(cx, cy) * w;
        }
      mu_u /= w_sum;
      mu_v /= w_sum;
      normal = normal / w_sum;
      double a = 0.0, b = 0.0, c = 0.0;
      for (int cy = 2 * y; cy < std::min(2 * y + 2, finer.height); ++cy)
        for (int cx = 2 * x; cx < std::min(2 * x + 2, finer.width); ++cx) {
          const double w = covered(cx, level, finest_width) * covered(cy, level, finest_height);
          const Offset2 f = finer.offset(cx, cy);
          const Covariance2 k = finer.covariance(cx, cy);
          const double du = f.f_u - mu_u, dv = f.f_v - mu_v;
          a += w * (k.a + du * du);
          b += w * (k.b + du * dv);
          c += w * (k.c + dv * dv);
        }
      const std::size_t i = coarse.index(x, y);
      coarse.f_u[i] = float(mu_u);
      coarse.f_v[i] = float(mu_v);
      coarse.k_a[i] = float(a / w_sum);
      coarse.k_b[i] = float(b / w_sum);
      coarse.k_c[i] = float(c / w_sum);
      coarse.n_x[i] = float(normal.x);
      coarse.n_y[i] = float(normal.y);
      coarse.n_z[i] = float(normal.z);
    }
  }
  return coarse;
}

std::vector<PyramidLevel> build_bump_pyramid(PyramidLevel finest) {
  std::vector<PyramidLevel> levels;
  const int width = finest.width, height = finest.height;
  levels.push_back(std::move(finest));
  while (levels.back().width > 1 || levels.back().height > 1) {
    const int level = int(levels.size()) - 1;
    levels.push_back(coarser_level(levels.back(), level, width, height));
  }
  return levels;
}

namespace {

// Texel index along an axis of `size` texels, past the edge per `edge`.
int texel_index(int i, int size, MapEdge edge) {
  if (edge == MapEdge::kClamp) return std::clamp(i, 0, size - 1);
  return ((i % size) + size) % size;
}

struct Weighted {
  int level, x, y;
  double w;
};

// The (up to four) texels of `level` a bilinear lookup at (x, y) (finest
// texel units) blends, with weights scaled by `scale`.
void bilinear(const PyramidLevel& level, int l, double x, double y, double scale, MapEdge edge,
              std::vector<Weighted>& out) {
  const double xl = x / double(1L << l) - 0.5, yl = y / double(1L << l) - 0.5;
  const double fx = std::floor(xl), fy = std::floor(yl);
  const double tx = xl - fx, ty = yl - fy;
  for (int dy = 0; dy < 2; ++dy)
    for (int dx = 0; dx < 2; ++dx) {
      const double w = scale * (dx ? tx : 1.0 - tx) * (dy ? ty : 1.0 - ty);
      if (w > 0.0)
        out.push_back({l, texel_index(int(fx) + dx, level.width, edge),
                       texel_index(int(fy) + dy, level.height, edge), w});
    }
}

}  // namespace

FilteredTexel sample_pyramid(const std::vector<PyramidLevel>& levels, double x, double y,
                             double footprint, MapEdge edge) {
  const int top = int(levels.size()) - 1;
  const double lod = std::clamp(std::log2(std::max(footprint, 1.0)), 0.0, double(top));
  const int l0 = std::min(int(std::floor(lod)), top);
  const double t = lod - l0;
  std::vector<Weighted> texels;
  bilinear(levels[l0], l0, x, y, 1.0 - t, edge, texels);
  if (t > 0.0 && l0 < top) bilinear(levels[l0 + 1], l0 + 1, x, y, t, edge, texels);
  double w_sum = 0.0;
  FilteredTexel out;
  for (const Weighted& k : texels) {
    const Offset2 f = levels[k.level].offset(k.x, k.y);
    w_sum += k.w;
    out.mean.f_u += k.w * f.f_u;
    out.mean.f_v += k.w * f.f_v;
    out.mean_normal += levels[k.level].mean_normal(k.x, k.y) * k.w;
  }
  out.mean.f_u /= w_sum;
  out.mean.f_v /= w_sum;
  out.mean_normal = out.mean_normal / w_sum;
  for (const Weighted& k : texels) {
    const Offset2 f = levels[k.level].offset(k.x, k.y);
    const Covariance2 c = levels[k.level].covariance(k.x, k.y);
    const double du = f.f_u - out.mean.f_u, dv = f.f_v - out.mean.f_v;
    out.covariance.a += k.w / w_sum * (c.a + du * du);
    out.covariance.b += k.w / w_sum * (c.b + du * dv);
    out.covariance.c += k.w / w_sum * (c.c + dv * dv);
  }
  return out;
}

double schilling_cos2_alpha(const Vec3& h_local, const Covariance2& k) {
  const double cos2 = h_local.z * h_local.z;
  const double dx = h_local.x, dy = h_local.y;
  const double numerator = k.c * dx * dx - 2.0 * k.b * dx * dy + k.a * dy * dy;
  const double det = k.a * k.c - k.b * k.b;
  // K singular (to rounding): the quadratic form is finite only for d in
  // K's range; elsewhere the highlight vanishes.
  const double scale = std::max(k.a + k.c, 0.0);
  if (!(det > 1e-14 * scale * scale)) {
    if (dx == 0.0 && dy == 0.0) return cos2;
    if (!(scale > 0.0)) return 0.0;
    // Range of a rank-one K = [[a,b],[b,c]] is (a, b) or (b, c); d must be
    // parallel to it (numerator = 0 exactly in exact arithmetic).
    const double along = (dx * dx + dy * dy) * scale;
    if (numerator > 1e-12 * along) return 0.0;
    const double variance = k.a + k.c;  // the one non-zero eigenvalue
    return cos2 / ((dx * dx + dy * dy) / variance + cos2);
  }
  return cos2 / (numerator / det + cos2);
}

double schilling_cos2_alpha_isotropic(double cos2_alpha, double lambda1) {
  const double l2c = lambda1 * lambda1 * cos2_alpha;
  const double denominator = 1.0 - cos2_alpha + l2c;
  return denominator > 0.0 ? l2c / denominator : 1.0;
}

}  // namespace penumbra
