#include "core/normal_integration.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>

namespace penumbra {

namespace {

// The grid's edges: texel p to its right neighbour and to the one below
// (wrapped, or missing at a clamped map's border).
struct Grid {
  int width = 0, height = 0;
  bool wrap = true;
  std::size_t size() const { return std::size_t(width) * height; }
  std::size_t at(int x, int y) const { return std::size_t(y) * width + x; }
  // The neighbour of (x, y) to the right (dx = 1) or below (dy = 1); false
  // at a clamped border.
  bool next(int x, int y, int dx, int dy, std::size_t* q) const {
    int nx = x + dx, ny = y + dy;
    if (nx == width || ny == height) {
      if (!wrap) return false;
      nx %= width;
      ny %= height;
    }
    *q = at(nx, ny);
    return true;
  }
};

// Per texel, the height's change over one texel step right (sx) and one
// step down a row (sy), in scene units.
struct Slopes {
  std::vector<double> sx, sy;
  int clamped = 0;
};

Slopes texel_slopes(const SurfaceMap& map, double length_u, double length_v) {
  const std::size_t count = std::size_t(map.width) * map.height;
  Slopes s;
  s.sx.resize(count);
  s.sy.resize(count);
  const double step_u = length_u / map.width, step_v = length_v / map.height;
  for (std::size_t p = 0; p < count; ++p) {
    const double nx = 2.0 * map.texels[3 * p] - 1.0, ny = 2.0 * map.texels[3 * p + 1] - 1.0;
    double nz = 2.0 * map.texels[3 * p + 2] - 1.0;
    if (nz < kMinNormalZ) {
      nz = kMinNormalZ;
      ++s.clamped;
    }
    // dH/du = -L_u n_x / n_z per unit u; a row down is a step of -1/height in v.
    s.sx[p] = -nx / nz * step_u;
    s.sy[p] = ny / nz * step_v;
  }
  return s;
}

// y = L x, the grid's graph Laplacian (degree minus neighbours).
void apply_laplacian(const Grid& g, const std::vector<double>& x, std::vector<double>* y) {
  std::fill(y->begin(), y->end(), 0.0);
  for (int row = 0; row < g.height; ++row)
    for (int col = 0; col < g.width; ++col) {
      const std::size_t p = g.at(col, row);
      std::size_t q = 0;
      for (const auto& [dx, dy] : {std::pair{1, 0}, std::pair{0, 1}})
        if (g.next(col, row, dx, dy, &q)) {
          const double d = x[p] - x[q];
          (*y)[p] += d;
          (*y)[q] -= d;
        }
    }
}

// The normal equations' right side: for each edge p -> q with target
// difference d (H_q - H_p = d), -d at p and +d at q.
std::vector<double> divergence(const Grid& g, const Slopes& s) {
  std::vector<double> b(g.size(), 0.0);
  for (int row = 0; row < g.height; ++row)
    for (int col = 0; col < g.width; ++col) {
      const std::size_t p = g.at(col, row);
      std::size_t q = 0;
      if (g.next(col, row, 1, 0, &q)) {
        const double d = 0.5 * (s.sx[p] + s.sx[q]);
        b[p] -= d;
        b[q] += d;
      }
      if (g.next(col, row, 0, 1, &q)) {
        const double d = 0.5 * (s.sy[p] + s.sy[q]);
        b[p] -= d;
        b[q] += d;
      }
    }
  return b;
}

double dot_product(const std::vector<double>& a, const std::vector<double>& b) {
  double sum = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) sum += a[i] * b[i];
  return sum;
}

// Conjugate gradients on L x = b (L singular on constants, b orthogonal to
// them, so the iterates stay in the range), to a residual of 1e-10 |b|.
std::vector<double> solve(const Grid& g, const std::vector<double>& b, int* iterations,
                          bool* converged) {
  std::vector<double> x(g.size(), 0.0), r = b, p = b, lp(g.size());
  double rr = dot_product(r, r);
  const double stop = 1e-20 * std::max(rr, 1e-300);
  const int limit = 20 * (g.width + g.height) + 100;
  int k = 0;
  for (; k < limit && rr > stop; ++k) {
    apply_laplacian(g, p, &lp);
    const double alpha = rr / dot_product(p, lp);
    for (std::size_t i = 0; i < x.size(); ++i) {
      x[i] += alpha * p[i];
      r[i] -= alpha * lp[i];
    }
    const double rr_next = dot_product(r, r);
    const double beta = rr_next / rr;
    rr = rr_next;
    for (std::size_t i = 0; i < p.size(); ++i) p[i] = r[i] + beta * p[i];
  }
  *iterations = k;
  *converged = rr <= stop;
  return x;
}

// The angle between the map's normal and the integrated height's at each
// texel, the height's slope by centred differences (one-sided at a clamped
// border), both per scene unit along u and v (a texel step is step_u right,
// step_v down).
void measure_angles(const Grid& g, const Slopes& s, const std::vector<double>& h, double step_u,
                    double step_v, IntegratedHeight* out) {
  double sum = 0.0;
  const auto slope = [&](int col, int row, int dx, int dy) {
    std::size_t ahead = 0, behind = 0;
    const bool has_ahead = g.next(col, row, dx, dy, &ahead);
    const int bx = col - dx, by = row - dy;
    bool has_behind = bx >= 0 && by >= 0;
    if (has_behind) behind = g.at(bx, by);
    if (!has_behind && g.wrap) {
      behind = g.at((bx + g.width) % g.width, (by + g.height) % g.height);
      has_behind = true;
    }
    const std::size_t p = g.at(col, row);
    if (has_ahead && has_behind) return 0.5 * (h[ahead] - h[behind]);
    return has_ahead ? h[ahead] - h[p] : has_behind ? h[p] - h[behind] : 0.0;
  };
  for (int row = 0; row < g.height; ++row)
    for (int col = 0; col < g.width; ++col) {
      const std::size_t p = g.at(col, row);
      const Vec3 wanted = normalize(Vec3{-s.sx[p] / step_u, s.sy[p] / step_v, 1.0});
      const Vec3 got =
          normalize(Vec3{-slope(col, row, 1, 0) / step_u, slope(col, row, 0, 1) / step_v, 1.0});
      const double angle = std::acos(std::clamp(dot(wanted, got), -1.0, 1.0)) * 180.0 / kPi;
      sum += angle * angle;
      out->largest_angle_deg = std::max(out->largest_angle_deg, angle);
    }
  out->rms_angle_deg = std::sqrt(sum / double(g.size()));
}

}  // namespace

IntegratedHeight integrate_normal_map(const SurfaceMap& map, double length_u, double length_v) {
  Grid g;
  g.width = map.width;
  g.height = map.height;
  g.wrap = map.edge == MapEdge::kWrap;
  const Slopes s = texel_slopes(map, length_u, length_v);
  IntegratedHeight out;
  out.width = map.width;
  out.height = map.height;
  out.clamped = s.clamped;
  std::vector<double> h = solve(g, divergence(g, s), &out.iterations, &out.converged);
  double mean = 0.0;
  for (double x : h) mean += x;
  mean /= double(h.size());
  for (double& x : h) x -= mean;
  measure_angles(g, s, h, length_u / map.width, length_v / map.height, &out);
  out.heights.resize(h.size());
  for (std::size_t i = 0; i < h.size(); ++i) out.heights[i] = float(h[i]);
  return out;
}

}  // namespace penumbra
