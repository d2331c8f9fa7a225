#include "study/fit.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <set>
#include <stdexcept>
#include <thread>
#include <tuple>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <nlohmann/json.hpp>

#include "analysis/metrics.h"
#include "core/shadow_origin.h"
#include "core/terminator.h"
#include "evaluator/evaluator.h"
#include "image/image_io.h"
#include "renderers/code_digest.h"
#include "scene/factor_table_file.h"
#include "scene/scene_json.h"
#include "study/provenance.h"
#include "util/files.h"
#include "util/hash.h"
#include "util/parallel.h"
#include "util/strict_json.h"
#include "util/version.h"

namespace penumbra {

using nlohmann::json;

FactorGrid default_fit_grid() {
  return {{{FactorInput::kLight, 20.0, 120.0, 2.0}, {FactorInput::kDeviation, 0.0, 60.0, 4.0}}};
}

FactorGrid fit_grid(const std::string& inputs) {
  if (inputs == kFitInputSets[0]) return default_fit_grid();
  const FactorAxis deviation{FactorInput::kDeviation, 0.0, 60.0, 6.0},
      shading{FactorInput::kShading, 0.0, 180.0, 12.0};
  if (inputs == kFitInputSets[1])
    return {{{FactorInput::kLight, 20.0, 120.0, 4.0}, deviation, shading}};
  if (inputs == kFitInputSets[2])
    return {{{FactorInput::kLight, 20.0, 120.0, 5.0},
             {FactorInput::kDeviation, 0.0, 60.0, 10.0},
             {FactorInput::kShading, 0.0, 180.0, 15.0},
             {FactorInput::kView, 0.0, 90.0, 45.0}}};
  throw std::invalid_argument(
      "expected light,deviation, light,deviation,shading or "
      "light,deviation,shading,view as the inputs, got " +
      inputs);
}

FactorGrid with_steps(FactorGrid grid, const std::vector<std::string>& steps) {
  for (const std::string& step : steps) {
    const std::size_t eq = step.find('=');
    const std::string name = step.substr(0, eq);
    FactorAxis* axis = nullptr;
    for (FactorAxis& a : grid.axes)
      if (name == name_of<FactorInput>(kFactorInputNames, a.input)) axis = &a;
    if (eq == std::string::npos || !axis)
      throw std::invalid_argument(
          fmt::format("expected AXIS=DEGREES with AXIS one of the grid's inputs ({}), got {}",
                      grid_inputs(grid), step));
    double degrees = 0.0;
    try {
      std::size_t used = 0;
      degrees = std::stod(step.substr(eq + 1), &used);
      if (used != step.size() - eq - 1) degrees = 0.0;
    } catch (const std::exception&) {
    }
    const double range = axis->max_deg - axis->min_deg, cells = range / degrees;
    if (!(degrees > 0.0) || std::abs(cells - std::round(cells)) > 1e-9 * cells)
      throw std::invalid_argument(
          fmt::format("expected {}'s step in degrees dividing its range [{:g}, {:g}), got {}", name,
                      axis->min_deg, axis->max_deg, step.substr(eq + 1)));
    axis->step_deg = degrees;
  }
  // Each variant's tally and the smoothed solves grow with the cells.
  if (grid.cells() > kMaxFitCells)
    throw std::invalid_argument(
        fmt::format("expected at most {} cells in the grid, got {}", kMaxFitCells, grid.cells()));
  return grid;
}

std::string grid_inputs(const FactorGrid& grid) {
  std::string out;
  for (const FactorAxis& a : grid.axes)
    out += (out.empty() ? "" : ",") + std::string(name_of<FactorInput>(kFactorInputNames, a.input));
  return out;
}

namespace {

constexpr double kConfidence = 0.95;

// Per variant, per method id: the evaluator's terminator RMSE against the
// evaluator's displacement truth, as the study's report holds it.
using MethodErrors = std::map<std::string, std::map<std::string, double>>;  // variant -> method

// `metric`: a JSON pointer into a comparison (the image RMSE's is in
// W m^-2 sr^-1, not yet divided by albedo*E/pi).
MethodErrors method_errors(const json& report, const json::json_pointer& metric =
                                                   "/profile/rmse_terminator"_json_pointer) {
  MethodErrors errors;
  for (const json& c : report.at("comparisons")) {
    if (c.value("renderer", "") != "evaluator" ||
        c.value("reference", "") != "evaluator:displacement")
      continue;
    const json& value = c.at(metric);
    if (value.is_number()) errors[c.at("variant")][c.at("method")] = value.get<double>();
  }
  return errors;
}

// The cache path (relative to the folder) of a variant's evaluator render
// of `method` in `representation`, or "" where the report has none.
std::string render_path(const json& variant, const std::string& representation) {
  for (const json& r : variant.at("renders"))
    if (r.value("renderer", "") == "evaluator" && r.value("method", "") == "none" &&
        r.value("representation", "") == representation && r.value("exr", json()).is_string())
      return r.at("exr").get<std::string>();
  return "";
}

// Whether two images hold the same bits in every channel of `a` (an EXR's
// channels come back in the file's order, not the evaluator's).
bool same_pixels(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height) return false;
  for (std::size_t c = 0; c < a.channels.size(); ++c) {
    const int k = b.channel_index(a.channels[c]);
    if (k < 0) return false;
    for (int y = 0; y < a.height; ++y)
      for (int x = 0; x < a.width; ++x)
        if (a.at(x, y, int(c)) != b.at(x, y, k)) return false;
  }
  return true;
}

// The scene a cached render was made from: its penumbra:scene attribute.
Scene scene_of(const std::string& path, const std::string& attribute) {
  const std::string origin = path + " (penumbra:scene metadata)";
  return scene_from_json(parse_json_text(attribute, origin), origin);
}

// One variant's tally: raw bump re-traced with the grid (its bits checked
// against the cached render) and its truth's profile. nullopt: skipped.
// `grid_tables`: the shipped factors of the grid's inputs, tabulated on it
// (FitVariant::image_on_grid); *rows: the variant's pixel rows, for its
// image floor (solved later, several at once).
std::optional<FitVariant> load_variant(
    const std::filesystem::path& folder, const json& variant, const FactorGrid& grid,
    const std::vector<std::pair<std::string, std::vector<double>>>& grid_tables, PixelRows* rows,
    FitResult* result) {
  const std::vector<ProbedConstant>& probed = result->probed;
  const std::string bump = render_path(variant, "bump"),
                    truth = render_path(variant, "displacement");
  // A render deleted from the cache leaves its variant out (the held-out
  // test deletes a family's).
  if (bump.empty() || truth.empty() || !std::filesystem::exists(folder / bump) ||
      !std::filesystem::exists(folder / truth))
    return std::nullopt;
  std::map<std::string, std::string> attributes;
  const Image cached = read_image((folder / bump).string(), &attributes);
  const Scene scene = scene_of((folder / bump).string(), attributes["penumbra:scene"]);
  if (scene.representation != Representation::kBump || scene.tessellation) return std::nullopt;
  PixelTally tally;
  TallyProbes probes = probes_for(probed, scene, cached);
  const Image traced = render_tallied(scene, grid, &tally, {}, nullptr, &probes);
  ++result->retraced;
  if (!same_pixels(traced, cached)) {
    ++result->retraced_different;
    return std::nullopt;
  }
  const double scale = radiance_scale(scene);
  FitVariant v;
  v.id = variant.at("id").get<std::string>();
  v.family = variant.at("scene").get<std::string>();
  const Image truth_image = read_image((folder / truth).string());
  v.data = {v.id, profile_tally(cached, tally, scale), terminator_profile(truth_image, scale)};
  v.probe_rmse = probe_errors(probes, traced, scale, v.data.truth);
  v.radiance_scale = scale;
  *rows = pixel_rows(cached, truth_image, tally, scale);
  v.image_none = pixel_rmse(*rows, std::vector<double>(std::size_t(grid.cells()), 1.0));
  for (const auto& [method, table] : grid_tables)
    v.image_on_grid[method] = pixel_rmse(*rows, table);
  return v;
}

// sqrt(mean of squares) of values[i] over `index`, NaNs left out.
double pooled(const std::vector<double>& values, const std::vector<std::size_t>& index) {
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t i : index)
    if (std::isfinite(values[i])) sum += values[i] * values[i], ++n;
  return n ? std::sqrt(sum / double(n)) : std::numeric_limits<double>::quiet_NaN();
}

std::vector<std::size_t> all_of(std::size_t n) {
  std::vector<std::size_t> index(n);
  for (std::size_t i = 0; i < n; ++i) index[i] = i;
  return index;
}

// Percentile-bootstrap intervals over a set of variants of N statistics
// computed together: `statistics` is given the indices of one resample and
// returns std::array<double, N>. nullopt for a statistic with no finite draw.
// The resamples are drawn in order from one stream and their statistics
// computed in parallel, each into its place (a fitted constant's is a
// search): the bits of a serial loop. `statistics` must be thread-safe.
template <std::size_t N, typename Statistics>
std::array<std::optional<Interval>, N> bootstrap_intervals(const std::vector<std::size_t>& index,
                                                           int resamples, std::uint64_t seed,
                                                           Statistics&& statistics) {
  std::mt19937_64 rng(seed);
  std::vector<std::vector<std::size_t>> samples(std::size_t(std::max(resamples, 0)),
                                                std::vector<std::size_t>(index.size()));
  for (std::vector<std::size_t>& sample : samples)
    for (std::size_t& s : sample) s = index[uniform_index(rng, index.size())];
  std::vector<std::array<double, N>> values(samples.size());
  tbb::parallel_for(std::size_t(0), samples.size(),
                    [&](std::size_t r) { values[r] = statistics(samples[r]); });
  std::array<std::vector<double>, N> draws;
  for (const std::array<double, N>& d : values)
    for (std::size_t n = 0; n < N; ++n)
      if (std::isfinite(d[n])) draws[n].push_back(d[n]);
  std::array<std::optional<Interval>, N> intervals;
  for (std::size_t n = 0; n < N; ++n) {
    if (draws[n].empty()) continue;
    std::sort(draws[n].begin(), draws[n].end());
    intervals[n] = Interval{quantile(draws[n], 0.5 * (1.0 - kConfidence)),
                            quantile(draws[n], 0.5 * (1.0 + kConfidence))};
  }
  return intervals;
}

// A statistic of a set of variants and its percentile-bootstrap interval
// over them: `statistic` is given the indices of one resample.
template <typename Statistic>
PooledError bootstrap(const std::vector<std::size_t>& index, int resamples, std::uint64_t seed,
                      Statistic&& statistic) {
  const double value = statistic(index);
  const auto [interval] = bootstrap_intervals<1>(
      index, resamples, seed,
      [&](const std::vector<std::size_t>& s) { return std::array<double, 1>{statistic(s)}; });
  return {value, interval.value_or(Interval{value, value})};
}

PooledError pooled_error(const std::vector<double>& values, const std::vector<std::size_t>& index,
                         const FitOptions& o) {
  return bootstrap(index, o.resamples, o.seed,
                   [&](const std::vector<std::size_t>& s) { return pooled(values, s); });
}

PairedError paired_error(const std::vector<double>& a, const std::vector<double>& b,
                         const std::vector<std::size_t>& index, const FitOptions& o) {
  const PooledError d =
      bootstrap(index, o.resamples, o.seed,
                [&](const std::vector<std::size_t>& s) { return pooled(a, s) - pooled(b, s); });
  return {d, d.interval.contains(0.0)};
}

// A method a renderer ships: not a table fitted to some study's truth.
bool shipped(const std::string& method) {
  return method.rfind("fitted", 0) != 0;
}

std::vector<TallyVariant> data_of(const std::vector<FitVariant>& variants,
                                  const std::vector<std::size_t>& index) {
  std::vector<TallyVariant> data;
  for (std::size_t i : index) data.push_back(variants[i].data);
  return data;
}

// Per variant (all of them), the terminator RMSE of table g.
std::vector<double> rmse_of(const std::vector<FitVariant>& variants, const std::vector<double>& g) {
  std::vector<double> rmse;
  for (const FitVariant& v : variants) rmse.push_back(tally_rmse(v.data, g));
  return rmse;
}

std::map<std::string, std::vector<std::size_t>> families(const std::vector<FitVariant>& variants) {
  std::map<std::string, std::vector<std::size_t>> f;
  for (std::size_t i = 0; i < variants.size(); ++i) f[variants[i].family].push_back(i);
  return f;
}

std::vector<std::size_t> without(const std::vector<FitVariant>& variants,
                                 const std::set<std::string>& left_out) {
  std::vector<std::size_t> index;
  for (std::size_t i = 0; i < variants.size(); ++i)
    if (!left_out.count(variants[i].family)) index.push_back(i);
  return index;
}

}  // namespace

namespace {

bool light_deviation_grid(const FactorGrid& grid) {
  return grid.axes.size() == 2 && grid.axes[0].input == FactorInput::kLight &&
         grid.axes[1].input == FactorInput::kDeviation;
}

bool has_axis(const FactorGrid& grid, FactorInput input) {
  return std::any_of(grid.axes.begin(), grid.axes.end(),
                     [input](const FactorAxis& a) { return a.input == input; });
}

// The angle of `input` at a cell's centre, radians; `fallback` where the
// grid has no such axis.
double centre_angle(const FactorGrid& grid, const std::vector<double>& centre, FactorInput input,
                    double fallback) {
  for (std::size_t a = 0; a < grid.axes.size(); ++a)
    if (grid.axes[a].input == input) return radians(centre[a]);
  return fallback;
}

// A factor of Ng, Ns and wi as a table at the cells' centres (a grid with
// light and deviation axes): vectors with the centre's angles between them.
// Without a shading axis Ns leans towards the light; a centre whose
// shading angle no vectors of its light and deviation angles have
// (|light - deviation| > shading or shading > light + deviation) takes the
// nearest that some do: only points beside it weigh it.
template <typename Factor>
std::vector<double> table_of(const FactorGrid& grid, Factor&& factor) {
  std::vector<double> g(std::size_t(grid.cells()));
  for (int c = 0; c < grid.cells(); ++c) {
    const std::vector<double> centre = grid.centre(c);
    const double l = centre_angle(grid, centre, FactorInput::kLight, 0.0),
                 d = centre_angle(grid, centre, FactorInput::kDeviation, 0.0),
                 s = centre_angle(grid, centre, FactorInput::kShading, 0.0);
    // The azimuth of wi about Ng from Ns's plane that makes <Ns,wi> = cos s.
    const double across = std::sin(d) * std::sin(l);
    const double cos_phi =
        has_axis(grid, FactorInput::kShading) && across > 1e-12
            ? std::clamp((std::cos(s) - std::cos(d) * std::cos(l)) / across, -1.0, 1.0)
            : 1.0;
    const double sin_phi = std::sqrt(std::max(0.0, 1.0 - cos_phi * cos_phi));
    const Vec3 ng{0, 0, 1}, ns{std::sin(d), 0, std::cos(d)},
        wi{std::sin(l) * cos_phi, std::sin(l) * sin_phi, std::cos(l)};
    g[std::size_t(c)] = factor(ng, ns, wi);
  }
  return g;
}

// The shipped factors that are functions of the cosines between Ng, Ns and
// wi alone, and the inputs they need.
struct GridMethod {
  const char* id;
  double (*factor)(const Vec3& ng, const Vec3& ns, const Vec3& wi);
  bool needs_shading;
};
constexpr GridMethod kGridMethods[] = {{"estevez2019", estevez2019, false},
                                       {"deshmukh2020", deshmukh2020, false},
                                       {"chiang2019", chiang2019, true},
                                       {"chiang2019-sine", chiang2019_sine, true}};

// Whether a method's factor is a function of the grid's inputs.
bool on_grid(const GridMethod& m, const FactorGrid& grid) {
  return has_axis(grid, FactorInput::kLight) && has_axis(grid, FactorInput::kDeviation) &&
         (!m.needs_shading || has_axis(grid, FactorInput::kShading));
}

}  // namespace

namespace {

// Nelder-Mead (reflection 1, expansion 2, contraction 1/2, shrink 1/2) on
// f(x, y) over the box [lo, hi]^2, trial points projected into it, from a
// right triangle of legs `step` at `start` (legs turned inwards at the box's
// edge), until every vertex lies within `tolerance` of the best on both
// axes or `max_evaluations` is spent. The best vertex's f never rises, so
// the result is never worse than `start`.
template <typename F>
std::array<double, 2> nelder_mead(F&& f, std::array<double, 2> start, double step, double lo,
                                  double hi, double tolerance, int max_evaluations) {
  using Point = std::array<double, 2>;
  struct Vertex {
    Point x;
    double f;
  };
  int evaluations = 0;
  const auto at = [&](Point x) {
    for (double& c : x) c = std::clamp(c, lo, hi);
    ++evaluations;
    return Vertex{x, f(x[0], x[1])};
  };
  const auto leg = [&](double c) { return c + step <= hi ? c + step : c - step; };
  std::array<Vertex, 3> v{at(start), at({leg(start[0]), start[1]}), at({start[0], leg(start[1])})};
  const auto along = [](const Point& from, const Point& to, double t) {
    return Point{from[0] + t * (to[0] - from[0]), from[1] + t * (to[1] - from[1])};
  };
  while (evaluations < max_evaluations) {
    std::sort(v.begin(), v.end(), [](const Vertex& a, const Vertex& b) { return a.f < b.f; });
    double spread = 0.0;
    for (const Vertex& w : v)
      for (int k = 0; k < 2; ++k) spread = std::max(spread, std::abs(w.x[k] - v[0].x[k]));
    if (spread < tolerance) break;
    const Point centroid = along(v[0].x, v[1].x, 0.5);
    const Vertex reflected = at(along(v[2].x, centroid, 2.0));
    if (reflected.f < v[0].f) {
      const Vertex expanded = at(along(v[2].x, centroid, 3.0));
      v[2] = expanded.f < reflected.f ? expanded : reflected;
    } else if (reflected.f < v[1].f) {
      v[2] = reflected;
    } else {
      const Vertex contracted = reflected.f < v[2].f ? at(along(v[2].x, centroid, 1.5))
                                                     : at(along(v[2].x, centroid, 0.5));
      if (contracted.f < std::min(reflected.f, v[2].f)) {
        v[2] = contracted;
      } else {
        for (int k = 1; k < 3; ++k) v[k] = at(along(v[0].x, v[k].x, 0.5));
      }
    }
  }
  std::sort(v.begin(), v.end(), [](const Vertex& a, const Vertex& b) { return a.f < b.f; });
  return v[0].x;
}

// deshmukh2020 (core/terminator.cpp) with its constants as arguments, the
// same operations in the same order, so that the published pair gives its
// bits (core/terminator.* is in every render's cache key: not edited there).
double deshmukh2020_with(const Vec3& ng, const Vec3& ns, const Vec3& wi,
                         const Deshmukh2020Constants& c) {
  const double cos_x = std::clamp(dot(ns, ng), 0.0, 1.0);
  const double d = c.d0 + (c.d1 - c.d0) * cos_x;
  const double t = std::clamp(dot(ng, wi) / d, 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

// fit_deshmukh2020 on any multiset of a fixed set of variants (every
// variant, a bootstrap resample, the variants without a family).
//
// G enters E only on the grid, so d only over its deviations: the search
// runs on d at the deviation axis' two ends, d1 at 0 and d_e at its end e
// (60 degrees on the default grid), d0 = (d_e - d1 cos e) / (1 - cos e), and
// on them as angles w = asin(d) in degrees, the width of light before the
// terminator that the smoothstep darkens, so that its steps compare with the
// light axis'. Range (0, 90] degrees, d in (0, 1] over the whole grid (d is
// linear in cos delta): d > 0 for the smoothstep to be defined, and at d = 1
// it already spans the whole lit hemisphere. d0 itself, d at 90 degrees, is
// an extrapolation the grid does not see, so it is not bounded.
//
// The coarse step is half the light axis' step: G is taken at the light
// cells' centres, where E changes how it bends (d crossing a centre's
// cosine), and every interval between two centres' angles then holds a
// node. Each variant's squared RMSE at the nodes is computed once; a
// resample's coarse search is then a weighted sum.
class Deshmukh2020Search {
 public:
  Deshmukh2020Search(std::vector<const TallyVariant*> variants, const FactorGrid& grid)
      : variants_(std::move(variants)),
        grid_(grid),
        step_(0.5 * grid.axes[0].step_deg),
        cos_end_(std::cos(radians(grid.axes[1].max_deg))) {
    n_ = int(std::floor(90.0 / step_ + 1e-9));
    coarse_.resize(std::size_t(n_) * std::size_t(n_));
    tbb::parallel_for(0, n_ * n_, [&](int node_index) {
      const int i = node_index / n_, j = node_index % n_;
      const std::vector<double> g = deshmukh2020_table(grid_, constants(node(i), node(j)));
      for (const TallyVariant* v : variants_) coarse(i, j).push_back(squared(tally_rmse(*v, g)));
    });
  }

  // Where `c` lies on the edge of the search's range (within 1e-3 degrees):
  // which d and which bound, "" where it does not.
  std::string bound_reached(const Deshmukh2020Constants& c) const {
    std::string bounds;
    const double d_end = c.d0 + (c.d1 - c.d0) * cos_end_;
    for (const auto& [d, where] :
         {std::pair{c.d1, std::string("at deviation 0")},
          std::pair{d_end, fmt::format("at deviation {:g} degrees", grid_.axes[1].max_deg)}}) {
      const double w = angle(std::clamp(d, 0.0, 1.0));
      if (w < 1e-3 || w > 90.0 - 1e-3)
        bounds += (bounds.empty() ? "" : "; ") + fmt::format("d {} = {}", where, w < 1e-3 ? 0 : 1);
    }
    return bounds;
  }

  // `sample`: indices into the variants, each counted as often as it occurs.
  Deshmukh2020Constants fit(const std::vector<std::size_t>& sample) const {
    std::vector<double> weight(variants_.size(), 0.0);
    for (std::size_t k : sample) weight[k] += 1.0;
    const Deshmukh2020Constants p = kDeshmukh2020Published;
    std::array<double, 2> start{angle(p.d1), angle(p.d0 + (p.d1 - p.d0) * cos_end_)};
    double best = error(weight, start[0], start[1]);
    for (int i = 0; i < n_; ++i)
      for (int j = 0; j < n_; ++j)
        if (const double e = mean(weight, coarse(i, j)); e < best)
          best = e, start = {node(i), node(j)};
    // 1e-6 degrees: d to about 2e-8, far below any difference the
    // bootstrap shows.
    const std::array<double, 2> w =
        nelder_mead([&](double w1, double w_end) { return error(weight, w1, w_end); }, start, step_,
                    1e-6, 90.0, 1e-6, 2000);
    return constants(w[0], w[1]);
  }

 private:
  static double squared(double e) { return e * e; }
  static double angle(double d) { return degrees(std::asin(d)); }
  // The constants of angles w1 = asin(d1), w_e = asin(d at the deviation
  // axis' end).
  Deshmukh2020Constants constants(double w1, double w_end) const {
    const double d1 = std::sin(radians(w1)), d_end = std::sin(radians(w_end));
    return {(d_end - d1 * cos_end_) / (1.0 - cos_end_), d1};
  }
  double node(int i) const { return step_ * double(i + 1); }
  std::vector<double>& coarse(int i, int j) {
    return coarse_[std::size_t(i) * std::size_t(n_) + std::size_t(j)];
  }
  const std::vector<double>& coarse(int i, int j) const {
    return coarse_[std::size_t(i) * std::size_t(n_) + std::size_t(j)];
  }
  // The mean of squared RMSEs e over the variants with weight, NaNs left
  // out (as fit_estevez2019_k leaves them out).
  static double mean(const std::vector<double>& weight, const std::vector<double>& e) {
    double sum = 0.0, n = 0.0;
    for (std::size_t k = 0; k < e.size(); ++k)
      if (weight[k] > 0.0 && std::isfinite(e[k])) sum += weight[k] * e[k], n += weight[k];
    return n > 0.0 ? sum / n : 0.0;
  }
  double error(const std::vector<double>& weight, double w1, double w_end) const {
    const std::vector<double> g = deshmukh2020_table(grid_, constants(w1, w_end));
    std::vector<double> e(variants_.size(), 0.0);
    for (std::size_t k = 0; k < variants_.size(); ++k)
      if (weight[k] > 0.0) e[k] = squared(tally_rmse(*variants_[k], g));
    return mean(weight, e);
  }

  std::vector<const TallyVariant*> variants_;
  FactorGrid grid_;
  double step_;     // degrees, of the coarse grid and the first simplex
  double cos_end_;  // cos of the deviation axis' end
  int n_ = 0;       // coarse nodes per axis: step_, 2 step_, ..., 90 degrees
  std::vector<std::vector<double>> coarse_;  // per node (w1 slowest), per variant
};

}  // namespace

namespace {

void say(const FitOptions& o, const std::string& line) {
  if (o.progress) o.progress(line);
}

int jobs_of(const FitOptions& o) {
  return o.jobs > 0 ? o.jobs : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

// Each variant's image floor (FitVariant::image_floor), `jobs` at a time.
// The active-set solve after the projected gradient's 5,000 steps cycles
// from a rougher start (300 steps left a KKT residual of 5e-6 rather than
// 2e-8 on the default study), so the steps stay and the solves share the
// cores instead.
void solve_image_floors(const FitOptions& o, const std::vector<PixelRows>& rows, FitResult* r) {
  say(o, fmt::format("image RMSE: each of {} variants' own floor", rows.size()));
  std::vector<std::string> failed(rows.size());
  // Largest first, so that no core is left with a large one at the end: a
  // solve's steps cost about the square of the cells its variant lights.
  std::vector<std::size_t> order = all_of(rows.size());
  std::vector<std::size_t> lit(rows.size());
  for (std::size_t k = 0; k < rows.size(); ++k)
    lit[k] = std::set<int>(rows[k].cells.begin(), rows[k].cells.end()).size();
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return lit[a] > lit[b]; });
  run_parallel(jobs_of(o), rows.size(), [&](std::size_t t) {
    const std::size_t k = order[t];
    try {
      const FloorSolution image = solve_image_floor(o.grid, rows[k]);
      r->variants[k].image_floor = image.variant_rmse.front();
      r->variants[k].image_kkt_residual = image.kkt_residual;
    } catch (const std::exception& e) {
      failed[k] = e.what();
    }
  });
  for (std::size_t k = 0; k < failed.size(); ++k)
    if (!failed[k].empty())
      throw std::runtime_error(
          fmt::format("the image floor of variant {}: {}", r->variants[k].id, failed[k]));
}

// The variants of the study that have an evaluator raw-bump render and
// truth, tallied.
void load_variants(const FitOptions& o, const json& report, FitResult* r) {
  const std::filesystem::path folder(o.folder);
  const json& variants = report.at("variants");
  // A truth that did not converge is not yet the truth: the floor and the
  // fitted constants would be fitted to its error.
  std::set<std::string> unconverged;
  if (report.contains("ground_truth") && report["ground_truth"].contains("variants"))
    for (const json& g : report["ground_truth"]["variants"])
      if (!g.value("converged", true)) unconverged.insert(g.at("variant").get<std::string>());
  if (light_deviation_grid(o.grid)) {
    std::set<std::string> labels;
    for (const auto& [id, row] : method_errors(report))
      for (const auto& [label, _] : row) labels.insert(label);
    r->probed = probed_constants(labels);
  }
  std::vector<std::pair<std::string, std::vector<double>>> grid_tables;
  for (const GridMethod& m : kGridMethods)
    if (on_grid(m, o.grid)) grid_tables.emplace_back(m.id, table_of(o.grid, m.factor));
  std::vector<PixelRows> rows;  // per fitted variant
  std::size_t done = 0;
  for (const json& variant : variants) {
    if (unconverged.count(variant.at("id").get<std::string>())) {
      r->unconverged.push_back(variant.at("id").get<std::string>());
      ++done;
      continue;
    }
    PixelRows variant_rows;
    if (auto v = load_variant(folder, variant, o.grid, grid_tables, &variant_rows, r)) {
      r->variants.push_back(std::move(*v));
      rows.push_back(std::move(variant_rows));
    } else
      ++r->skipped;
    if (++done % 12 == 0 || done == variants.size())
      say(o, fmt::format("tallied raw bump: {} of {} variants", done, variants.size()));
  }
  if (r->variants.empty())
    throw InputError((folder / "report.json").string(), "/variants",
                     fmt::format("no variant with an evaluator raw-bump render and displacement "
                                 "truth to fit ({} left out: their truth did not converge; {} "
                                 "re-traced differ from the cache)",
                                 r->unconverged.size(), r->retraced_different));
  solve_image_floors(o, rows, r);
  double outside = 0.0, total = 0.0;
  for (const FitVariant& v : r->variants)
    for (std::size_t b = 0; b < v.data.tally.count.size(); ++b) {
      const double centre = (double(b) + 0.5) * v.data.tally.bin_degrees;
      if (centre < kTerminatorBegin || centre >= kTerminatorEnd) continue;
      outside += v.data.tally.rest[b];
      total += v.data.tally.rest[b];
      for (const auto& [cell, light] : v.data.tally.scaled[b]) total += light;
    }
  // `rest` also holds the lobes no factor scales; the share is an upper bound.
  r->outside_share = total > 0.0 ? outside / total : 0.0;
}

FloorFit floor_over(const FitResult& r, const std::string& scope,
                    const std::vector<std::size_t>& index, const std::vector<double>& none,
                    const FitOptions& o) {
  FloorFit f;
  f.scope = scope;
  f.variants = index.size();
  f.solution = solve_floor(r.grid, data_of(r.variants, index));
  std::vector<double> rmse(r.variants.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t k = 0; k < index.size(); ++k) rmse[index[k]] = f.solution.variant_rmse[k];
  f.floor = pooled_error(rmse, index, o);
  f.none = pooled_error(none, index, o);
  return f;
}

// The study floor of each shorter set of kFitInputSets on the grid's own
// axes (NestedFloor).
void fit_nested_floors(const FitOptions& o, const std::vector<double>& none, FitResult* r) {
  const std::string inputs = grid_inputs(r->grid);
  const std::vector<std::size_t> index = all_of(r->variants.size());
  for (const std::string shorter : kFitInputSets) {
    if (inputs.rfind(shorter + ",", 0) != 0) continue;
    FactorGrid grid;
    const auto axes = std::count(shorter.begin(), shorter.end(), ',') + 1;
    grid.axes.assign(r->grid.axes.begin(), r->grid.axes.begin() + axes);
    say(o, fmt::format("floor of a {} factor on the same grid", shorter));
    std::vector<TallyVariant> data;
    for (const FitVariant& v : r->variants)
      data.push_back({v.id, marginal_tally(v.data.tally, r->grid, grid), v.data.truth});
    NestedFloor n;
    n.inputs = shorter;
    n.floor.scope = "study";
    n.floor.variants = data.size();
    n.floor.solution = solve_floor(grid, data);
    n.floor.floor = pooled_error(n.floor.solution.variant_rmse, index, o);
    n.floor.none = pooled_error(none, index, o);
    n.gain =
        paired_error(r->study_floor.solution.variant_rmse, n.floor.solution.variant_rmse, index, o);
    r->nested.push_back(std::move(n));
  }
}

// The smoothed floor solves of a fit, each (training variants, smoothness)
// solved once: the leave-one-family-out choice of smoothness within each
// held-out family's complement solves the same pairs of families left out
// again, and the table's choice repeats the held-out fits. A solve is
// deterministic, so sharing and the order of solving change no bit.
class FloorSolves {
 public:
  using Key = std::pair<std::vector<std::size_t>, double>;
  FloorSolves(const FitResult& r, const FitOptions& o) : r_(r), o_(o), jobs_(jobs_of(o)) {}

  // Solves the keys not solved yet, `jobs` at a time.
  void solve(const std::vector<Key>& wanted) {
    std::vector<Key> missing;
    for (const Key& k : wanted)
      if (!solved_.count(k) && std::find(missing.begin(), missing.end(), k) == missing.end())
        missing.push_back(k);
    std::vector<FloorSolution> out(missing.size());
    std::vector<std::exception_ptr> failed(missing.size());
    std::atomic<std::size_t> done{0};
    std::mutex say_one;
    run_parallel(jobs_, missing.size(), [&](std::size_t i) {
      try {
        FloorOptions options;
        options.smoothness = missing[i].second;
        out[i] = solve_floor(r_.grid, data_of(r_.variants, missing[i].first), options);
      } catch (...) {
        failed[i] = std::current_exception();
      }
      // A fine grid's tables take minutes: a line each tenth of them.
      const std::size_t n = ++done;
      if (n * 10 / missing.size() != (n - 1) * 10 / missing.size()) {
        const std::lock_guard<std::mutex> lock(say_one);
        say(o_, fmt::format("  {} of {} smoothed tables solved", n, missing.size()));
      }
    });
    for (const std::exception_ptr& e : failed)
      if (e) std::rethrow_exception(e);
    for (std::size_t i = 0; i < missing.size(); ++i) solved_[missing[i]] = std::move(out[i]);
  }

  // Per variant of `test`, the RMSE of the table fitted on `train` with
  // smoothness w (solved first where it is not yet).
  void held_out_rmse(const std::vector<std::size_t>& train, const std::vector<std::size_t>& test,
                     double w, std::vector<double>* rmse) {
    solve({{train, w}});
    const FloorSolution& s = solved_.at({train, w});
    for (std::size_t i : test) (*rmse)[i] = tally_rmse(r_.variants[i].data, s.g);
  }

 private:
  const FitResult& r_;
  const FitOptions& o_;
  int jobs_;
  std::map<Key, FloorSolution> solved_;
};

// The training variants of family f's fold when choosing a smoothness
// within `within`: every family of `within` but f.
std::vector<std::size_t> fold_train(const FitResult& r, const std::set<std::string>& within,
                                    const std::string& f) {
  std::set<std::string> left_out;
  for (const FitVariant& v : r.variants)
    if (!within.count(v.family) || v.family == f) left_out.insert(v.family);
  return without(r.variants, left_out);
}

// The solves choose_smoothness(within) needs.
std::vector<FloorSolves::Key> smoothness_solves(const FitResult& r,
                                                const std::set<std::string>& within,
                                                const FitOptions& o) {
  std::vector<FloorSolves::Key> keys;
  if (within.size() < 2) return keys;
  for (const double w : o.smoothness)
    for (const std::string& f : within) keys.push_back({fold_train(r, within, f), w});
  return keys;
}

// The candidate smoothness with the lowest leave-one-family-out error
// within `within` (families); the middle candidate when there is one family.
double choose_smoothness(const FitResult& r, const std::set<std::string>& within,
                         const FitOptions& o, FloorSolves& solves) {
  if (within.size() < 2) return o.smoothness[o.smoothness.size() / 2];
  solves.solve(smoothness_solves(r, within, o));
  const auto by_family = families(r.variants);
  double best = o.smoothness.front(), best_error = std::numeric_limits<double>::infinity();
  for (const double w : o.smoothness) {
    std::vector<double> rmse(r.variants.size(), std::numeric_limits<double>::quiet_NaN());
    std::vector<std::size_t> scored;
    for (const std::string& f : within) {
      solves.held_out_rmse(fold_train(r, within, f), by_family.at(f), w, &rmse);
      scored.insert(scored.end(), by_family.at(f).begin(), by_family.at(f).end());
    }
    const double e = pooled(rmse, scored);
    if (e < best_error) best = w, best_error = e;
  }
  return best;
}

// Each family held out: the table fitted on the others (smoothness chosen
// among them) on it, beside the floor and the best shipped method there.
void fit_held_out(const FitOptions& o, const std::vector<double>& none,
                  const std::map<std::string, std::vector<double>>& methods, FloorSolves& solves,
                  FitResult* r) {
  const auto by_family = families(r->variants);
  const auto others = [&](const std::string& family) {
    std::set<std::string> out;
    for (const auto& [name, _] : by_family)
      if (name != family) out.insert(name);
    return out;
  };
  // Every family's folds at once: each pair of families left out is shared
  // by two of them.
  if (by_family.size() >= 2) {
    say(o,
        fmt::format("held out: choosing the smoothness of {} families' tables", by_family.size()));
    std::vector<FloorSolves::Key> keys;
    for (const auto& [family, _] : by_family)
      for (FloorSolves::Key& k : smoothness_solves(*r, others(family), o)) keys.push_back(k);
    solves.solve(keys);
  }
  std::vector<double> held(r->variants.size(), std::numeric_limits<double>::quiet_NaN());
  std::vector<FloorSolves::Key> held_keys;
  for (const auto& [family, index] : by_family) {
    if (by_family.size() < 2) break;
    HeldOutFit h;
    h.family = family;
    h.variants = index.size();
    h.smoothness = choose_smoothness(*r, others(family), o, solves);
    held_keys.push_back({without(r->variants, {family}), h.smoothness});
    r->held_out.push_back(h);
  }
  if (!held_keys.empty()) say(o, "held out: fitting each family's table without it");
  solves.solve(held_keys);
  for (HeldOutFit& h : r->held_out) {
    const std::vector<std::size_t>& index = by_family.at(h.family);
    solves.held_out_rmse(without(r->variants, {h.family}), index, h.smoothness, &held);
    h.held_out = pooled_error(held, index, o);
    h.in_sample = pooled(rmse_of(r->variants, r->study_floor.solution.g), index);
    h.none = pooled_error(none, index, o);
    double best = std::numeric_limits<double>::infinity();
    for (const auto& [method, values] : methods)
      if (const double e = pooled(values, index); shipped(method) && e < best)
        best = e, h.best_method = method;
  }
  // Paired differences once every family's held-out errors are in `held`.
  for (HeldOutFit& h : r->held_out)
    if (!h.best_method.empty()) {
      const std::vector<std::size_t>& index = by_family.at(h.family);
      h.best = pooled_error(methods.at(h.best_method), index, o);
      h.held_out_minus_best = paired_error(held, methods.at(h.best_method), index, o);
    }
  const std::vector<std::size_t> all = all_of(r->variants.size());
  r->held_out_pooled = pooled_error(held, all, o);
  double best = std::numeric_limits<double>::infinity();
  for (const auto& [method, values] : methods)
    if (const double e = pooled(values, all); shipped(method) && e < best)
      best = e, r->best_method = method;
  if (!r->held_out.empty() && !r->best_method.empty())
    r->held_out_minus_best = paired_error(held, methods.at(r->best_method), all, o);
}

}  // namespace

namespace {

// The shares' tie groups (MethodShare::group), by paired differences of
// shares over the same resamples as the shares' own intervals.
void share_groups(const FitOptions& o, const std::vector<double>& none,
                  const std::vector<double>& floor,
                  const std::map<std::string, std::vector<double>>& methods,
                  std::vector<MethodShare>* shares) {
  const std::vector<std::size_t> index = all_of(none.size());
  const auto share = [&](const std::string& m, const std::vector<std::size_t>& k) {
    const double e_none = pooled(none, k);
    return (e_none - pooled(methods.at(m), k)) / (e_none - pooled(floor, k));
  };
  std::vector<MethodShare*> order;
  for (MethodShare& s : *shares)
    if (std::isfinite(s.share.value)) order.push_back(&s);
  std::stable_sort(order.begin(), order.end(), [](const MethodShare* a, const MethodShare* b) {
    return a->share.value != b->share.value ? a->share.value > b->share.value
                                            : a->method < b->method;
  });
  int group = 0;
  for (std::size_t i = 0; i < order.size(); ++i) {
    MethodShare& lead = *order[i];
    if (lead.group) continue;
    lead.group = ++group, lead.leader = lead.method;
    lead.versus_leader = {{0.0, {0.0, 0.0}}, true};
    for (std::size_t j = i + 1; j < order.size(); ++j) {
      MethodShare& m = *order[j];
      if (m.group) continue;
      const PooledError d =
          bootstrap(index, o.resamples, o.seed, [&](const std::vector<std::size_t>& k) {
            return share(m.method, k) - share(lead.method, k);
          });
      if (!d.interval.contains(0.0)) continue;
      m.group = group, m.leader = lead.method, m.versus_leader = {d, true};
    }
  }
}

// (E_none - E_method) / (E_none - E_floor) over `index`, the three paired
// over the same resamples.
PooledError share_of(const std::vector<double>& none, const std::vector<double>& method,
                     const std::vector<double>& floor, const std::vector<std::size_t>& index,
                     const FitOptions& o) {
  return bootstrap(index, o.resamples, o.seed, [&](const std::vector<std::size_t>& k) {
    const double e_none = pooled(none, k);
    return (e_none - pooled(method, k)) / (e_none - pooled(floor, k));
  });
}

// Each shipped method's pooled error and its share of the improvement the
// study floor achieves over raw bump, paired over the same resamples.
void fit_shares(const FitOptions& o, const std::vector<double>& none,
                const std::map<std::string, std::vector<double>>& methods, FitResult* r) {
  // The study floor's index is every variant, in order.
  const std::vector<double>& floor = r->study_floor.solution.variant_rmse;
  const std::vector<std::size_t> index = all_of(r->variants.size());
  for (const auto& [method, values] : methods) {
    MethodShare s;
    s.method = method;
    s.error = pooled_error(values, index, o);
    s.share = share_of(none, values, floor, index, o);
    for (const GridMethod& m : kGridMethods) {
      if (method != m.id || !on_grid(m, r->grid)) continue;
      s.on_grid_inputs = true;
      s.grid_error = pooled(rmse_of(r->variants, table_of(r->grid, m.factor)), index);
      s.resolution_error = std::abs(s.grid_error - s.error.value);
    }
    r->shares.push_back(s);
  }
  std::sort(r->shares.begin(), r->shares.end(), [](const MethodShare& a, const MethodShare& b) {
    return a.error.value < b.error.value;
  });
  share_groups(o, none, floor, methods, &r->shares);
}

// A constant's errors with its value chosen without each family (held[i]:
// variant i's), pooled over every variant and paired with the published.
void set_held_out(const FitOptions& o, const std::vector<double>& held,
                  const std::vector<double>& published, FittedConstant* c) {
  const std::vector<std::size_t> index = all_of(held.size());
  c->held_out_defined = true;
  c->held_out = pooled_error(held, index, o);
  c->held_out_minus_published = paired_error(held, published, index, o);
}

// estevez2019's 1/8 refitted: on every variant, per bootstrap resample
// (refitted each time; fewer resamples, each is a search), and per family
// held out.
void fit_estevez2019_constant(const FitOptions& o, FitResult* r) {
  say(o, "fitting estevez2019's constant");
  const std::vector<std::size_t> index = all_of(r->variants.size());
  FittedConstant c;
  c.method = "estevez2019";
  c.constant = "k in alpha^2 = k tan^2(delta)";
  c.published = 1.0 / 8.0;
  c.fitted = fit_estevez2019_k(data_of(r->variants, index), r->grid);
  // The golden section's range, [1e-3, 10], to its 1e-4 in log k.
  for (const double end : {1e-3, 10.0})
    if (std::abs(std::log(c.fitted / end)) < 1e-3) c.at_bound = fmt::format("k = {:g}", end);
  c.in_sample = pooled_error(rmse_of(r->variants, estevez2019_table(r->grid, c.fitted)), index, o);
  const std::vector<double> published =
      rmse_of(r->variants, estevez2019_table(r->grid, c.published));
  c.at_published = pooled_error(published, index, o);
  const int resamples = std::min(o.resamples, 200);
  c.interval = bootstrap(index, resamples, o.seed, [&](const std::vector<std::size_t>& k) {
                 return fit_estevez2019_k(data_of(r->variants, k), r->grid);
               }).interval;
  const auto by_family = families(r->variants);
  if (by_family.size() >= 2) {
    std::vector<double> held(r->variants.size(), std::numeric_limits<double>::quiet_NaN());
    for (const auto& [family, members] : by_family) {
      const double k =
          fit_estevez2019_k(data_of(r->variants, without(r->variants, {family})), r->grid);
      const std::vector<double> g = estevez2019_table(r->grid, k);
      for (std::size_t i : members) held[i] = tally_rmse(r->variants[i].data, g);
    }
    set_held_out(o, held, published, &c);
  }
  r->constants.push_back(c);
}

// deshmukh2020's pair refitted as estevez2019's k is (the same resamples:
// same count and seed), one entry per constant; the errors are the pair's.
void fit_deshmukh2020_constants(const FitOptions& o, FitResult* r) {
  say(o, "fitting deshmukh2020's constants");
  const std::vector<std::size_t> index = all_of(r->variants.size());
  std::vector<const TallyVariant*> data;
  for (const FitVariant& v : r->variants) data.push_back(&v.data);
  const Deshmukh2020Search search(data, r->grid);
  const Deshmukh2020Constants fitted = search.fit(index), published = kDeshmukh2020Published;
  const auto pair_of = [&](const std::vector<std::size_t>& k) {
    const Deshmukh2020Constants c = search.fit(k);
    return std::array<double, 2>{c.d0, c.d1};
  };
  const auto intervals = bootstrap_intervals<2>(index, std::min(o.resamples, 200), o.seed, pair_of);
  FittedConstant c;
  c.method = "deshmukh2020";
  c.in_sample = pooled_error(rmse_of(r->variants, deshmukh2020_table(r->grid, fitted)), index, o);
  const std::vector<double> at_published =
      rmse_of(r->variants, deshmukh2020_table(r->grid, published));
  c.at_published = pooled_error(at_published, index, o);
  if (const auto by_family = families(r->variants); by_family.size() >= 2) {
    std::vector<double> held(r->variants.size(), std::numeric_limits<double>::quiet_NaN());
    for (const auto& [family, members] : by_family) {
      const std::vector<double> g =
          deshmukh2020_table(r->grid, search.fit(without(r->variants, {family})));
      for (std::size_t i : members) held[i] = tally_rmse(r->variants[i].data, g);
    }
    set_held_out(o, held, at_published, &c);
  }
  c.at_bound = search.bound_reached(fitted);
  // No comma: fit.csv writes this as its unit column.
  const char* lerp = " in d = d0 + (d1 - d0) cos(delta)";
  for (const auto& [symbol, p, f, interval] :
       {std::tuple{"d0", published.d0, fitted.d0, intervals[0]},
        std::tuple{"d1", published.d1, fitted.d1, intervals[1]}}) {
    c.constant = std::string(symbol) + lerp;
    c.published = p, c.fitted = f;
    c.interval = interval.value_or(Interval{f, f});
    r->constants.push_back(c);
  }
}

// Of a constant's values, the index whose errors (error[k][i]: value k,
// variant i) pool lowest over `index` (the first of equals).
std::size_t lowest_value(const std::vector<std::vector<double>>& error,
                         const std::vector<std::size_t>& index) {
  std::size_t best = 0;
  double best_e = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < error.size(); ++k)
    if (const double e = pooled(error[k], index); e < best_e) best_e = e, best = k;
  return best;
}

// A constant refitted among `values` (ascending), each with its own error
// per variant, as estevez2019's k is: the value with the lowest pooled E
// over every variant, its interval over resamples of variants (refitted on
// each), E at it, at values[published] and with the value chosen without
// each family (family[i]: variant i's), paired with the published. Sets
// every field of *c but its names and probe_minus_rendered.
void fit_among_values(const FitOptions& o, const std::vector<double>& values, std::size_t published,
                      const std::vector<std::vector<double>>& error,
                      const std::vector<std::string>& family, FittedConstant* c) {
  const std::vector<std::size_t> index = all_of(family.size());
  const std::size_t best = lowest_value(error, index);
  c->published = values[published];
  c->fitted = values[best];
  if (best == 0 || best + 1 == values.size())
    c->at_bound = fmt::format("{} = {:g}", c->constant.substr(0, c->constant.find(' ')), c->fitted);
  c->in_sample = pooled_error(error[best], index, o);
  c->at_published = pooled_error(error[published], index, o);
  c->interval =
      bootstrap(index, std::min(o.resamples, 200), o.seed, [&](const std::vector<std::size_t>& k) {
        return values[lowest_value(error, k)];
      }).interval;
  std::map<std::string, std::vector<std::size_t>> members;
  for (std::size_t i = 0; i < family.size(); ++i) members[family[i]].push_back(i);
  if (members.size() < 2) return;
  std::vector<double> held(family.size(), std::numeric_limits<double>::quiet_NaN());
  for (const auto& [f, in_family] : members) {
    std::vector<std::size_t> train;
    for (std::size_t i = 0; i < family.size(); ++i)
      if (family[i] != f) train.push_back(i);
    const std::size_t k = lowest_value(error, train);
    for (std::size_t i : in_family) held[i] = error[k][i];
  }
  set_held_out(o, held, error[published], c);
}

// A probed constant refitted among the values it tried (so to their step),
// each E that of a render with the value.
void fit_probed_constant(const FitOptions& o, std::size_t constant, const MethodErrors& errors,
                         FitResult* r) {
  const ProbedConstant& p = r->probed[constant];
  say(o, fmt::format("fitting {}'s constant", method_info(p.method).id));
  std::vector<std::vector<double>> error(p.values.size());
  std::vector<std::string> family;
  for (const FitVariant& v : r->variants) {
    family.push_back(v.family);
    for (std::size_t k = 0; k < p.values.size(); ++k) error[k].push_back(v.probe_rmse[constant][k]);
  }
  FittedConstant c;
  c.method = std::string(method_info(p.method).id);
  c.constant = p.constant;
  c.reference = p.reference;
  const std::size_t at =
      std::size_t(std::find(p.values.begin(), p.values.end(), p.published) - p.values.begin());
  fit_among_values(o, p.values, at, error, family, &c);
  if (!p.label.empty()) {
    c.probe_minus_rendered = 0.0;
    for (std::size_t i = 0; i < r->variants.size(); ++i) {
      const auto row = errors.find(r->variants[i].id);
      if (row == errors.end() || !row->second.count(p.label)) continue;
      c.probe_minus_rendered =
          std::max(c.probe_minus_rendered, std::abs(error[at][i] - row->second.at(p.label)));
    }
  }
  r->constants.push_back(c);
}

void fit_constants(const FitOptions& o, const MethodErrors& errors, FitResult* r) {
  if (!light_deviation_grid(r->grid)) return;
  fit_estevez2019_constant(o, r);
  fit_deshmukh2020_constants(o, r);
  for (std::size_t c = 0; c < r->probed.size(); ++c) fit_probed_constant(o, c, errors, r);
}

}  // namespace

std::vector<double> estevez2019_table(const FactorGrid& grid, double k) {
  return table_of(grid, [k](const Vec3& ng, const Vec3& ns, const Vec3& wi) {
    return estevez2019_g1(ng, wi, estevez2019_alpha2(ng, ns) * 8.0 * k);
  });
}

double fit_estevez2019_k(const std::vector<TallyVariant>& variants, const FactorGrid& grid) {
  const auto error = [&](double log_k) {
    const std::vector<double> g = estevez2019_table(grid, std::exp(log_k));
    double sum = 0.0;
    std::size_t n = 0;
    for (const TallyVariant& v : variants)
      if (const double e = tally_rmse(v, g); std::isfinite(e)) sum += e * e, ++n;
    return n ? sum / double(n) : 0.0;
  };
  // Golden section on log k over [1e-3, 10], to 1e-4 in log k.
  const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
  double a = std::log(1e-3), b = std::log(10.0);
  double c = b - phi * (b - a), d = a + phi * (b - a);
  double fc = error(c), fd = error(d);
  while (b - a > 1e-4) {
    if (fc < fd)
      b = d, d = c, fd = fc, c = b - phi * (b - a), fc = error(c);
    else
      a = c, c = d, fc = fd, d = a + phi * (b - a), fd = error(d);
  }
  return std::exp(0.5 * (a + b));
}

std::vector<double> deshmukh2020_table(const FactorGrid& grid, const Deshmukh2020Constants& c) {
  return table_of(grid, [&c](const Vec3& ng, const Vec3& ns, const Vec3& wi) {
    return deshmukh2020_with(ng, ns, wi, c);
  });
}

Deshmukh2020Constants fit_deshmukh2020(const std::vector<TallyVariant>& variants,
                                       const FactorGrid& grid) {
  std::vector<const TallyVariant*> data;
  for (const TallyVariant& v : variants) data.push_back(&v);
  return Deshmukh2020Search(data, grid).fit(all_of(variants.size()));
}

namespace {

// A metric of the study's report per fitted variant: raw bump's and every
// other method's (NaN where the report has none for a variant).
struct VariantValues {
  std::vector<double> none;
  std::map<std::string, std::vector<double>> methods;
};

// `per_scale`: divided by each variant's albedo*E/pi (the image RMSE).
VariantValues variant_values(const MethodErrors& errors, const std::vector<FitVariant>& variants,
                             bool per_scale) {
  VariantValues out;
  for (const FitVariant& v : variants) {
    const auto row = errors.find(v.id);
    if (row != errors.end())
      for (const auto& [m, _] : row->second)
        if (m != "none") out.methods[m];
  }
  const auto at = [&](const FitVariant& v, const std::string& m) {
    const auto row = errors.find(v.id);
    if (row == errors.end() || !row->second.count(m))
      return std::numeric_limits<double>::quiet_NaN();
    return row->second.at(m) / (per_scale ? v.radiance_scale : 1.0);
  };
  for (const FitVariant& v : variants) {
    out.none.push_back(at(v, "none"));
    for (auto& [m, values] : out.methods) values.push_back(at(v, m));
  }
  return out;
}

// The image RMSE's per-variant floors pooled, and each method's image error
// and share of the floors' improvement on raw bump (ImageFloors). Raw
// bump's E is the tally's, the floors' own data; `reported` checks it.
void fit_image_floors(const FitOptions& o, const VariantValues& reported, FitResult* r) {
  say(o, "image RMSE: per-variant floors and shares");
  ImageFloors& f = r->image;
  const std::vector<std::size_t> index = all_of(r->variants.size());
  std::vector<double> none, floor;
  f.none_minus_report = 0.0;
  for (std::size_t k = 0; k < r->variants.size(); ++k) {
    const FitVariant& v = r->variants[k];
    none.push_back(v.image_none);
    floor.push_back(v.image_floor);
    f.kkt_residual = std::max(f.kkt_residual, v.image_kkt_residual);
    if (std::isfinite(reported.none[k]))
      f.none_minus_report =
          std::max(f.none_minus_report, std::abs(v.image_none - reported.none[k]));
  }
  f.floor = pooled_error(floor, index, o);
  f.none = pooled_error(none, index, o);
  for (const auto& [method, values] : reported.methods) {
    MethodShare s;
    s.method = method;
    s.error = pooled_error(values, index, o);
    s.share = share_of(none, values, floor, index, o);
    if (!r->variants.empty() && r->variants.front().image_on_grid.count(method)) {
      std::vector<double> tabulated;
      for (const FitVariant& v : r->variants) tabulated.push_back(v.image_on_grid.at(method));
      s.on_grid_inputs = true;
      s.grid_error = pooled(tabulated, index);
      s.resolution_error = std::abs(s.grid_error - s.error.value);
    }
    f.methods.push_back(s);
  }
  std::stable_sort(f.methods.begin(), f.methods.end(),
                   [](const MethodShare& a, const MethodShare& b) {
                     // NaN (no image RMSE in the report) last.
                     return std::isfinite(a.error.value) &&
                            (!std::isfinite(b.error.value) || a.error.value < b.error.value);
                   });
  share_groups(o, none, floor, reported.methods, &f.methods);
}

// One evaluator render of the study's low-poly section: its offset and
// its image RMSE against its variant's analytic render.
struct OffsetRun {
  std::size_t variant = 0;  // index into LowpolyRuns::family
  OffsetSettings settings;
  double error = 0.0;              // fraction of albedo*E/pi
  double report_difference = 0.0;  // |recomputed - report.json's| RMSE, W m^-2 sr^-1
};

struct LowpolyRuns {
  std::vector<std::string> family;  // per low-poly variant read: its scene
  std::vector<OffsetRun> runs;      // those of offsets with a parameter
};

// Every evaluator render of report.json's low-poly section whose offset has
// a parameter, read back from the cache (a render deleted from it is left
// out) and compared with its variant's analytic render as the study
// compares them (compare_images).
LowpolyRuns lowpoly_runs(const std::filesystem::path& folder, const json& report) {
  LowpolyRuns out;
  if (!report.contains("lowpoly") || report.at("lowpoly").is_null()) return out;
  const json& lowpoly = report.at("lowpoly");
  std::map<std::pair<std::string, std::string>, double> reported;  // (variant, offset) -> RMSE
  for (const json& c : lowpoly.at("comparisons"))
    if (c.value("renderer", "") == "evaluator" &&
        c.value("reference", "") == "evaluator:analytic" && c.at("image").at("rmse").is_number())
      reported[{c.at("variant"), c.at("offset")}] = c.at("image").at("rmse").get<double>();
  for (const json& v : lowpoly.at("variants")) {
    std::string truth;
    std::vector<std::pair<std::string, std::string>> renders;  // (offset label, cache path)
    for (const json& r : v.at("renders")) {
      if (r.value("renderer", "") != "evaluator" || !r.value("exr", json()).is_string() ||
          !std::filesystem::exists(folder / r.at("exr").get<std::string>()))
        continue;
      const std::string exr = (folder / r.at("exr").get<std::string>()).string();
      if (r.value("offset", "") == "analytic")
        truth = exr;
      else
        renders.emplace_back(r.value("offset", ""), exr);
    }
    if (truth.empty()) continue;
    const std::size_t variant = out.family.size();
    out.family.push_back(v.at("scene").get<std::string>());
    std::map<std::string, std::string> attributes;
    const Image truth_image = read_image(truth, &attributes);
    const double scale = radiance_scale(scene_of(truth, attributes["penumbra:scene"]));
    for (const auto& [label, exr] : renders) {
      const Scene scene = scene_of(exr, read_image_attribute(exr, "penumbra:scene"));
      if (!offset_parameter(scene.offset)) continue;
      const double rmse = compare_images(read_image(exr), truth_image).rmse;
      const auto at = reported.find({v.at("id").get<std::string>(), label});
      out.runs.push_back({variant, scene.offset, rmse / scale,
                          at == reported.end() ? std::numeric_limits<double>::quiet_NaN()
                                               : std::abs(rmse - at->second)});
    }
  }
  return out;
}

// What a low-poly offset's parameter is fitted against: its source's value
// where the shipped default is one (MethodParameter::default_value).
std::string offset_reference(OffsetMethod method) {
  switch (method) {
    case OffsetMethod::kCyclesGeometryOffset:
      return "Blender's default";
    case OffsetMethod::kPhong2008:
      return "published";
    case OffsetMethod::kOspray:
      return "OSPRay's";
    case OffsetMethod::kEpsilon:
    case OffsetMethod::kNone:
    case OffsetMethod::kGist2020:
    case OffsetMethod::kHanika2021:
      break;
  }
  return "Penumbra's default";
}

// One offset's parameter fitted among its values (FittedOffsetParameter),
// over the low-poly variants that rendered every value; nullopt where none did.
std::optional<FittedOffsetParameter> fit_offset_parameter(
    const FitOptions& o, OffsetMethod method,
    const std::map<double, std::map<std::size_t, const OffsetRun*>>& by_value,
    const std::vector<std::string>& families) {
  std::vector<std::size_t> variants;
  for (std::size_t i = 0; i < families.size(); ++i)
    if (std::all_of(by_value.begin(), by_value.end(),
                    [&](const auto& value) { return value.second.count(i) != 0; }))
      variants.push_back(i);
  if (variants.empty()) return std::nullopt;
  FittedOffsetParameter f;
  f.variants = variants.size();
  std::vector<std::vector<double>> error;
  for (const auto& [value, runs] : by_value) {
    f.values.push_back(value);
    error.emplace_back();
    for (std::size_t i : variants) {
      error.back().push_back(runs.at(i)->error);
      if (std::isfinite(runs.at(i)->report_difference))
        f.report_difference = std::max(f.report_difference, runs.at(i)->report_difference);
    }
    f.errors.push_back(pooled_error(error.back(), all_of(variants.size()), o));
  }
  std::vector<std::string> family;
  for (std::size_t i : variants) family.push_back(families[i]);
  const MethodParameter& parameter = offset_method_info(method).parameters.front();
  f.fit.method = std::string(offset_method_info(method).id);
  f.fit.constant = fmt::format("{} [{}]", parameter.name, parameter.unit);
  const auto published = std::find(f.values.begin(), f.values.end(), parameter.default_value);
  f.fit.reference =
      published == f.values.end() ? "the study's lowest value" : offset_reference(method);
  fit_among_values(o, f.values,
                   published == f.values.end() ? 0 : std::size_t(published - f.values.begin()),
                   error, family, &f.fit);
  return f;
}

// Every low-poly offset the study rendered at two or more values of its
// parameter, refitted among them.
void fit_offset_parameters(const FitOptions& o, const LowpolyRuns& lowpoly, FitResult* r) {
  std::map<OffsetMethod, std::map<double, std::map<std::size_t, const OffsetRun*>>> by_method;
  for (const OffsetRun& run : lowpoly.runs)
    by_method[run.settings.method][*offset_parameter(run.settings)][run.variant] = &run;
  for (const auto& [method, by_value] : by_method) {
    if (by_value.size() < 2) continue;
    say(o, fmt::format("fitting {}'s parameter on the low-poly section",
                       offset_method_info(method).id));
    if (auto f = fit_offset_parameter(o, method, by_value, lowpoly.family))
      r->offset_parameters.push_back(std::move(*f));
  }
}

}  // namespace

FitResult fit_study(const FitOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  const std::filesystem::path report_path = std::filesystem::path(o.folder) / "report.json";
  if (!std::filesystem::is_regular_file(report_path))
    throw InputError(report_path.string(), "",
                     "no such file (give a finished study's output folder)");
  const json report = read_json_file(report_path.string());
  FitResult r;
  r.folder = o.folder;
  r.grid = o.grid;
  if (o.smoothness.empty()) throw std::invalid_argument("fit_study: no candidate smoothness");
  r.smoothness_candidates = o.smoothness;
  MethodErrors errors, image_errors;
  LowpolyRuns lowpoly;
  try {
    r.study = report.at("study").value("name", "");
    load_variants(o, report, &r);
    errors = method_errors(report);
    image_errors = method_errors(report, "/image/rmse"_json_pointer);
    lowpoly = lowpoly_runs(o.folder, report);
  } catch (const json::exception& e) {
    throw InputError(report_path.string(), "", fmt::format("not a study's report: {}", e.what()));
  }
  const VariantValues values = variant_values(errors, r.variants, false);
  const std::vector<double>& none = values.none;
  const std::map<std::string, std::vector<double>>& methods = values.methods;
  say(o, fmt::format("floor over the study's {} variants", r.variants.size()));
  r.study_floor = floor_over(r, "study", all_of(r.variants.size()), none, o);
  fit_nested_floors(o, none, &r);
  for (const auto& [family, index] : families(r.variants))
    r.family_floors.push_back(floor_over(r, family, index, none, o));
  fit_shares(o, none, methods, &r);
  FloorSolves solves(r, o);
  fit_held_out(o, none, methods, solves, &r);
  std::set<std::string> all_families;
  for (const FitVariant& v : r.variants) all_families.insert(v.family);
  say(o, "the table: choosing its smoothness over every family");
  r.table_smoothness = choose_smoothness(r, all_families, o, solves);
  FloorOptions options;
  options.smoothness = r.table_smoothness;
  r.table = {r.grid,
             solve_floor(r.grid, data_of(r.variants, all_of(r.variants.size())), options).g};
  fit_constants(o, errors, &r);
  fit_image_floors(o, variant_values(image_errors, r.variants, true), &r);
  fit_offset_parameters(o, lowpoly, &r);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

namespace {

json interval_json(const PooledError& e) {
  return {e.value, e.interval.low, e.interval.high};
}

json paired_json(const PairedError& p) {
  return {{"difference", interval_json(p.difference)}, {"tie", p.tie}};
}

json floor_json(const FloorFit& f) {
  return {{"scope", f.scope},
          {"variants", f.variants},
          {"floor", interval_json(f.floor)},
          {"none", interval_json(f.none)},
          {"kkt_residual", f.solution.kkt_residual},
          // The cells some variant lights: the floor's free values.
          {"lit_cells",
           std::count(f.solution.constrained.begin(), f.solution.constrained.end(), char(1))}};
}

// G over the grid's cells for the report's contour figure (light,deviation
// grids only): the study floor's G* (null where no variant has light), the
// fitted table, and chiang2019 and estevez2019 with Ns tilted towards the
// light (analysis/contour.h's geometry, Chiang et al. 2019 Fig. 5).
json pictures_json(const FitResult& r) {
  if (!light_deviation_grid(r.grid)) return nullptr;
  const auto rows = [&](const std::vector<double>& g, const std::vector<char>* mask) {
    const int nl = r.grid.axes[0].cells(), nd = r.grid.axes[1].cells();
    json out = json::array();
    for (int d = 0; d < nd; ++d) {
      json row = json::array();
      for (int l = 0; l < nl; ++l) {
        const std::size_t c = std::size_t(d) * std::size_t(nl) + std::size_t(l);
        row.push_back(mask && !(*mask)[c] ? json() : json(g[c]));
      }
      out.push_back(row);
    }
    return out;
  };
  const auto centres = [](const FactorAxis& a) {
    json c = json::array();
    for (int k = 0; k < a.cells(); ++k) c.push_back(a.min_deg + (k + 0.5) * a.step_deg);
    return c;
  };
  return {{"light_deg", centres(r.grid.axes[0])},
          {"deviation_deg", centres(r.grid.axes[1])},
          {"note",
           "G at the cells' centres, rows by deviation; chiang2019 and estevez2019 with "
           "Ns tilted towards the light"},
          {"g",
           {{"floor", rows(r.study_floor.solution.g, &r.study_floor.solution.constrained)},
            {"fitted", rows(r.table.values, nullptr)},
            {"estevez2019", rows(table_of(r.grid, estevez2019), nullptr)},
            {"chiang2019", rows(table_of(r.grid, chiang2019), nullptr)}}}};
}

json share_json(const MethodShare& s) {
  json m{{"method", s.method},
         {"error", interval_json(s.error)},
         {"share", interval_json(s.share)},
         {"group", s.group ? json(s.group) : json()},
         {"leader", s.group ? json(s.leader) : json()},
         {"versus_leader", s.group ? paired_json(s.versus_leader) : json()}};
  if (s.on_grid_inputs)
    m["on_grid"] = {{"error", s.grid_error}, {"resolution_error", s.resolution_error}};
  return m;
}

json image_json(const ImageFloors& f) {
  json j{{"unit",
          "image RMSE (ImageMetrics::rmse over pixels fully covered in the render and the truth), "
          "fraction of albedo*E/pi, pooled over variants as a root mean square; each variant's "
          "floor is fitted to that variant alone; intervals: 95 % percentile bootstrap over "
          "variants"},
         {"floor", interval_json(f.floor)},
         {"none", interval_json(f.none)},
         {"none_minus_report",
          std::isfinite(f.none_minus_report) ? json(f.none_minus_report) : json()},
         {"kkt_residual", f.kkt_residual},
         {"methods", json::array()}};
  for (const MethodShare& s : f.methods) j["methods"].push_back(share_json(s));
  return j;
}

// A refitted constant's value, errors and edge, as fit.json names them.
json fitted_json(const FittedConstant& c) {
  return {{"fitted", {c.fitted, c.interval.low, c.interval.high}},
          {"error_fitted_in_sample", interval_json(c.in_sample)},
          {"error_published", interval_json(c.at_published)},
          {"error_fitted_held_out", c.held_out_defined ? interval_json(c.held_out) : json()},
          {"held_out_minus_published",
           c.held_out_defined ? paired_json(c.held_out_minus_published) : json()},
          {"at_bound", c.at_bound.empty() ? json() : json(c.at_bound)}};
}

json offset_parameter_json(const FittedOffsetParameter& f) {
  const FittedConstant& c = f.fit;
  json values = json::array();
  for (std::size_t k = 0; k < f.values.size(); ++k)
    values.push_back({{"value", f.values[k]}, {"error", interval_json(f.errors[k])}});
  json j{{"offset", c.method},
         {"parameter", c.constant},
         {"unit",
          "image RMSE of the evaluator's mesh render against the analytic surface (pixels fully "
          "covered in both), fraction of albedo*E/pi, pooled over the low-poly variants as a root "
          "mean square; intervals: 95 % percentile bootstrap over those variants"},
         {"variants", f.variants},
         {"reference", c.reference},
         {"published", c.published},
         {"values", values},
         {"report_difference", f.report_difference}};
  j.update(fitted_json(c));
  return j;
}

json result_json(const FitResult& r) {
  json j{
      {"study", r.study},
      {"unit",
       "terminator-profile RMSE, fraction of albedo*E/pi, pooled over variants as a "
       "root mean square; intervals: 95 % percentile bootstrap over variants"},
      {"inputs", grid_inputs(r.grid)},
      {"grid", factor_grid_json(r.grid)},
      {"variants", r.variants.size()},
      {"skipped", r.skipped},
      {"unconverged_truths", r.unconverged},
      {"retraced", r.retraced},
      {"retraced_different", r.retraced_different},
      {"outside_grid_share", r.outside_share},
      {"floor", floor_json(r.study_floor)},
      {"image_floor", image_json(r.image)},
      {"pictures", pictures_json(r)},
      {"held_out_pooled", r.held_out.empty() ? json() : interval_json(r.held_out_pooled)},
      {"best_method", r.best_method.empty() ? json() : json(r.best_method)},
      {"held_out_minus_best",
       r.held_out.empty() || r.best_method.empty() ? json() : paired_json(r.held_out_minus_best)},
      {"table_smoothness", r.table_smoothness},
      {"smoothness_candidates", r.smoothness_candidates},
      {"seconds", r.seconds},
      // Arrays even when empty (one scene family: nothing to hold out).
      {"family_floors", json::array()},
      {"nested_floors", json::array()},
      {"held_out", json::array()},
      {"methods", json::array()},
      {"constants", json::array()},
      {"offset_parameters", json::array()}};
  for (const FloorFit& f : r.family_floors) j["family_floors"].push_back(floor_json(f));
  for (const NestedFloor& n : r.nested) {
    json f = floor_json(n.floor);
    f["inputs"] = n.inputs;
    f["gain"] = paired_json(n.gain);
    j["nested_floors"].push_back(f);
  }
  for (const HeldOutFit& h : r.held_out)
    j["held_out"].push_back(
        {{"family", h.family},
         {"variants", h.variants},
         {"smoothness", h.smoothness},
         {"held_out", interval_json(h.held_out)},
         {"in_sample_floor", h.in_sample},
         {"none", interval_json(h.none)},
         {"best_method", h.best_method},
         {"best", interval_json(h.best)},
         {"held_out_minus_best",
          h.best_method.empty() ? json() : paired_json(h.held_out_minus_best)}});
  for (const MethodShare& s : r.shares) j["methods"].push_back(share_json(s));
  for (const FittedConstant& c : r.constants) {
    json e{{"method", c.method},
           {"constant", c.constant},
           {"reference", c.reference},
           {"published", c.published},
           {"probe_minus_rendered",
            std::isfinite(c.probe_minus_rendered) ? json(c.probe_minus_rendered) : json()}};
    e.update(fitted_json(c));
    j["constants"].push_back(e);
  }
  for (const FittedOffsetParameter& f : r.offset_parameters)
    j["offset_parameters"].push_back(offset_parameter_json(f));
  return j;
}

// One row per number: what, scope, value, interval, unit.
std::string result_csv(const FitResult& r) {
  const std::string unit = "fraction of albedo*E/pi (pooled terminator RMSE)";
  std::string csv = "quantity,scope,value,low,high,unit\n";
  const auto row = [&](const std::string& q, const std::string& scope, const PooledError& e,
                       const std::string& u) {
    csv += fmt::format("{},{},{:.9g},{:.9g},{:.9g},{}\n", q, scope, e.value, e.interval.low,
                       e.interval.high, u);
  };
  row("floor", "study", r.study_floor.floor, unit);
  row("none", "study", r.study_floor.none, unit);
  for (const FloorFit& f : r.family_floors) row("floor", f.scope, f.floor, unit);
  for (const NestedFloor& n : r.nested) {
    row("floor_of:" + n.inputs, "study", n.floor.floor, unit);
    row("floor_minus_floor_of:" + n.inputs, "study", n.gain.difference, unit);
  }
  for (const HeldOutFit& h : r.held_out) {
    row("fitted_table_held_out", h.family, h.held_out, unit);
    if (!h.best_method.empty())
      row("held_out_minus_best:" + h.best_method, h.family, h.held_out_minus_best.difference, unit);
  }
  row("fitted_table_held_out", "study", r.held_out_pooled, unit);
  if (!r.held_out.empty() && !r.best_method.empty())
    row("held_out_minus_best:" + r.best_method, "study", r.held_out_minus_best.difference, unit);
  for (const MethodShare& s : r.shares) {
    row("error:" + s.method, "study", s.error, unit);
    row("share:" + s.method, "study", s.share, "fraction of the floor's improvement on raw bump");
  }
  const std::string image_unit = "fraction of albedo*E/pi (pooled image RMSE)";
  row("image_floor", "study", r.image.floor, image_unit + ", per-variant floors");
  row("image_none", "study", r.image.none, image_unit);
  for (const MethodShare& s : r.image.methods) {
    row("image_error:" + s.method, "study", s.error, image_unit);
    row("image_share:" + s.method, "study", s.share,
        "fraction of the per-variant image floors' improvement on raw bump");
  }
  // A method with several constants names each by its symbol (the first
  // word of `constant`): constant:deshmukh2020:d0.
  std::map<std::string, int> per_method;
  for (const FittedConstant& c : r.constants) ++per_method[c.method];
  for (const FittedConstant& c : r.constants) {
    const std::string symbol = c.constant.substr(0, c.constant.find(' '));
    row("constant:" + c.method + (per_method[c.method] > 1 ? ":" + symbol : ""), "study",
        {c.fitted, c.interval}, c.constant);
  }
  // The errors are the method's set of constants': one row each per method.
  std::set<std::string> errors_written;
  for (const FittedConstant& c : r.constants) {
    if (!errors_written.insert(c.method).second) continue;
    row("constant_error_published:" + c.method, "study", c.at_published, unit);
    row("constant_error_in_sample:" + c.method, "study", c.in_sample, unit);
    if (!c.held_out_defined) continue;
    row("constant_error_held_out:" + c.method, "study", c.held_out, unit);
    row("held_out_minus_published:" + c.method, "study", c.held_out_minus_published.difference,
        unit);
  }
  const std::string lowpoly_unit =
      "fraction of albedo*E/pi (pooled image RMSE of the low-poly renders against the analytic "
      "surface)";
  for (const FittedOffsetParameter& f : r.offset_parameters) {
    const FittedConstant& c = f.fit;
    row("offset_parameter:" + c.method, "lowpoly", {c.fitted, c.interval}, c.constant);
    for (std::size_t k = 0; k < f.values.size(); ++k)
      row(fmt::format("offset_error:{}={:g}", c.method, f.values[k]), "lowpoly", f.errors[k],
          lowpoly_unit);
    row("offset_error_published:" + c.method, "lowpoly", c.at_published, lowpoly_unit);
    row("offset_error_in_sample:" + c.method, "lowpoly", c.in_sample, lowpoly_unit);
    if (!c.held_out_defined) continue;
    row("offset_error_held_out:" + c.method, "lowpoly", c.held_out, lowpoly_unit);
    row("offset_held_out_minus_published:" + c.method, "lowpoly",
        c.held_out_minus_published.difference, lowpoly_unit);
  }
  return csv;
}

}  // namespace

void write_fit(const FitResult& r, const std::filesystem::path& out) {
  std::filesystem::create_directories(out);
  write_text_file((out / "fit.json").string(), result_json(r).dump(2) + "\n");
  write_text_file((out / "fit.csv").string(), result_csv(r));
  const json table = factor_table_json(
      r.table, {{"smoothness", r.table_smoothness},
                {"note",
                 "G at the cells' centres, first axis fastest, multilinear between them; "
                 "outside the grid G = 1"}});
  write_text_file((out / "table.json").string(), table.dump(1) + "\n");
}

// What fit.json holds, raised when it gains a quantity, so that a study's
// fit step redoes a fit written without it (2: deshmukh2020's constants;
// 3: intervals on the constants' errors, paired differences, share groups;
// 4: variants whose truth did not converge left out and named; 5: the
// inputs, nested floors, chiang2019 on grids with a shading axis; 6: the
// probed constants of shading-offset and the micro-shadowing methods; 7:
// the image RMSE's per-variant floors; 8: the low-poly offsets'
// parameters).
constexpr const char* kFitContents = "8";

std::string fit_inputs_digest(const std::filesystem::path& study) {
  std::uint64_t h = fnv1a(without_run_keys(read_file((study / "report.json").string())));
  h = fnv1a(std::string(build_code_digests().evaluator) + "\n" + kPenumbraVersion + "\nfit.json " +
                kFitContents,
            h);
  return fmt::format("{:016x}", h);
}

bool fit_is_current(const std::filesystem::path& fit_dir, const std::string& digest) {
  for (const char* file : {"fit.json", "fit.csv", "table.json"})
    if (!std::filesystem::is_regular_file(fit_dir / file)) return false;
  std::ifstream in(fit_dir / ".inputs");
  std::string line;
  return std::getline(in, line) && line == digest;
}

void write_fit_stamp(const std::filesystem::path& fit_dir, const std::string& digest) {
  write_text_file((fit_dir / ".inputs").string(), digest + "\n");
}

}  // namespace penumbra
