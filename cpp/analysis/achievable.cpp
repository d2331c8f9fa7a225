#include "analysis/achievable.h"

#include <Eigen/Dense>
#include <Eigen/Sparse>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <type_traits>

namespace penumbra {

namespace {

// The bins a variant's terminator RMSE is over (compare_profiles): the
// terminator region, where both profiles hold enough pixels.
std::vector<std::size_t> terminator_bins(const TallyVariant& v) {
  const ProfileOptions options;
  std::vector<std::size_t> bins;
  const std::size_t n = std::min(v.tally.count.size(), v.truth.count.size());
  for (std::size_t b = 0; b < n; ++b) {
    const double centre = (double(b) + 0.5) * v.tally.bin_degrees;
    if (centre >= kTerminatorBegin && centre < kTerminatorEnd &&
        v.tally.count[b] >= options.min_count && v.truth.count[b] >= options.min_count)
      bins.push_back(b);
  }
  return bins;
}

// The normal equations of the mean squared error over variants, in the
// cells `index` maps to variables (-1: fixed at 1), and the prior: objective
// = g' h g - 2 f' g + c, h's terms listed in the order they are added.
struct Terms {
  std::vector<Eigen::Triplet<double>> h;
  Eigen::VectorXd f;
};

// The profile bins as rows of a weighted least-squares problem: row r's
// squared residual is weighted by w[r], its coefficients (row, variable,
// value) are in `a`. Their normal equations are summed once (add_gram)
// rather than as each row's outer product: under an area light or an
// environment one bin spreads over hundreds of cells, and the outer
// products of the lighting study's 10^3 bins listed 10^8 triplets.
struct WeightedRows {
  std::vector<Eigen::Triplet<double>> a;
  std::vector<double> w;
};

void add_variant(const TallyVariant& v, const std::vector<int>& index, double weight,
                 WeightedRows& rows, Terms& q) {
  const std::vector<std::size_t> bins = terminator_bins(v);
  if (bins.empty()) return;
  const double w = weight / double(bins.size());
  for (std::size_t b : bins) {
    const double n = double(v.tally.count[b]);
    const int row = static_cast<int>(rows.w.size());
    double y = v.truth.value[b] - v.tally.rest[b] / n;
    const std::size_t first = rows.a.size();
    for (const auto& [cell, light] : v.tally.scaled[b]) {
      if (index[static_cast<std::size_t>(cell)] < 0)
        y -= light / n;  // a fixed cell: G = 1
      else
        rows.a.emplace_back(row, index[static_cast<std::size_t>(cell)], light / n);
    }
    for (std::size_t e = first; e < rows.a.size(); ++e)
      q.f[rows.a[e].col()] += w * rows.a[e].value() * y;
    rows.w.push_back(w);
  }
}

// h += A' diag(w) A, one triplet per nonzero of the sum.
void add_gram(const WeightedRows& rows, Terms& q) {
  const Eigen::Index n = q.f.size();
  Eigen::SparseMatrix<double> a(static_cast<Eigen::Index>(rows.w.size()), n);
  a.setFromTriplets(rows.a.begin(), rows.a.end());
  const Eigen::Map<const Eigen::VectorXd> w(rows.w.data(), Eigen::Index(rows.w.size()));
  const Eigen::SparseMatrix<double> h = a.transpose() * w.asDiagonal() * a;
  for (Eigen::Index col = 0; col < h.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(h, col); it; ++it)
      q.h.emplace_back(int(it.row()), int(it.col()), it.value());
}

// Squared second differences along each axis and (G - 1)^2, each a mean
// over its terms.
void add_prior(const FactorGrid& grid, const std::vector<int>& index,
               const std::vector<char>& constrained, const FloorOptions& o, Terms& q) {
  const int cells = grid.cells();
  std::vector<std::array<int, 3>> terms;
  int stride = 1;
  for (const FactorAxis& axis : grid.axes) {
    const int n = axis.cells();
    for (int c = 0; c < cells; ++c) {
      const int k = (c / stride) % n;
      if (k == 0 || k == n - 1) continue;
      const std::array<int, 3> t{index[std::size_t(c - stride)], index[std::size_t(c)],
                                 index[std::size_t(c + stride)]};
      if (t[0] >= 0 && t[1] >= 0 && t[2] >= 0) terms.push_back(t);
    }
    stride *= n;
  }
  const double w = terms.empty() ? 0.0 : o.smoothness / double(terms.size());
  const double coefficient[3] = {1.0, -2.0, 1.0};
  for (const auto& t : terms)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) q.h.emplace_back(t[a], t[b], w * coefficient[a] * coefficient[b]);
  // The ridge ties only the cells no variant lights (their G is otherwise
  // any linear continuation of their neighbours); lit cells stay unbiased.
  const double r = o.ridge / double(std::max<Eigen::Index>(1, q.f.size()));
  for (std::size_t c = 0; c < index.size(); ++c)
    if (index[c] >= 0 && !constrained[c])
      q.h.emplace_back(index[c], index[c], r), q.f[index[c]] += r;
}

// The quadratic with h dense or sparse (Matrix: Eigen::MatrixXd or
// Eigen::SparseMatrix<double>).
template <typename Matrix>
struct Quadratic {
  Matrix h;
  Eigen::VectorXd f;
};

Quadratic<Eigen::MatrixXd> dense(const Terms& t) {
  const Eigen::Index n = t.f.size();
  Quadratic<Eigen::MatrixXd> q{Eigen::MatrixXd::Zero(n, n), t.f};
  for (const Eigen::Triplet<double>& e : t.h) q.h(e.row(), e.col()) += e.value();
  return q;
}

Quadratic<Eigen::SparseMatrix<double>> sparse(const Terms& t) {
  const Eigen::Index n = t.f.size();
  Quadratic<Eigen::SparseMatrix<double>> q{Eigen::SparseMatrix<double>(n, n), t.f};
  q.h.setFromTriplets(t.h.begin(), t.h.end());
  return q;
}

// The largest violation of the bounded problem's optimality conditions.
template <typename Matrix>
double kkt_residual(const Quadratic<Matrix>& q, const Eigen::VectorXd& x, const FloorOptions& o) {
  const Eigen::VectorXd grad = 2.0 * (q.h * x - q.f);
  double worst = 0.0;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    const double v = x[i] <= o.g_min   ? std::max(0.0, -grad[i])
                     : x[i] >= o.g_max ? std::max(0.0, grad[i])
                                       : std::abs(grad[i]);
    worst = std::max(worst, v);
  }
  return worst;
}

Eigen::VectorXd clamp(Eigen::VectorXd x, const FloorOptions& o) {
  return x.cwiseMax(o.g_min).cwiseMin(o.g_max);
}

// Accelerated projected gradient (FISTA) from G = 1: finds the active set.
template <typename Matrix>
Eigen::VectorXd projected_gradient(const Quadratic<Matrix>& q, const FloorOptions& o,
                                   int* iterations) {
  const Eigen::Index n = q.f.size();
  // A fixed start (not Eigen's Random, which draws from std::rand).
  Eigen::VectorXd v(n);
  for (Eigen::Index i = 0; i < n; ++i) v[i] = 1.0 + 0.5 * std::sin(double(i));
  double lipschitz = 1.0;
  for (int k = 0; k < 50; ++k) {  // power iteration on the PSD h
    const Eigen::VectorXd w = q.h * v;
    lipschitz = w.norm() / std::max(v.norm(), 1e-300);
    v = w / std::max(w.norm(), 1e-300);
  }
  const double step = 1.0 / (2.0 * lipschitz * 1.01 + 1e-300);
  Eigen::VectorXd x = clamp(Eigen::VectorXd::Ones(n), o), y = x;
  const double scale = std::max(2.0 * q.f.template lpNorm<Eigen::Infinity>(), 1e-300);
  double t = 1.0;
  for (*iterations = 0; *iterations < o.max_iterations; ++*iterations) {
    const Eigen::VectorXd next = clamp(y - step * 2.0 * (q.h * y - q.f), o);
    const double t_next = 0.5 * (1.0 + std::sqrt(1.0 + 4.0 * t * t));
    y = next + ((t - 1.0) / t_next) * (next - x);
    x = next, t = t_next;
    // Relative to the gradient's scale at G = 0: the active-set solve
    // after this makes the free cells exact, so this need only find the
    // bounds that hold.
    if (*iterations % 50 == 49 && kkt_residual(q, x, o) < 1e-9 * scale) break;
  }
  return x;
}

// The free cells' normal equations solved, the others held at x. Dense:
// Eigen's LDLT, whose pivoting also solves the semidefinite systems of a
// floor without a prior (fewer lit bins than cells). Sparse: a simplicial
// LDLT without a prior, conjugate gradients with one.
Eigen::VectorXd solve_free(const Quadratic<Eigen::MatrixXd>& q, const Eigen::VectorXd& x,
                           const std::vector<Eigen::Index>& free, const FloorOptions&) {
  const Eigen::Index m = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd hff(m, m);
  Eigen::VectorXd rhs(m);
  for (Eigen::Index a = 0; a < m; ++a) {
    rhs[a] = q.f[free[a]] - q.h.row(free[a]).dot(x) + q.h.row(free[a])(free).dot(x(free));
    for (Eigen::Index b = 0; b < m; ++b) hff(a, b) = q.h(free[a], free[b]);
  }
  return hff.ldlt().solve(rhs);
}

// The sparse solve's relative residual and its most iterations.
constexpr double kSparseTolerance = 1e-10;
constexpr int kSparseIterations = 200;

Eigen::VectorXd solve_free(const Quadratic<Eigen::SparseMatrix<double>>& q,
                           const Eigen::VectorXd& x, const std::vector<Eigen::Index>& free,
                           const FloorOptions& o) {
  const Eigen::Index m = static_cast<Eigen::Index>(free.size());
  std::vector<Eigen::Index> position(static_cast<std::size_t>(x.size()), -1);
  Eigen::VectorXd held = x;
  for (Eigen::Index a = 0; a < m; ++a) position[std::size_t(free[a])] = a, held[free[a]] = 0.0;
  std::vector<Eigen::Triplet<double>> terms;
  for (Eigen::Index col = 0; col < q.h.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(q.h, col); it; ++it)
      if (position[std::size_t(it.row())] >= 0 && position[std::size_t(it.col())] >= 0)
        terms.emplace_back(position[std::size_t(it.row())], position[std::size_t(it.col())],
                           it.value());
  // Without a prior the free cells' system can be semidefinite (cells
  // that the same pixels always light together): a proximal term
  // delta |x_f - x|^2, delta a 1e-9 of the mean diagonal, makes it definite
  // and leaves x where the data do not decide, moving the objective by
  // delta times the step's squared length.
  double delta = 0.0;
  if (o.smoothness <= 0.0) {
    for (const auto& t : terms)
      if (t.row() == t.col()) delta += t.value();
    delta *= 1e-9 / double(std::max<Eigen::Index>(1, m));
    for (Eigen::Index a = 0; a < m; ++a) terms.emplace_back(a, a, delta);
  }
  Eigen::SparseMatrix<double> hff(m, m);
  hff.setFromTriplets(terms.begin(), terms.end());
  const Eigen::VectorXd pushed = q.h * held;
  Eigen::VectorXd rhs(m);
  for (Eigen::Index a = 0; a < m; ++a) rhs[a] = q.f[free[a]] - pushed[free[a]] + delta * x[free[a]];
  if (o.smoothness <= 0.0) {
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(hff);
    if (ldlt.info() != Eigen::Success) return x(free);  // not definite: leave x as it is
    return ldlt.solve(rhs);
  }
  // With a prior every cell is a variable, coupled to its neighbours along
  // each axis: a complete factor of a grid with a third input fills in, so
  // conjugate gradients from x, preconditioned by an incomplete Cholesky
  // factor. The lit cells of a floor without one couple more sparsely and
  // factor faster than they iterate.
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper,
                           Eigen::IncompleteCholesky<double>>
      cg;
  cg.setTolerance(kSparseTolerance);
  cg.setMaxIterations(kSparseIterations);
  cg.compute(hff);
  if (cg.info() != Eigen::Success) return x(free);  // no preconditioner: leave x as it is
  return cg.solveWithGuess(rhs, Eigen::VectorXd(x(free)));
}

constexpr int kSparseActiveSetRounds = 8;

double objective(const auto& q, const Eigen::VectorXd& g) {
  return g.dot(q.h * g) - 2.0 * q.f.dot(g);
}

// Cells strictly inside the bounds solve their normal equations exactly,
// the others held at their bound; repeated while a solve leaves the bounds
// or a held cell's gradient points inside, at most `rounds` times. Clamping
// a whole solve can cycle between active sets: with `keep_lowest`, the
// round of the lowest objective is returned rather than the last.
template <typename Matrix>
Eigen::VectorXd active_set(const Quadratic<Matrix>& q, Eigen::VectorXd x, const FloorOptions& o,
                           int rounds, bool keep_lowest) {
  const Eigen::Index n = x.size();
  Eigen::VectorXd lowest = x;
  double lowest_value = objective(q, x);
  for (int round = 0; round < rounds; ++round) {
    const Eigen::VectorXd grad = 2.0 * (q.h * x - q.f);
    std::vector<Eigen::Index> free;
    for (Eigen::Index i = 0; i < n; ++i) {
      const bool low = x[i] <= o.g_min && grad[i] >= 0.0;
      const bool high = x[i] >= o.g_max && grad[i] <= 0.0;
      if (!low && !high) free.push_back(i);
    }
    if (free.empty()) break;
    const Eigen::VectorXd solved = solve_free(q, x, free, o);
    const Eigen::VectorXd before = x;
    for (std::size_t a = 0; a < free.size(); ++a) x[free[a]] = solved[Eigen::Index(a)];
    x = clamp(x, o);
    if (const double v = objective(q, x); keep_lowest && v <= lowest_value)
      lowest = x, lowest_value = v;
    if ((x - before).lpNorm<Eigen::Infinity>() < 1e-15) break;
  }
  return keep_lowest ? lowest : x;
}

bool sparse_solve(const FloorOptions& options, int variables) {
  return variables > options.dense_variables;
}

// The bounded minimum of q (FloorSolution's iterations, KKT residual).
template <typename Matrix>
Eigen::VectorXd minimise(const Quadratic<Matrix>& q, const FloorOptions& options,
                         FloorSolution& s) {
  Eigen::VectorXd x = projected_gradient(q, options, &s.iterations);
  // The active-set solve is exact where the free cells' system is well
  // posed and the active set settles; where it is singular (fewer lit
  // profile bins than cells) it can land above its start, so the lower of
  // the two is kept. A sparse solve has fewer rounds, each a factorisation
  // of thousands of cells, and keeps its lowest.
  const bool sparse = std::is_same_v<Matrix, Eigen::SparseMatrix<double>>;
  const Eigen::VectorXd refined =
      active_set(q, x, options, sparse ? kSparseActiveSetRounds : 100, sparse);
  if (objective(q, refined) <= objective(q, x)) x = refined;
  s.kkt_residual = kkt_residual(q, x, options);
  return x;
}

}  // namespace

ProfileTally profile_tally(const Image& image, const PixelTally& tally, double radiance_scale,
                           const ProfileOptions& options) {
  const int alpha = image.channel_index("A"), theta = image.channel_index("analysis.theta");
  if (alpha < 0 || theta < 0)
    throw std::invalid_argument("a tally needs the evaluator's A and analysis.theta channels");
  if (tally.width != image.width || tally.height != image.height)
    throw std::invalid_argument("the tally and the image differ in size");
  ProfileTally t;
  t.bin_degrees = options.bin_degrees;
  const std::size_t bins = static_cast<std::size_t>(std::ceil(180.0 / options.bin_degrees));
  t.count.assign(bins, 0);
  t.rest.assign(bins, 0.0);
  std::vector<std::map<int, double>> scaled(bins);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      if (image.at(x, y, alpha) < options.min_coverage) continue;
      const double angle = image.at(x, y, theta);
      if (!std::isfinite(angle)) continue;
      const auto k =
          std::min(bins - 1, static_cast<std::size_t>(std::max(0.0, angle) / options.bin_degrees));
      const std::size_t p = static_cast<std::size_t>(y) * std::size_t(image.width) + std::size_t(x);
      ++t.count[k];
      t.rest[k] += tally.rest[p] / radiance_scale;
      for (std::uint32_t e = tally.offsets[p]; e < tally.offsets[p + 1]; ++e)
        scaled[k][tally.cells[e]] += tally.light[e] / radiance_scale;
    }
  t.scaled.resize(bins);
  for (std::size_t k = 0; k < bins; ++k) t.scaled[k].assign(scaled[k].begin(), scaled[k].end());
  return t;
}

ProfileTally marginal_tally(const ProfileTally& t, const FactorGrid& from, const FactorGrid& to) {
  // Per axis of `from`: its stride in `to`, 0 where it is summed out.
  std::vector<int> to_stride(from.axes.size(), 0);
  for (std::size_t b = 0, stride = 1; b < to.axes.size(); ++b) {
    const FactorAxis& axis = to.axes[b];
    const auto same = [&axis](const FactorAxis& a) {
      return a.input == axis.input && a.min_deg == axis.min_deg && a.max_deg == axis.max_deg &&
             a.step_deg == axis.step_deg;
    };
    const auto it = std::find_if(from.axes.begin(), from.axes.end(), same);
    if (it == from.axes.end())
      throw std::invalid_argument("marginal_tally: an axis of the target grid is not the source's");
    to_stride[std::size_t(it - from.axes.begin())] = int(stride);
    stride *= std::size_t(axis.cells());
  }
  const auto target = [&](int cell) {
    int index = 0;
    for (std::size_t a = 0; a < from.axes.size(); ++a) {
      const int n = from.axes[a].cells();
      index += (cell % n) * to_stride[a];
      cell /= n;
    }
    return index;
  };
  ProfileTally m = t;
  for (auto& bin : m.scaled) {
    std::map<int, double> summed;
    for (const auto& [cell, light] : bin) summed[target(cell)] += light;
    bin.assign(summed.begin(), summed.end());
  }
  return m;
}

Profile ProfileTally::profile(const std::vector<double>& g) const {
  Profile p;
  p.bin_degrees = bin_degrees;
  p.count = count;
  p.value.assign(count.size(), 0.0);
  for (std::size_t b = 0; b < count.size(); ++b) {
    if (!count[b]) continue;
    double light = rest[b];
    for (const auto& [cell, value] : scaled[b]) light += value * g[static_cast<std::size_t>(cell)];
    p.value[b] = light / double(count[b]);
  }
  return p;
}

double tally_rmse(const TallyVariant& v, const std::vector<double>& g) {
  return compare_profiles(v.tally.profile(g), v.truth).rmse_terminator;
}

namespace {

// The bounded minimum (FloorOptions) of the terms `add_rows(index, terms)`
// adds, plus the prior, over every cell with a prior and over the cells
// s->constrained marks without one: the others stay 1. Into s->g.
template <typename AddRows>
void solve_cells(const FactorGrid& grid, const FloorOptions& options, AddRows&& add_rows,
                 FloorSolution* s) {
  const int cells = grid.cells();
  std::vector<int> index(static_cast<std::size_t>(cells), -1);
  int n = 0;
  for (int c = 0; c < cells; ++c)
    if (options.smoothness > 0.0 || s->constrained[static_cast<std::size_t>(c)]) index[c] = n++;
  Terms terms{{}, Eigen::VectorXd::Zero(n)};
  add_rows(index, terms);
  add_prior(grid, index, s->constrained, options, terms);
  const Eigen::VectorXd x = sparse_solve(options, n) ? minimise(sparse(terms), options, *s)
                                                     : minimise(dense(terms), options, *s);
  s->g.assign(static_cast<std::size_t>(cells), 1.0);
  for (int c = 0; c < cells; ++c)
    if (index[c] >= 0) s->g[static_cast<std::size_t>(c)] = x[index[c]];
}

// The mean over pixel rows of the squared error, as Terms: each covered
// pixel a row of equal weight, summed once as the profile bins are.
void add_pixel_rows(const PixelRows& rows, const std::vector<int>& index, Terms& q) {
  WeightedRows weighted;
  const double w = 1.0 / double(rows.rows());
  for (std::size_t r = 0; r < rows.rows(); ++r) {
    const int row = static_cast<int>(r);
    double y = rows.target[r];
    const std::size_t first = weighted.a.size();
    for (std::uint32_t e = rows.offsets[r]; e < rows.offsets[r + 1]; ++e) {
      const int i = index[static_cast<std::size_t>(rows.cells[e])];
      if (i < 0)
        y -= rows.light[e];  // a fixed cell: G = 1
      else
        weighted.a.emplace_back(row, i, rows.light[e]);
    }
    for (std::size_t e = first; e < weighted.a.size(); ++e)
      q.f[weighted.a[e].col()] += w * weighted.a[e].value() * y;
    weighted.w.push_back(w);
  }
  add_gram(weighted, q);
}

}  // namespace

FloorSolution solve_floor(const FactorGrid& grid, const std::vector<TallyVariant>& variants,
                          const FloorOptions& options) {
  FloorSolution s;
  s.constrained.assign(static_cast<std::size_t>(grid.cells()), 0);
  for (const TallyVariant& v : variants)
    for (std::size_t b : terminator_bins(v))
      for (const auto& [cell, light] : v.tally.scaled[b])
        if (light != 0.0) s.constrained[static_cast<std::size_t>(cell)] = 1;
  solve_cells(
      grid, options,
      [&](const std::vector<int>& index, Terms& terms) {
        WeightedRows rows;
        for (const TallyVariant& v : variants)
          add_variant(v, index, 1.0 / double(variants.size()), rows, terms);
        add_gram(rows, terms);
      },
      &s);
  for (const TallyVariant& v : variants) {
    s.variant_rmse.push_back(tally_rmse(v, s.g));
    if (std::isfinite(s.variant_rmse.back()))
      s.objective += s.variant_rmse.back() * s.variant_rmse.back() / double(variants.size());
  }
  return s;
}

PixelRows pixel_rows(const Image& render, const Image& truth, const PixelTally& tally,
                     double radiance_scale, double min_coverage) {
  if (tally.width != render.width || tally.height != render.height || truth.width != render.width ||
      truth.height != render.height)
    throw std::invalid_argument("pixel_rows: the tally, the render and the truth differ in size");
  const auto rgb = [](const Image& im) {
    const std::array<int, 4> c{im.channel_index("R"), im.channel_index("G"), im.channel_index("B"),
                               im.channel_index("A")};
    if (*std::min_element(c.begin(), c.end()) < 0)
      throw std::invalid_argument("pixel_rows: an image without R, G, B and A");
    return c;
  };
  const std::array<int, 4> rc = rgb(render), tc = rgb(truth);
  // As compare_images reads a pixel: (R + G + B) / 3 in float.
  const auto value = [](const Image& im, const std::array<int, 4>& c, int x, int y) {
    return (im.at(x, y, c[0]) + im.at(x, y, c[1]) + im.at(x, y, c[2])) / 3.0f;
  };
  PixelRows rows;
  for (int y = 0; y < render.height; ++y)
    for (int x = 0; x < render.width; ++x) {
      const float ar = render.at(x, y, rc[3]), at = truth.at(x, y, tc[3]);
      if (!(ar >= min_coverage) || !(at >= min_coverage)) continue;
      const float vr = value(render, rc, x, y), vt = value(truth, tc, x, y);
      if (!std::isfinite(vr) || !std::isfinite(vt)) continue;
      const std::size_t p =
          static_cast<std::size_t>(y) * std::size_t(render.width) + std::size_t(x);
      rows.target.push_back((double(vt) - tally.rest[p]) / radiance_scale);
      for (std::uint32_t e = tally.offsets[p]; e < tally.offsets[p + 1]; ++e) {
        rows.cells.push_back(tally.cells[e]);
        rows.light.push_back(tally.light[e] / radiance_scale);
      }
      rows.offsets.push_back(static_cast<std::uint32_t>(rows.cells.size()));
    }
  return rows;
}

double pixel_rmse(const PixelRows& rows, const std::vector<double>& g) {
  if (rows.rows() == 0) return std::numeric_limits<double>::quiet_NaN();
  double sum = 0.0;
  for (std::size_t r = 0; r < rows.rows(); ++r) {
    double d = -rows.target[r];
    for (std::uint32_t e = rows.offsets[r]; e < rows.offsets[r + 1]; ++e)
      d += rows.light[e] * g[static_cast<std::size_t>(rows.cells[e])];
    sum += d * d;
  }
  return std::sqrt(sum / double(rows.rows()));
}

FloorSolution solve_image_floor(const FactorGrid& grid, const PixelRows& rows,
                                const FloorOptions& options) {
  FloorSolution s;
  s.constrained.assign(static_cast<std::size_t>(grid.cells()), 0);
  for (std::size_t e = 0; e < rows.cells.size(); ++e)
    if (rows.light[e] != 0.0) s.constrained[static_cast<std::size_t>(rows.cells[e])] = 1;
  if (rows.rows() > 0)
    solve_cells(
        grid, options,
        [&](const std::vector<int>& index, Terms& terms) { add_pixel_rows(rows, index, terms); },
        &s);
  else
    s.g.assign(static_cast<std::size_t>(grid.cells()), 1.0);
  s.variant_rmse = {pixel_rmse(rows, s.g)};
  s.objective = std::isfinite(s.variant_rmse[0]) ? s.variant_rmse[0] * s.variant_rmse[0] : 0.0;
  return s;
}

}  // namespace penumbra
