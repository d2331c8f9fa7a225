// `penumbra report`: redraws a study folder's figures and report.html from
// its report.json (study/figures.h).
#include <filesystem>

#include <fmt/format.h>

#include "cli/command.h"
#include "study/figures.h"
#include "study/report_files.h"
#include "study/study.h"
#include "util/strict_json.h"

namespace penumbra {

namespace {

struct ReportArgs {
  std::string folder;
  bool self_contained = false;  // report.html embeds its images
};

int report(const ReportArgs& a, const CommandContext& c) {
  const std::filesystem::path report = std::filesystem::path(a.folder) / "report.json";
  if (!std::filesystem::is_regular_file(report))
    throw UsageError(fmt::format("{}: no such file (give a study output folder)", report.string()));
  // Strict and bounded: a damaged or hostile report is bad input, named here.
  read_report_json(report.string());
  const std::string html =
      draw_report(a.folder, a.self_contained, "", kFiguresTimeoutS, [&c](const std::string& line) {
        c.err << "penumbra report: " << line << "\n" << std::flush;
      });
  c.out << fmt::format("report: {}\n", html);
  return kExitOk;
}

}  // namespace

Command add_report_command(CLI::App& app, SharedOptions&) {
  auto a = std::make_shared<ReportArgs>();
  CLI::App* cmd = app.add_subcommand(
      "report", "redraw the figures and report.html of a study folder from its report.json");
  cmd->add_option("folder", a->folder, "study output folder (holds report.json)")->required();
  cmd->add_flag("--self-contained", a->self_contained,
                "report.html embeds every image (one file to mail; default: it links "
                "images/ and figures/ beside it)");
  return {cmd, [a](const CommandContext& c) { return report(*a, c); }};
}

}  // namespace penumbra
