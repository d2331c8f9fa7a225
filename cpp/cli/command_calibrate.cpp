// `penumbra calibrate`: the calibration set rendered by all three renderers
// and compared (study/calibration.h).
#include <fmt/format.h>

#include "cli/command.h"
#include "study/calibration.h"
#include "util/data_files.h"

namespace penumbra {

namespace {

struct CalibrateArgs {
  CalibrationOptions options;
  bool quiet = false;
};

int calibrate(const CalibrateArgs& a, const CommandContext& c) {
  CalibrationOptions o = a.options;
  o.parallelism = c.parallelism;
  if (!a.quiet) o.log = [&](const std::string& line) { c.err << line << "\n" << std::flush; };
  const CalibrationResult result = run_calibration(o);
  write_calibration_reports(result, o.output_dir);
  c.out << calibration_table(result);
  c.out << fmt::format("wrote {0}/calibration.md, {0}/calibration.json, {0}/calibration.csv\n",
                       o.output_dir);
  if (!result.all_rendered()) {
    c.err << "penumbra: failed: some renders did not finish (see above and the logs in "
          << o.output_dir << "/renders)\n";
    return kExitFailure;
  }
  if (!result.all_pass()) {
    c.err << "penumbra: calibration bounds missed (FAIL rows above)\n";
    return kExitThreshold;
  }
  return kExitOk;
}

}  // namespace

Command add_calibrate_command(CLI::App& app, SharedOptions& shared) {
  auto a = std::make_shared<CalibrateArgs>();
  CalibrationOptions& o = a->options;
  o.scenes_dir = data_file("scenes/calibration");
  o.output_dir = "results/calibration";
  CLI::App* cmd = app.add_subcommand(
      "calibrate", "render the calibration set with all three renderers and compare them");
  cmd->add_option("-o,--output", o.output_dir, "output folder")->capture_default_str();
  cmd->add_option("--scenes", o.scenes_dir, "folder with cylinder.json and sphere.json")
      ->capture_default_str();
  add_jobs_option(cmd, shared)->check(CLI::Range(1, 256));
  cmd->add_option("--timeout", o.timeout_s, "seconds per external render")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--blender-spp", o.blender_spp, "Cycles samples per pixel")
      ->check(CLI::Range(1, 65536))
      ->capture_default_str();
  cmd->add_option("--set", o.sets, "override a value of both base scenes");
  cmd->add_flag("-q,--quiet", a->quiet, "no per-render lines");
  return {cmd, [a](const CommandContext& c) { return calibrate(*a, c); }};
}

}  // namespace penumbra
