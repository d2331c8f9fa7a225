#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "analysis/filtering.h"

namespace penumbra {

namespace {

using nlohmann::json;

json number(double x) {
  return std::isfinite(x) ? json(x) : json(nullptr);
}

json stat_json(const MeanWithInterval& m) {
  return {{"mean", number(m.mean)},
          {"interval", {number(m.interval.low), number(m.interval.high)}},
          {"n", m.n}};
}

std::string id(RoughnessFilter f) {
  return std::string(roughness_filter_info(f).id);
}

// "a tie", "ggx better", ... from an interval of a mean difference (a - b).
const char* verdict(const PairedComparison& c) {
  if (c.n == 0) return "no data";
  if (c.interval.high < 0.0) return "first lower";
  if (c.interval.low > 0.0) return "second lower";
  return "tie";
}

// The perceived roughness is the highlight's width: which filter keeps it
// closest to the reference's (|log width ratio|), and which keep it within
// their interval (the interval contains 1).
std::string perceived_roughness_finding(const std::vector<FilterSummary>& summary) {
  const FilterSummary* closest = nullptr;
  std::string within;
  for (const FilterSummary& s : summary) {
    const MeanWithInterval& w = s.width_ratio;
    if (!(w.mean > 0.0)) continue;
    if (!closest || std::abs(std::log(w.mean)) < std::abs(std::log(closest->width_ratio.mean)))
      closest = &s;
    if (w.interval.low <= 1.0 && w.interval.high >= 1.0)
      within += (within.empty() ? "" : ", ") + id(s.filter);
  }
  if (!closest) return "No filter has a defined highlight width.";
  const MeanWithInterval& w = closest->width_ratio;
  return fmt::format(
      "Perceived roughness (highlight width): closest to the reference's is {} ({:.3f} [{:.3f}, "
      "{:.3f}]); {}.",
      id(closest->filter), w.mean, w.interval.low, w.interval.high,
      within.empty() ? "no filter's interval contains 1 (every one changes the width)"
                     : "width ratio interval containing 1 (width kept): " + within);
}

}  // namespace

std::vector<std::string> filtering_findings(const FilteringResult& r) {
  std::vector<std::string> out;
  if (r.summary.size() >= 2) {
    const FilterSummary& best = r.summary[0];
    const FilterSummary& next = r.summary[1];
    const PairedComparison& c = r.best_against_runner_up;
    const bool tie = std::string(verdict(c)) != "first lower";
    out.push_back(fmt::format(
        "Lowest profile error over levels >= 1: {} ({:.3f} [{:.3f}, {:.3f}], fraction of the "
        "reference profile's L2 norm), {} {} ({:.3f} [{:.3f}, {:.3f}]): mean difference {:.4f} "
        "[{:.4f}, {:.4f}] over {} footprints{}.",
        id(best.filter), best.profile_error.mean, best.profile_error.interval.low,
        best.profile_error.interval.high, tie ? "tied with" : "ahead of", id(next.filter),
        next.profile_error.mean, next.profile_error.interval.low, next.profile_error.interval.high,
        c.mean_difference, c.interval.low, c.interval.high, c.n,
        tie ? " (the interval contains 0: a tie)" : ""));
    out.push_back(
        fmt::format("Highlight width kept by {}: {:.3f} [{:.3f}, {:.3f}] of the reference's (1 = "
                    "preserved).",
                    id(best.filter), best.width_ratio.mean, best.width_ratio.interval.low,
                    best.width_ratio.interval.high));
    out.push_back(perceived_roughness_finding(r.summary));
  }
  std::size_t ggx_better = 0, beckmann_better = 0, ties = 0;
  // Per base roughness: which mapping wins in how many of its levels.
  std::string per_alpha;
  for (std::size_t i = 0; i < r.claim.size();) {
    const double alpha = r.claim[i].alpha;
    std::size_t g = 0, b = 0, t = 0;
    for (; i < r.claim.size() && r.claim[i].alpha == alpha; ++i) {
      const std::string v = verdict(r.claim[i].comparison);
      (v == "first lower" ? g : v == "second lower" ? b : t)++;
    }
    ggx_better += g;
    beckmann_better += b;
    ties += t;
    per_alpha +=
        fmt::format("{}alpha {:g}: {}/{}/{}", per_alpha.empty() ? "" : "; ", alpha, g, b, t);
  }
  if (!r.claim.empty())
    out.push_back(fmt::format(
        "The chapter's claim (sigma^2 = 2 alpha^2 beats sigma^2 = alpha^2) on profile error: "
        "ggx-variance-estevez2019 lower in {} of {} (alpha, level) cells, "
        "beckmann-variance lower in {}, tied in {} (95 % bootstrap interval of the paired "
        "mean difference); per base alpha, ggx lower/beckmann lower/tied over the levels: {}.",
        ggx_better, r.claim.size(), beckmann_better, ties, per_alpha));
  return out;
}

std::string filtering_json(const FilteringResult& r, const FilteringOptions& o,
                           const FilteringSource& source) {
  json cells = json::array();
  for (const FilteringCell& c : r.cells)
    cells.push_back({{"filter", id(c.filter)},
                     {"alpha", c.alpha},
                     {"level", c.level},
                     {"texels_per_pixel", 1 << c.level},
                     {"energy_ratio", stat_json(c.energy_ratio)},
                     {"width_ratio", stat_json(c.width_ratio)},
                     {"profile_error", stat_json(c.profile_error)}});
  json claim = json::array();
  for (const ClaimCell& c : r.claim)
    claim.push_back(
        {{"alpha", c.alpha},
         {"level", c.level},
         {"mean_difference", number(c.comparison.mean_difference)},
         {"interval", {number(c.comparison.interval.low), number(c.comparison.interval.high)}},
         {"ggx_lower", c.comparison.a_better},
         {"beckmann_lower", c.comparison.b_better},
         {"sign_test_p", c.comparison.p},
         {"verdict", verdict(c.comparison)}});
  json summary = json::array();
  for (const FilterSummary& s : r.summary)
    summary.push_back({{"filter", id(s.filter)},
                       {"energy_ratio", stat_json(s.energy_ratio)},
                       {"width_ratio", stat_json(s.width_ratio)},
                       {"profile_error", stat_json(s.profile_error)}});
  return json{
      {"format", "penumbra-filtering"},
      {"version", 1},
      {"source",
       {{"heights", source.heights},
        {"channel", source.channel},
        {"size", {source.width, source.height}},
        {"texel_size", source.texel_size},
        {"height_scale", source.height_scale},
        {"edge", source.edge}}},
      {"options",
       {{"alphas", o.alphas},
        {"levels", r.levels},
        {"footprints_per_level", o.footprints},
        {"view_deg", o.view_deg},
        {"shift_pixels", o.random_shift ? json("random") : json(o.shift)},
        {"lookup", o.lookup == FilteringOptions::Lookup::kBox ? "box" : "trilinear"},
        {"sweep_max_deg", o.sweep_max_deg},
        {"sweep_step_deg", o.sweep_step_deg},
        {"seed", o.seed}}},
      {"compared_against",
       "the unfiltered footprint: the mean over every finest texel it covers of the base GGX "
       "lobe shaded with that texel's bumped normal (plane, distant light, orthographic view, "
       "Fresnel 1, no diffuse)"},
      {"units",
       {{"energy_ratio", "filtered / reference sum of the highlight profile, dimensionless"},
        {"width_ratio",
         "filtered / reference interquartile width of the profile over light angle, geometric "
         "mean of the x-z and y-z sweeps, dimensionless"},
        {"profile_error", "||filtered - reference||_2 / ||reference||_2, dimensionless"},
        {"interval", "95 % percentile bootstrap of the mean over footprints (2000 resamples)"}}},
      {"findings", filtering_findings(r)},
      {"summary", summary},
      {"claim", claim},
      {"cells", cells}}
      .dump(2);
}

std::string filtering_csv(const FilteringResult& r) {
  std::string csv =
      "filter,alpha,level,texels_per_pixel,footprints,energy_ratio,energy_low,energy_high,"
      "width_ratio,width_low,width_high,profile_error,error_low,error_high\n";
  const auto f = [](double x) { return std::isfinite(x) ? fmt::format("{}", x) : std::string(); };
  for (const FilteringCell& c : r.cells)
    csv += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", id(c.filter), c.alpha,
                       c.level, 1 << c.level, c.profile_error.n, f(c.energy_ratio.mean),
                       f(c.energy_ratio.interval.low), f(c.energy_ratio.interval.high),
                       f(c.width_ratio.mean), f(c.width_ratio.interval.low),
                       f(c.width_ratio.interval.high), f(c.profile_error.mean),
                       f(c.profile_error.interval.low), f(c.profile_error.interval.high));
  return csv;
}

}  // namespace penumbra
