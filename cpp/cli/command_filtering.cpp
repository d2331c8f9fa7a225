// `penumbra filtering`: the bump-filtering experiment on a height map
// (analysis/filtering.h), with its CSV, JSON and plots.
#include <chrono>
#include <filesystem>

#include <fmt/format.h>

#include "analysis/filtering.h"
#include "cli/command.h"
#include "core/roughness_filter.h"
#include "image/bump_maps.h"
#include "image/image_io.h"
#include "study/figures.h"

namespace penumbra {

namespace fs = std::filesystem;

namespace {

struct FilteringArgs {
  MapArgs map;  // heights, output folder, channel, texel size, scale, edge
  std::vector<double> alphas;
  std::vector<std::string> filters;
  int max_level = 6, footprints = 32;
  double view_deg = 0.0, sweep_step_deg = 0.5;
  std::string shift = "0";  // pixels in [0, 1), or "random"
  std::string lookup = "box";
};

// "random", or a number of pixels in [0, 1).
void set_shift(const std::string& text, FilteringOptions& o) {
  if (text == "random") {
    o.random_shift = true;
    return;
  }
  std::size_t used = 0;
  double shift = -1.0;
  try {
    shift = std::stod(text, &used);
  } catch (const std::exception&) {
  }
  if (used != text.size() || !(shift >= 0.0 && shift < 1.0))
    throw UsageError(fmt::format(
        "--shift: expected a number of pixels in [0, 1) or \"random\", got \"{}\"", text));
  o.shift = shift;
}

FilteringOptions filtering_options(const FilteringArgs& a, const Parallelism& parallelism) {
  FilteringOptions o;
  if (!a.alphas.empty()) o.alphas = a.alphas;
  for (const std::string& id : a.filters) {
    const auto f = roughness_filter_from_id(id);
    if (!f)
      throw UsageError(
          fmt::format("--filter: unknown roughness filter \"{}\" (see penumbra methods)", id));
    if (!is_measurable(*f))
      throw UsageError(fmt::format(
          "--filter: {} has no normalised BRDF in its source, so it cannot be measured", id));
    o.filters.push_back(*f);
  }
  for (double alpha : o.alphas)
    if (!(alpha > 0.0 && alpha <= 1.0))
      throw UsageError(fmt::format("--alpha: expected a GGX alpha in (0, 1], got {}", alpha));
  o.max_level = a.max_level;
  o.footprints = a.footprints;
  o.view_deg = a.view_deg;
  o.sweep_step_deg = a.sweep_step_deg;
  set_shift(a.shift, o);
  o.lookup = a.lookup == "trilinear" ? FilteringOptions::Lookup::kTrilinear
                                     : FilteringOptions::Lookup::kBox;
  // Each footprint is a task of one thread.
  o.jobs = parallelism.renders;
  return o;
}

int filtering(const FilteringArgs& a, const CommandContext& c) {
  const MapEdge edge = check_map_args(a.map);
  const FilteringOptions options = filtering_options(a, c.parallelism);
  const HeightMap map = read_height_map(a.map.heights, a.map.channel);
  const double texel_size = a.map.texel_size > 0.0 ? a.map.texel_size : 1.0 / map.width;
  check_map_slopes(map, a.map.heights, texel_size, a.map.height_scale);
  std::error_code ec;
  fs::create_directories(a.map.output, ec);
  check_writable((fs::path(a.map.output) / "filtering.json").string());
  const std::vector<PyramidLevel> pyramid = build_bump_pyramid(offsets_from_heights(
      map.heights, map.width, map.height, texel_size, a.map.height_scale, edge));
  const auto start = std::chrono::steady_clock::now();
  std::size_t reported = 0;
  const FilteringResult result =
      run_filtering_experiment(pyramid, options, [&](std::size_t done, std::size_t total) {
        if (a.map.quiet || done * 10 / total == reported) return;
        reported = done * 10 / total;
        c.err << fmt::format("filtering: {}/{} footprints measured\n", done, total);
      });
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const FilteringSource source{a.map.heights, map.channel,        map.width, map.height,
                               texel_size,    a.map.height_scale, a.map.edge};
  write_text_file((fs::path(a.map.output) / "filtering.csv").string(), filtering_csv(result));
  const std::string json_path = (fs::path(a.map.output) / "filtering.json").string();
  write_text_file(json_path, filtering_json(result, options, source) + "\n");
  run_plot_script(
      {"filtering", fs::absolute(json_path).string(), fs::absolute(a.map.output).string()},
      (fs::path(a.map.output) / "filtering.log").string());
  if (a.map.quiet) return kExitOk;
  c.out << fmt::format("{} footprints over {} levels, {} filters x {} alphas, in {:.1f} s\n",
                       result.footprints, result.levels, result.filters.size(),
                       options.alphas.size(), seconds);
  for (const std::string& line : filtering_findings(result)) c.out << line << "\n";
  c.out << fmt::format(
      "wrote {0}/filtering.json, {0}/filtering.csv and {0}/filtering-*.{{png,svg,pdf}}\n",
      a.map.output);
  return kExitOk;
}

void add_experiment_options(CLI::App* cmd, FilteringArgs& a) {
  cmd->add_option("--alpha", a.alphas,
                  "base GGX alpha (repeatable; default 0.01 0.05 0.1 0.2 0.4 0.8)");
  cmd->add_option("--filter", a.filters,
                  "roughness filter id (repeatable; default: every measurable one)");
  cmd->add_option("--max-level", a.max_level,
                  "coarsest level measured (2^level texels per pixel side)")
      ->check(CLI::Range(0, 16))
      ->capture_default_str();
  cmd->add_option("--footprints", a.footprints, "footprints per level")
      ->check(CLI::Range(2, 100000))
      ->capture_default_str();
  cmd->add_option("--view", a.view_deg, "view zenith angle, degrees")
      ->check(CLI::Range(0.0, 80.0))
      ->capture_default_str();
  cmd->add_option("--sweep-step", a.sweep_step_deg, "light sweep step, degrees")
      ->check(CLI::Range(0.05, 10.0))
      ->capture_default_str();
  cmd->add_option("--shift", a.shift,
                  "pixel grid offset from the texel grid, pixels, [0, 1) (0: aligned), or "
                  "random (each footprint its own, from the seed)")
      ->capture_default_str();
  cmd->add_option("--lookup", a.lookup,
                  "what the filters read: box (the footprint's exact moments) or trilinear "
                  "(the pyramid's mip-map lookup)")
      ->check(CLI::IsMember({"box", "trilinear"}))
      ->capture_default_str();
}

}  // namespace

Command add_filtering_command(CLI::App& app, SharedOptions& shared) {
  auto a = std::make_shared<FilteringArgs>();
  CLI::App* cmd = app.add_subcommand(
      "filtering",
      "the bump-filtering experiment (RTG Fig. 12-6) on a height map: each roughness "
      "filter against the unfiltered footprint, 1 to 64 texels per pixel");
  add_map_options(cmd, a->map);
  add_experiment_options(cmd, *a);
  add_jobs_option(cmd, shared)->check(CLI::NonNegativeNumber);
  cmd->add_flag("-q,--quiet", a->map.quiet, "print nothing on success");
  return {cmd, [a](const CommandContext& c) { return filtering(*a, c); }};
}

}  // namespace penumbra
