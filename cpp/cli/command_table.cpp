// `penumbra table`: a finished study's ranking table, or its per-level table
// over one axis, as LaTeX (booktabs), Markdown or CSV, numbers with their
// intervals (harness/report.py table).
#include "cli/plot_command.h"

namespace penumbra {

namespace {

struct TableArgs {
  std::string folder, format, by, metric, output;
};

int table(const TableArgs& a, const CommandContext& c) {
  std::vector<std::string> arguments{"table", a.folder};
  forward_option(arguments, "--format", a.format);
  forward_option(arguments, "--by", a.by);
  forward_option(arguments, "--metric", a.metric);
  forward_option(arguments, "-o", a.output);
  return run_plot_command(arguments, c);
}

}  // namespace

Command add_table_command(CLI::App& app, SharedOptions&) {
  auto a = std::make_shared<TableArgs>();
  CLI::App* cmd = app.add_subcommand(
      "table", "a finished study's ranking or per-level table as LaTeX, Markdown or CSV");
  cmd->add_option("folder", a->folder, "study output folder (holds report.json)")->required();
  cmd->add_option("--format", a->format, "latex (booktabs), markdown or csv")
      ->required()
      ->check(CLI::IsMember({"latex", "markdown", "csv"}));
  cmd->add_option("--by", a->by,
                  "an axis (pointer or name): methods x its levels, each cell the mean with its "
                  "interval and the rank group at that level");
  cmd->add_option("--metric", a->metric,
                  "the quantity (default: combined_relative_error, the ranking metric)");
  cmd->add_option("-o,--output", a->output, "write the table to this file (default: stdout)");
  return {cmd, [a](const CommandContext& c) { return table(*a, c); }};
}

}  // namespace penumbra
