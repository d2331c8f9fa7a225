// `penumbra status`: what a study folder's Slurm submissions have done so far.
#include <filesystem>

#include <fmt/format.h>

#include "cli/command.h"
#include "study/slurm.h"
#include "util/strict_json.h"

namespace penumbra {

namespace {

int status(const std::string& folder, std::ostream& out) {
  if (!std::filesystem::is_directory(folder))
    throw InputError(folder, "", "expected a study output folder");
  const SlurmStatus status = slurm_status(folder);
  if (status.batches.empty()) out << fmt::format("{}: no Slurm submissions\n", folder);
  for (const SlurmStatus::Batch& b : status.batches)
    out << fmt::format(
        "array job {} (report job {}): {} renders: {} done, {} failed, {} not yet{}\n",
        b.array_job.empty() ? "?" : b.array_job, b.report_job.empty() ? "?" : b.report_job,
        b.renders, b.done, b.failed, b.renders - b.done - b.failed,
        b.chains > 0 ? fmt::format("; and {} ground-truth convergence chains (their renders are "
                                   "counted by the report job)",
                                   b.chains)
                     : "");
  out << (status.report_written ? fmt::format("report: {}/report.json\n", folder)
                                : std::string("report: not written yet\n"));
  return kExitOk;
}

}  // namespace

Command add_status_command(CLI::App& app, SharedOptions&) {
  auto folder = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand("status", "progress of a study folder's Slurm submissions");
  cmd->add_option("folder", *folder, "study output folder")->required();
  return {cmd, [folder](const CommandContext& c) { return status(*folder, c.out); }};
}

}  // namespace penumbra
