// `penumbra figure`: redraws one figure of a finished study from its
// report.json, with another method subset or order, axis or style, without
// rendering (harness/report.py figure; docs/report.md lists the kinds).
#include "cli/plot_command.h"

namespace penumbra {

namespace {

struct FigureArgs {
  std::string folder, kind, x, y, metric, methods, variant, scene, style, columns, output;
};

int figure(const FigureArgs& a, const CommandContext& c) {
  std::vector<std::string> arguments{"figure", a.folder};
  forward_option(arguments, "--kind", a.kind);
  forward_option(arguments, "--x", a.x);
  forward_option(arguments, "--y", a.y);
  forward_option(arguments, "--metric", a.metric);
  forward_option(arguments, "--methods", a.methods);
  forward_option(arguments, "--variant", a.variant);
  forward_option(arguments, "--scene", a.scene);
  forward_option(arguments, "--style", a.style);
  forward_option(arguments, "--columns", a.columns);
  forward_option(arguments, "-o", a.output);
  return run_plot_command(arguments, c);
}

}  // namespace

Command add_figure_command(CLI::App& app, SharedOptions&) {
  auto a = std::make_shared<FigureArgs>();
  CLI::App* cmd = app.add_subcommand(
      "figure",
      "redraw one figure of a finished study (report.json) for another method subset, "
      "axis or style, without rendering");
  cmd->add_option("folder", a->folder, "study output folder (holds report.json)")->required();
  cmd->add_option("--kind", a->kind,
                  "line: a metric against one axis's levels, a line per method with intervals; "
                  "profile: a variant's terminator profiles; ranking: the primary metric per "
                  "method with its interval; heatmap: a metric over two axes; grid: a variant's "
                  "images and differences; achievable-share, achievable-contour: from "
                  "FOLDER/fit/fit.json (penumbra fit), each method's share of the achievable "
                  "improvement and the floor's G* beside chiang2019, estevez2019 and the fitted "
                  "table")
      ->required()
      ->check(CLI::IsMember({"line", "profile", "ranking", "heatmap", "grid", "achievable-share",
                             "achievable-contour"}));
  cmd->add_option("--x", a->x, "the axis (its pointer, e.g. /height/amplitude, or its name)");
  cmd->add_option("--y", a->y, "heatmap: the second axis");
  cmd->add_option(
      "--metric", a->metric,
      "line and ranking: combined_relative_error (default), profile.rmse_terminator, "
      "view.rmse_grazing, profile.position_error_deg, image.rmse, image.ssim or image.flip; "
      "heatmap: any comparison metric");
  cmd->add_option("--methods", a->methods,
                  "comma-separated method labels in the order to draw, or all (default: none, the "
                  "study's figures.methods and the leading methods, at most 5)");
  cmd->add_option("--variant", a->variant, "profile and grid: the variant id (default: the first)");
  cmd->add_option("--scene", a->scene, "heatmap: one scene (default: all pooled)");
  cmd->add_option(
         "--style", a->style,
         "paper: 8-pt text, exactly 3.5 or 7 in wide, vector PDF; screen: the report's look")
      ->check(CLI::IsMember({"paper", "screen"}));
  cmd->add_option("--columns", a->columns, "paper style: 1 (3.5 in) or 2 (7 in, default)")
      ->check(CLI::IsMember({"1", "2"}));
  cmd->add_option("-o,--output", a->output, "the figure file: .pdf, .svg or .png")->required();
  return {cmd, [a](const CommandContext& c) { return figure(*a, c); }};
}

}  // namespace penumbra
