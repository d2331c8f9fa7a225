// `penumbra pyramid`: a height map's bump and roughness pyramids, one EXR
// per level (image/bump_maps.h).
#include <chrono>
#include <cmath>

#include <fmt/format.h>

#include "cli/command.h"
#include "image/bump_maps.h"
#include "util/resource_usage.h"

namespace penumbra {

namespace {

double seconds_between(std::chrono::steady_clock::time_point from,
                       std::chrono::steady_clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

int pyramid(const MapArgs& a, std::ostream& out) {
  const MapEdge edge = check_map_args(a);
  const auto start = std::chrono::steady_clock::now();
  const HeightMap map = read_height_map(a.heights, a.channel);
  const double texel_size = a.texel_size > 0.0 ? a.texel_size : 1.0 / map.width;
  check_map_slopes(map, a.heights, texel_size, a.height_scale);
  const auto read = std::chrono::steady_clock::now();
  const std::vector<PyramidLevel> levels = build_bump_pyramid(
      offsets_from_heights(map.heights, map.width, map.height, texel_size, a.height_scale, edge));
  const auto built = std::chrono::steady_clock::now();
  write_pyramid(levels, {a.heights, map.channel, texel_size, a.height_scale, edge}, a.output);
  const auto written = std::chrono::steady_clock::now();
  if (a.quiet) return kExitOk;
  const PyramidLevel& top = levels.back();
  const Covariance2 k = top.covariance(0, 0);
  out << fmt::format(
      "{} (channel {}, {}x{} texels, texel {:.6g} scene units, heights x {:.6g}, edge {}): "
      "{} levels in {}\n",
      a.heights, map.channel, map.width, map.height, texel_size, a.height_scale, a.edge,
      levels.size(), a.output);
  out << fmt::format(
      "whole map (level {}): mean offset ({:.6g}, {:.6g}), slope standard deviations "
      "sqrt(K_uu) {:.6g}, sqrt(K_vv) {:.6g}, lambda1 {:.6g} (slopes, dimensionless); "
      "mean normal length {:.6f}\n",
      levels.size() - 1, top.f_u[0], top.f_v[0], std::sqrt(k.a), std::sqrt(k.c),
      isotropic_roughness(k), length(top.mean_normal(0, 0)));
  out << fmt::format(
      "read {:.3f} s, built {:.3f} s (1 thread), written {:.3f} s; peak RSS {:.0f} MiB\n",
      seconds_between(start, read), seconds_between(read, built), seconds_between(built, written),
      peak_rss_mib());
  return kExitOk;
}

}  // namespace

Command add_pyramid_command(CLI::App& app, SharedOptions&) {
  auto a = std::make_shared<MapArgs>();
  CLI::App* cmd =
      app.add_subcommand("pyramid",
                         "a height map's bump (offset) and roughness pyramids, one EXR per level "
                         "(Schilling; see README)");
  add_map_options(cmd, *a);
  cmd->add_flag("-q,--quiet", a->quiet, "print nothing on success");
  return {cmd, [a](const CommandContext& c) { return pyramid(*a, c.out); }};
}

}  // namespace penumbra
