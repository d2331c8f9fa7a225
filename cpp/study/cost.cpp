#include "study/cost.h"

#include <algorithm>
#include <charconv>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <tuple>

#include "image/image_io.h"
#include "study/cache.h"
#include "study/plan.h"

namespace penumbra {
namespace {

using Kind = std::tuple<RendererKind, Representation, bool>;

Kind kind_of(const Job& job) {
  return {job.renderer, job.representation, job.scene().tessellation.has_value()};
}

double msamples(const Scene& scene) {
  return double(scene.camera.width) * scene.camera.height * scene.camera.spp / 1e6;
}

// Probing the renderers' versions, core-seconds.
constexpr double kProbeSeconds = 2.0;
// The comparisons (metrics, intervals, pictures) and the figures, wall
// seconds on 2 cores: fixed + per comparison (default study: 2,136
// comparisons, about 90 s; smoke study: 64, about 9 s).
constexpr double kReportFixedSeconds = 6.0;
constexpr double kReportSecondsPerComparison = 0.04;

RenderCostModel model_for(const Kind& kind) {
  if (const auto m = built_in_cost(std::get<0>(kind), std::get<1>(kind), std::get<2>(kind)))
    return *m;
  // A kind missing from its renderer's costs is priced like the dearest, so
  // that an estimate errs on the safe side (the tests keep the costs complete).
  RenderCostModel dearest;
  for (RendererKind r : all_renderers())
    for (const BuiltInCost& c : renderer(r).costs)
      dearest.per_msample = std::max(dearest.per_msample, c.model.per_msample);
  return dearest;
}

double mtriangles(const Job& job) {
  return job.resources.triangles / 1e6;
}

std::optional<double> parse_number(const std::string& text) {
  double value = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size() || !(value >= 0.0)) return std::nullopt;
  return value;
}

// A cached render's core-seconds per 10^6 pixel samples, if it recorded them
// (entries written before version 0.7 did not).
std::optional<double> measured_rate(const Job& job, const RenderCache& cache) {
  std::map<std::string, std::string> attributes;
  try {
    attributes = read_image_attributes(cache.exr_path(job.key));
  } catch (const std::exception&) {
    return std::nullopt;
  }
  const auto wall = parse_number(attributes[kCostWallAttribute]);
  const auto threads = parse_number(attributes[kCostThreadsAttribute]);
  if (!wall || !threads || *threads < 1.0) return std::nullopt;
  const RenderCostModel m = model_for(kind_of(job));
  return std::max(0.0, *wall * *threads - m.fixed - m.per_mtriangle * mtriangles(job)) /
         msamples(job.scene());
}

double median(std::vector<double> values) {
  const std::size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + long(mid), values.end());
  const double upper = values[mid];
  if (values.size() % 2 == 1) return upper;
  return 0.5 * (upper + *std::max_element(values.begin(), values.begin() + long(mid)));
}

}  // namespace

// The built-in prices (RendererEntry::costs, in each renderer's entry) are
// core-seconds per render kind: fixed + per 10^6 pixel samples + per 10^6
// mesh triangles (the displaced truths' and Blender's meshes), fitted to the
// cache headers of cold runs of the smoke, quick and default studies on a
// 2-core AMD EPYC (2 renders at a time, one thread each; Blender 3.4.1,
// POV-Ray 3.7). Kinds those studies do not render are marked "as" the kind
// they are priced like. Only used for kinds of which the study's own cache
// holds no render yet.
std::optional<RenderCostModel> built_in_cost(RendererKind renderer, Representation representation,
                                             bool tessellated) {
  for (const BuiltInCost& c : penumbra::renderer(renderer).costs)
    if (c.representation == representation && c.tessellated == tessellated) return c.model;
  return std::nullopt;
}

namespace {

// Per kind with renders to do: the line, priced from the cache where it can.
std::map<Kind, CostLine> price_lines(const Plan& plan, const RenderCache& cache,
                                     const std::vector<char>& to_render) {
  constexpr std::size_t kMaxMeasured = 64;
  std::map<Kind, CostLine> lines;
  for (std::size_t i = 0; i < plan.jobs.size(); ++i) {
    if (!to_render[i]) continue;
    CostLine& line = lines[kind_of(plan.jobs[i])];
    std::tie(line.renderer, line.representation, line.tessellated) = kind_of(plan.jobs[i]);
    ++line.renders;
  }
  // Headers are read only for kinds that have renders to price.
  std::map<Kind, std::vector<double>> rates;
  for (std::size_t i = 0; i < plan.jobs.size(); ++i) {
    const Kind kind = kind_of(plan.jobs[i]);
    if (to_render[i] || !lines.count(kind) || rates[kind].size() >= kMaxMeasured) continue;
    if (const auto rate = measured_rate(plan.jobs[i], cache)) rates[kind].push_back(*rate);
  }
  for (auto& [kind, line] : lines) {
    line.model = model_for(kind);
    std::vector<double>& measured = rates[kind];
    line.measured = measured.size();
    if (measured.empty()) continue;
    std::sort(measured.begin(), measured.end());
    line.model.per_msample = median(measured);
    line.core_seconds_low = measured.front();  // rates until the renders are summed
    line.core_seconds_high = measured.back();
  }
  return lines;
}

double job_core_seconds(const Job& job, const RenderCostModel& m) {
  return m.core_seconds(msamples(job.scene()), mtriangles(job));
}

// The comparisons a cold run makes: each test render against its own
// renderer's truth, and an external one also against the evaluator's.
std::size_t comparison_count(const Plan& plan) {
  std::size_t n = 0;
  for (const Job& job : plan.jobs)
    if (!job.truth) n += job.renderer == RendererKind::kEvaluator ? 1 : 2;
  return n;
}

}  // namespace

CostEstimate estimate_cost(const Plan& plan, const RenderCache& cache,
                           const std::vector<char>& to_render, const std::vector<Job>& first_checks,
                           int cores) {
  std::map<Kind, CostLine> lines = price_lines(plan, cache, to_render);
  std::map<Kind, double> work;  // 10^6 pixel samples to render, per kind
  CostEstimate estimate;
  std::set<RendererKind> renderers;  // that have renders to do
  for (std::size_t i = 0; i < plan.jobs.size(); ++i) {
    if (!to_render[i]) continue;
    const Kind kind = kind_of(plan.jobs[i]);
    lines[kind].core_seconds += job_core_seconds(plan.jobs[i], lines[kind].model);
    work[kind] += msamples(plan.jobs[i].scene());
    renderers.insert(plan.jobs[i].renderer);
  }
  for (auto& [kind, line] : lines) {
    if (line.measured > 0) {  // price_lines left the slowest and fastest rates here
      const double median_rate = line.model.per_msample;
      line.core_seconds_low =
          line.core_seconds + (line.core_seconds_low - median_rate) * work[kind];
      line.core_seconds_high =
          line.core_seconds + (line.core_seconds_high - median_rate) * work[kind];
    }
    estimate.core_seconds += line.core_seconds;
    estimate.lines.push_back(line);
  }
  for (const Job& check : first_checks)
    estimate.first_checks_core_seconds += job_core_seconds(check, model_for(kind_of(check)));
  estimate.first_checks = first_checks.size();
  estimate.checks_core_seconds = kCheckRoundsRatio * estimate.first_checks_core_seconds;
  estimate.comparisons = comparison_count(plan);
  estimate.report_seconds =
      kReportFixedSeconds + kReportSecondsPerComparison * double(estimate.comparisons);
  estimate.cores = std::max(1, cores);
  double starts = kProbeSeconds;
  for (RendererKind r : renderers) starts += renderer(r).start_seconds * double(estimate.cores);
  estimate.wall_seconds =
      (estimate.core_seconds + estimate.checks_core_seconds + starts) / double(estimate.cores) +
      estimate.report_seconds;
  return estimate;
}

}  // namespace penumbra
