#include "study/cost.h"

#include <algorithm>
#include <charconv>
#include <map>
#include <optional>
#include <string>
#include <tuple>

#include "image/image_io.h"
#include "study/cache.h"
#include "study/plan.h"

namespace penumbra {
namespace {

using Kind = std::tuple<RendererKind, Representation, bool>;

Kind kind_of(const Job& job) {
  return {job.renderer, job.representation, job.scene.tessellation.has_value()};
}

double msamples(const Scene& scene) {
  return double(scene.camera.width) * scene.camera.height * scene.camera.spp / 1e6;
}

// Core-seconds per 10^6 pixel samples, measured on the default study
// (`harness/run-main.sh`, cold, version 0.7.0, 2 renders at a time with one
// thread each) on a 2-core AMD EPYC machine with Blender 3.4.1 and POV-Ray
// 3.7: the median over its cache entries of each kind, and, for kinds that
// study does not render, the kind named beside the row. Only used for kinds
// of which the study's own cache holds no render yet.
struct BuiltInRate {
  RendererKind renderer;
  Representation representation;
  bool tessellated;
  double core_seconds_per_msample;
};
constexpr BuiltInRate kBuiltInRates[] = {
    {RendererKind::kEvaluator, Representation::kSmooth, false, 0.144},       // as bump
    {RendererKind::kEvaluator, Representation::kSmooth, true, 0.248},        // 148 renders
    {RendererKind::kEvaluator, Representation::kBump, false, 0.144},         // 168 renders
    {RendererKind::kEvaluator, Representation::kBump, true, 0.248},          // as smooth, low-poly
    {RendererKind::kEvaluator, Representation::kDisplacement, false, 2.48},  // 117 renders
    {RendererKind::kEvaluator, Representation::kDisplacement, true, 2.48},   // as untessellated
    {RendererKind::kPovray, Representation::kSmooth, false, 4.55},           // as bump
    {RendererKind::kPovray, Representation::kSmooth, true, 3.78},            // 21 renders
    {RendererKind::kPovray, Representation::kBump, false, 4.55},             // 24 renders
    {RendererKind::kPovray, Representation::kBump, true, 4.55},              // as bump
    {RendererKind::kPovray, Representation::kDisplacement, false, 54.3},     // 24 renders
    {RendererKind::kPovray, Representation::kDisplacement, true, 54.3},      // as untessellated
    {RendererKind::kBlender, Representation::kSmooth, false, 2.42},          // as bump
    {RendererKind::kBlender, Representation::kSmooth, true, 1.08},           // 57 renders
    {RendererKind::kBlender, Representation::kBump, false, 2.42},            // 72 renders
    {RendererKind::kBlender, Representation::kBump, true, 2.42},             // as bump
    {RendererKind::kBlender, Representation::kDisplacement, false, 15.6},    // 24 renders
    {RendererKind::kBlender, Representation::kDisplacement, true, 15.6},     // as untessellated
};

double rate_for(const Kind& kind) {
  if (const auto rate = built_in_rate(std::get<0>(kind), std::get<1>(kind), std::get<2>(kind)))
    return *rate;
  // A kind missing from the table is priced like the dearest, so that an
  // estimate errs on the safe side (the tests keep the table complete).
  double dearest = 0.0;
  for (const BuiltInRate& r : kBuiltInRates)
    dearest = std::max(dearest, r.core_seconds_per_msample);
  return dearest;
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
  return *wall * *threads / msamples(job.scene);
}

double median(std::vector<double> values) {
  const std::size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + long(mid), values.end());
  const double upper = values[mid];
  if (values.size() % 2 == 1) return upper;
  return 0.5 * (upper + *std::max_element(values.begin(), values.begin() + long(mid)));
}

}  // namespace

std::optional<double> built_in_rate(RendererKind renderer, Representation representation,
                                    bool tessellated) {
  for (const BuiltInRate& r : kBuiltInRates)
    if (r.renderer == renderer && r.representation == representation &&
        r.tessellated == tessellated)
      return r.core_seconds_per_msample;
  return std::nullopt;
}

CostEstimate estimate_cost(const Plan& plan, const RenderCache& cache,
                           const std::vector<char>& to_render) {
  constexpr std::size_t kMaxMeasured = 64;
  std::map<Kind, CostLine> lines;
  std::map<Kind, double> work;  // 10^6 pixel samples to render
  for (std::size_t i = 0; i < plan.jobs.size(); ++i) {
    if (!to_render[i]) continue;
    const Kind kind = kind_of(plan.jobs[i]);
    CostLine& line = lines[kind];
    std::tie(line.renderer, line.representation, line.tessellated) = kind;
    ++line.renders;
    work[kind] += msamples(plan.jobs[i].scene);
  }
  // Headers are read only for kinds that have renders to price.
  std::map<Kind, std::vector<double>> rates;
  for (std::size_t i = 0; i < plan.jobs.size(); ++i) {
    const Kind kind = kind_of(plan.jobs[i]);
    if (to_render[i] || !lines.count(kind) || rates[kind].size() >= kMaxMeasured) continue;
    if (const auto rate = measured_rate(plan.jobs[i], cache)) rates[kind].push_back(*rate);
  }
  CostEstimate estimate;
  for (auto& [kind, line] : lines) {
    std::vector<double>& measured = rates[kind];
    line.measured = measured.size();
    line.core_seconds_per_msample = measured.empty() ? rate_for(kind) : median(measured);
    line.core_seconds = line.core_seconds_per_msample * work[kind];
    if (!measured.empty()) {
      std::sort(measured.begin(), measured.end());
      line.core_seconds_low = measured.front() * work[kind];
      line.core_seconds_high = measured.back() * work[kind];
    }
    estimate.core_seconds += line.core_seconds;
    estimate.lines.push_back(line);
  }
  return estimate;
}

}  // namespace penumbra
