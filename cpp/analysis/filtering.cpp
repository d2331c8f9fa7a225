#include "analysis/filtering.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <random>
#include <stdexcept>

#include "core/filtered_lobe.h"
#include "util/parallel.h"

namespace penumbra {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Light directions: plane x-z, then plane y-z, each from -max to +max.
struct Sweep {
  std::vector<Vec3> wi;
  std::vector<double> theta_deg;  // per direction of one plane
  std::size_t per_plane = 0;
};

Sweep make_sweep(const FilteringOptions& o) {
  Sweep s;
  const int steps = int(std::floor(2.0 * o.sweep_max_deg / o.sweep_step_deg + 1e-9));
  for (int i = 0; i <= steps; ++i) s.theta_deg.push_back(-o.sweep_max_deg + i * o.sweep_step_deg);
  s.per_plane = s.theta_deg.size();
  for (int plane = 0; plane < 2; ++plane)
    for (double theta : s.theta_deg) {
      const double t = radians(theta);
      s.wi.push_back(plane == 0 ? Vec3(std::sin(t), 0.0, std::cos(t))
                                : Vec3(0.0, std::sin(t), std::cos(t)));
    }
  return s;
}

// The plane's normal for an offset: z = h(x, y) has normal (-h_x, -h_y, 1),
// and u, v run along x, y.
Vec3 world_normal(double f_u, double f_v) {
  return normalize(Vec3(-f_u, -f_v, 1.0));
}

// A frame around n whose first axis is x projected onto the tangent plane,
// so that K's axes (u, v) stay the lobe's axes under small tilts.
Frame tangent_frame(const Vec3& n) {
  const Vec3 s = normalize(Vec3(1.0, 0.0, 0.0) - n * n.x);
  return {s, cross(n, s), n};
}

// Adds weight * f(wi, wo) <n, wi> for every sweep direction (E = 1).
void add_profile(const Vec3& n, FilteredDistribution d, const Covariance2& a, const Sweep& sweep,
                 const Vec3& wo, double weight, double* profile) {
  const Frame frame = tangent_frame(n);
  const Vec3 wo_l = frame.to_local(wo);
  if (wo_l.z <= 0.0) return;
  for (std::size_t i = 0; i < sweep.wi.size(); ++i) {
    const Vec3 wi_l = frame.to_local(sweep.wi[i]);
    if (wi_l.z > 0.0) profile[i] += weight * lobe_brdf(d, a, wi_l, wo_l) * wi_l.z;
  }
}

// Degrees of light angle between the profile's 25 % and 75 % energy points.
double interquartile_width(const double* p, const std::vector<double>& theta) {
  double total = 0.0;
  for (std::size_t i = 0; i < theta.size(); ++i) total += p[i];
  if (!(total > 0.0)) return kNaN;
  const auto crossing = [&](double fraction) {
    double cumulative = 0.0;
    for (std::size_t i = 0; i < theta.size(); ++i) {
      const double next = cumulative + p[i];
      if (next >= fraction * total) {
        // The sample's energy spreads over its step, linearly.
        const double step = i + 1 < theta.size() ? theta[i + 1] - theta[i] : theta[1] - theta[0];
        return theta[i] - 0.5 * step + step * (fraction * total - cumulative) / p[i];
      }
      cumulative = next;
    }
    return theta.back();
  };
  return crossing(0.75) - crossing(0.25);
}

struct FootprintMetrics {
  double energy = kNaN, width = kNaN, error = kNaN;
};

FootprintMetrics compare(const std::vector<double>& filtered, const std::vector<double>& reference,
                         const Sweep& sweep) {
  FootprintMetrics m;
  double sum_f = 0, sum_r = 0, diff2 = 0, ref2 = 0;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    sum_f += filtered[i];
    sum_r += reference[i];
    diff2 += (filtered[i] - reference[i]) * (filtered[i] - reference[i]);
    ref2 += reference[i] * reference[i];
  }
  if (!(sum_r > 0.0)) return m;
  m.energy = sum_f / sum_r;
  m.error = std::sqrt(diff2 / ref2);
  double log_ratio = 0.0;
  for (int plane = 0; plane < 2; ++plane) {
    const std::size_t at = plane * sweep.per_plane;
    const double w_f = interquartile_width(filtered.data() + at, sweep.theta_deg);
    const double w_r = interquartile_width(reference.data() + at, sweep.theta_deg);
    log_ratio += std::log(w_f / w_r);  // NaN or inf where undefined
  }
  m.width = std::exp(0.5 * log_ratio);
  if (!std::isfinite(m.width)) m.width = kNaN;
  return m;
}

// Length of [a, a + 1) inside [lo, hi).
double overlap(int a, double lo, double hi) {
  return std::max(0.0, std::min(a + 1.0, hi) - std::max(double(a), lo));
}

// Calls visit(offset, weight) for every finest texel in the square
// [x0, x0 + size) x [y0, y0 + size), weights = area / size^2 (tiled map).
template <typename Visit>
void for_each_covered(const PyramidLevel& finest, double x0, double y0, double size,
                      Visit&& visit) {
  for (int j = int(std::floor(y0)); j < int(std::ceil(y0 + size)); ++j)
    for (int i = int(std::floor(x0)); i < int(std::ceil(x0 + size)); ++i) {
      const double weight = overlap(i, x0, x0 + size) * overlap(j, y0, y0 + size) / (size * size);
      if (weight > 0.0)
        visit(finest.offset(((i % finest.width) + finest.width) % finest.width,
                            ((j % finest.height) + finest.height) % finest.height),
              weight);
    }
}

// The exact moments of the square footprint centred at (cx, cy).
FilteredTexel box_moments(const PyramidLevel& finest, double cx, double cy, double size) {
  FilteredTexel t;
  double suu = 0, suv = 0, svv = 0;
  for_each_covered(finest, cx - 0.5 * size, cy - 0.5 * size, size, [&](const Offset2& f, double w) {
    t.mean.f_u += w * f.f_u;
    t.mean.f_v += w * f.f_v;
    suu += w * f.f_u * f.f_u;
    suv += w * f.f_u * f.f_v;
    svv += w * f.f_v * f.f_v;
    t.mean_normal += normalize(Vec3(f.f_u, f.f_v, 1.0)) * w;
  });
  t.covariance = {std::max(suu - t.mean.f_u * t.mean.f_u, 0.0), suv - t.mean.f_u * t.mean.f_v,
                  std::max(svv - t.mean.f_v * t.mean.f_v, 0.0)};
  return t;
}

// What the filters read for the footprint of `size` finest texels centred
// at (cx, cy): K and the mean normal's length (box or trilinear), and the
// per-pixel change of the shading normal to the neighbouring footprints
// (central differences).
struct Lookup {
  Vec3 normal;
  FootprintStatistics stats;
};
Lookup lookup(const std::vector<PyramidLevel>& pyramid, double cx, double cy, double size,
              FilteringOptions::Lookup kind) {
  const auto read = [&](double x, double y) {
    return kind == FilteringOptions::Lookup::kBox
               ? box_moments(pyramid[0], x, y, size)
               : sample_pyramid(pyramid, x, y, size, MapEdge::kWrap);
  };
  const auto normal_at = [&](double x, double y) {
    const FilteredTexel t = read(x, y);
    return world_normal(t.mean.f_u, t.mean.f_v);
  };
  const FilteredTexel centre = read(cx, cy);
  const Vec3 dx = (normal_at(cx + size, cy) - normal_at(cx - size, cy)) * 0.5;
  const Vec3 dy = (normal_at(cx, cy + size) - normal_at(cx, cy - size)) * 0.5;
  return {world_normal(centre.mean.f_u, centre.mean.f_v),
          {centre.covariance, length(centre.mean_normal), length_squared(dx) + length_squared(dy)}};
}

// Texels of `level` to measure: all, or `count` drawn without replacement.
std::vector<std::pair<int, int>> pick_footprints(const PyramidLevel& level, int count,
                                                 std::uint64_t seed) {
  std::vector<std::pair<int, int>> all;
  for (int y = 0; y < level.height; ++y)
    for (int x = 0; x < level.width; ++x) all.emplace_back(x, y);
  if (int(all.size()) <= count) return all;
  std::mt19937_64 rng(seed);
  for (int i = 0; i < count; ++i) std::swap(all[i], all[i + uniform_index(rng, all.size() - i)]);
  all.resize(count);
  return all;
}

// Metrics of every (alpha, filter) at one footprint, [alpha][filter].
using FootprintTable = std::vector<std::vector<FootprintMetrics>>;

// A footprint: level l's texel (x, y), its square moved by (sx, sy) pixels.
struct Footprint {
  int level, x, y;
  double sx, sy;
};

FootprintTable measure_footprint(const std::vector<PyramidLevel>& pyramid, const Footprint& fp,
                                 const FilteringOptions& o, const Sweep& sweep) {
  const int l = fp.level;
  const std::size_t n_dir = sweep.wi.size();
  const Vec3 wo{std::sin(radians(o.view_deg)), 0.0, std::cos(radians(o.view_deg))};
  std::vector<std::vector<double>> reference(o.alphas.size(), std::vector<double>(n_dir, 0.0));
  const PyramidLevel& finest = pyramid[0];
  const double size = double(1L << l);
  const double x0 = (fp.x + fp.sx) * size, y0 = (fp.y + fp.sy) * size;
  for_each_covered(finest, x0, y0, size, [&](const Offset2& f, double weight) {
    const Vec3 n = world_normal(f.f_u, f.f_v);
    for (std::size_t a = 0; a < o.alphas.size(); ++a) {
      const double a2 = o.alphas[a] * o.alphas[a];
      add_profile(n, FilteredDistribution::kGgx, {a2, 0.0, a2}, sweep, wo, weight,
                  reference[a].data());
    }
  });
  const Lookup filtered_at = lookup(pyramid, x0 + 0.5 * size, y0 + 0.5 * size, size, o.lookup);
  const Vec3& n_mean = filtered_at.normal;
  const FootprintStatistics& stats = filtered_at.stats;
  FootprintTable table(o.alphas.size());
  for (std::size_t a = 0; a < o.alphas.size(); ++a)
    for (RoughnessFilter filter : o.filters) {
      FilterSettings settings;
      settings.filter = filter;
      const FilteredLobe lobe = filter_roughness(settings, stats, o.alphas[a]);
      std::vector<double> filtered(n_dir, 0.0);
      add_profile(n_mean, lobe.distribution, lobe.alpha2, sweep, wo, 1.0, filtered.data());
      table[a].push_back(compare(filtered, reference[a], sweep));
    }
  return table;
}

MeanWithInterval summarise(const std::vector<double>& values) {
  std::vector<double> defined;
  for (double v : values)
    if (std::isfinite(v)) defined.push_back(v);
  MeanWithInterval m;
  m.n = defined.size();
  if (defined.empty()) return {kNaN, {kNaN, kNaN}, 0};
  for (double v : defined) m.mean += v / double(defined.size());
  m.interval = bootstrap_mean_interval(defined, 0.95, 2000, 1);
  return m;
}

void summarise_filters(const std::vector<FootprintTable>& tables,
                       const std::vector<std::size_t>& level_begin, const FilteringOptions& o,
                       FilteringResult& result) {
  // Levels >= 1 only: at level 0 every filter but LEAN's Beckmann lobe is
  // the reference itself.
  const std::size_t first = level_begin.size() > 2 ? level_begin[1] : 0;
  std::vector<std::vector<double>> errors(o.filters.size());
  for (std::size_t fi = 0; fi < o.filters.size(); ++fi) {
    std::vector<double> energy, width;
    for (std::size_t t = first; t < tables.size(); ++t) {
      double e = 0, w = 0, err = 0;
      for (std::size_t a = 0; a < o.alphas.size(); ++a) {
        e += tables[t][a][fi].energy / double(o.alphas.size());
        w += std::log(tables[t][a][fi].width) / double(o.alphas.size());
        err += tables[t][a][fi].error / double(o.alphas.size());
      }
      energy.push_back(e);
      width.push_back(std::exp(w));
      errors[fi].push_back(err);
    }
    result.summary.push_back(
        {o.filters[fi], summarise(energy), summarise(width), summarise(errors[fi])});
  }
  std::vector<std::size_t> order(o.filters.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const double ea = result.summary[a].profile_error.mean,
                 eb = result.summary[b].profile_error.mean;
    return std::isnan(eb) ? !std::isnan(ea) : ea < eb;
  });
  std::vector<FilterSummary> sorted;
  for (std::size_t i : order) sorted.push_back(result.summary[i]);
  result.summary = sorted;
  if (order.size() >= 2)
    result.best_against_runner_up = compare_paired(errors[order[0]], errors[order[1]]);
}

void check_options(const std::vector<PyramidLevel>& pyramid, const FilteringOptions& o) {
  if (pyramid.empty()) throw std::invalid_argument("no pyramid levels");
  if (o.alphas.empty() || o.filters.empty() || o.footprints < 1 || o.max_level < 0 ||
      !(o.sweep_step_deg > 0.0) || !(o.sweep_max_deg > 0.0 && o.sweep_max_deg < 90.0) ||
      !(o.shift >= 0.0 && o.shift < 1.0))
    throw std::invalid_argument("filtering options out of their domains");
  for (double alpha : o.alphas)
    if (!(alpha > 0.0 && alpha <= 1.0)) throw std::invalid_argument("alpha must lie in (0, 1]");
}

}  // namespace

bool is_measurable(RoughnessFilter filter) {
  return roughness_filter_info(filter).distribution != FilteredDistribution::kSchillingBlinnPhong;
}

std::vector<RoughnessFilter> measurable_filters() {
  std::vector<RoughnessFilter> filters;
  for (const RoughnessFilterInfo& f : all_roughness_filters())
    if (is_measurable(f.filter)) filters.push_back(f.filter);
  return filters;
}

FilteringResult run_filtering_experiment(
    const std::vector<PyramidLevel>& pyramid, const FilteringOptions& options,
    const std::function<void(std::size_t, std::size_t)>& progress) {
  FilteringOptions o = options;
  if (o.filters.empty()) o.filters = measurable_filters();
  check_options(pyramid, o);
  const Sweep sweep = make_sweep(o);
  const int levels = std::min<int>(o.max_level + 1, int(pyramid.size()));
  std::vector<Footprint> tasks;
  std::vector<std::size_t> level_begin;
  std::mt19937_64 shifts(o.seed ^ 0x5eedf00dULL);
  const auto draw = [&] { return o.random_shift ? double(shifts() >> 11) * 0x1.0p-53 : o.shift; };
  for (int l = 0; l < levels; ++l) {
    level_begin.push_back(tasks.size());
    for (const auto& [x, y] : pick_footprints(pyramid[l], o.footprints, o.seed + l)) {
      const double sx = draw(), sy = draw();
      tasks.push_back({l, x, y, sx, sy});
    }
  }
  level_begin.push_back(tasks.size());
  std::vector<FootprintTable> tables(tasks.size());
  std::atomic<std::size_t> done{0};
  std::mutex progress_mutex;
  run_parallel(o.jobs, tasks.size(), [&](std::size_t t) {
    tables[t] = measure_footprint(pyramid, tasks[t], o, sweep);
    const std::size_t finished = ++done;
    if (progress) {
      const std::lock_guard lock(progress_mutex);
      progress(finished, tasks.size());
    }
  });
  FilteringResult result;
  result.levels = levels;
  result.filters = o.filters;
  result.footprints = tasks.size();
  for (std::size_t fi = 0; fi < o.filters.size(); ++fi)
    for (std::size_t a = 0; a < o.alphas.size(); ++a)
      for (int l = 0; l < levels; ++l) {
        std::vector<double> energy, width, error;
        for (std::size_t t = level_begin[l]; t < level_begin[l + 1]; ++t) {
          energy.push_back(tables[t][a][fi].energy);
          width.push_back(tables[t][a][fi].width);
          error.push_back(tables[t][a][fi].error);
        }
        result.cells.push_back(
            {o.filters[fi], o.alphas[a], l, summarise(energy), summarise(width), summarise(error)});
      }
  summarise_filters(tables, level_begin, o, result);
  const auto index_of = [&](RoughnessFilter f) {
    return std::size_t(std::find(o.filters.begin(), o.filters.end(), f) - o.filters.begin());
  };
  const std::size_t ggx = index_of(RoughnessFilter::kGgxVarianceEstevez2019);
  const std::size_t beckmann = index_of(RoughnessFilter::kBeckmannVariance);
  if (ggx < o.filters.size() && beckmann < o.filters.size())
    for (std::size_t a = 0; a < o.alphas.size(); ++a)
      for (int l = 1; l < levels; ++l) {
        std::vector<double> e_ggx, e_beckmann;
        for (std::size_t t = level_begin[l]; t < level_begin[l + 1]; ++t) {
          e_ggx.push_back(tables[t][a][ggx].error);
          e_beckmann.push_back(tables[t][a][beckmann].error);
        }
        result.claim.push_back({o.alphas[a], l, compare_paired(e_ggx, e_beckmann)});
      }
  return result;
}

}  // namespace penumbra
