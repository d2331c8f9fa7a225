// The subcommands of `penumbra`, as functions of parsed arguments: cli.cpp
// declares the options (CLI11) and maps exceptions to exit codes.
#pragma once

#include <signal.h>

#include <array>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli/cli.h"
#include "renderers/renderers.h"
#include "study/calibration.h"
#include "study/slurm.h"

namespace penumbra {

// A command-line value that parses but makes no sense (exit 2).
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// While alive, SIGINT, SIGTERM and SIGHUP stop the command cleanly: running
// renderers are ended, nothing half-written is left, and the exit status is
// 128 + the signal (130 for Ctrl-C).
class StopSignals {
 public:
  StopSignals();
  ~StopSignals();
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;
  static int exit_code();

 private:
  std::array<struct sigaction, 3> previous_{};
};

// Scene shortcuts shared by render and export: each is --set on one pointer.
struct SceneArgs {
  std::string method, offset, representation;
  int segments = 0, width = 0, height = 0, spp = 0;
  std::vector<std::string> sets;
};

struct RenderArgs {
  std::string scene;
  std::string output;
  std::string preview;
  SceneArgs scene_args;
  bool quiet = false;
  std::string renderer = "evaluator";
  double timeout = 600.0;
  double max_memory_gib = kDefaultMaxMemoryBytes / kGiB;
};

struct CompareArgs {
  std::string reference, test;
  std::string difference;  // -o: the difference image
  bool json = false;
  double scale = 0.0;
  double max_rmse = -1.0;
  // The coverage of an image without an A channel (another renderer's PNG):
  // a mask image, or the lit region, radiance >= threshold * albedo*E/pi.
  std::string mask;
  std::optional<double> threshold;
  bool no_mask = false;     // image metrics over every pixel, the usual SSIM
  bool same_scene = false;  // different penumbra:scene geometry: exit 2, not a warning
};

struct ExportArgs {
  std::string to;
  std::string scene;
  std::string output;
  SceneArgs scene_args;
};

struct RunArgs {
  std::string study, output;
  int jobs = 0;
  double timeout = 600.0;
  long max_renders = -1;
  bool no_figures = false, quiet = false, dry_run = false;
  bool self_contained = false;  // report.html embeds its images
  double max_memory_gib = kDefaultMaxMemoryBytes / kGiB;
  std::string executor = "local";  // local or slurm
  SlurmOptions slurm;              // --partition, --array-limit, ... (chain: --slurm-chain)
};

// penumbra pyramid: a height map's bump and roughness pyramids.
struct PyramidArgs {
  std::string heights, output, channel;
  double texel_size = 0.0;  // 0: 1 / width (the map spans one scene unit)
  double height_scale = 1.0;
  std::string edge = "wrap";
  bool quiet = false;
};

// penumbra filtering: the bump-filtering experiment on a height map.
struct FilteringArgs {
  PyramidArgs map;  // heights, output folder, channel, texel size, scale, edge
  std::vector<double> alphas;
  std::vector<std::string> filters;
  int max_level = 6, footprints = 32, jobs = 0;
  double view_deg = 0.0, sweep_step_deg = 0.5;
  std::string shift = "0";  // pixels in [0, 1), or "random"
  std::string lookup = "box";
};

// penumbra bake: a scene's analytic height function as a height map.
struct BakeArgs {
  std::string scene, output;
  std::vector<std::string> sets;
  int size = 1024;
  double extent = 1.0;
  std::string on = "plane";     // "plane": z = 0 over [0, extent)^2; "shape": the shape's (u, v)
  std::string kind = "height";  // "height" or "normal" (shape only)
};

struct RunBatchArgs {
  std::string batch;
  int task = -1;  // default: SLURM_ARRAY_TASK_ID
};

int command_methods(bool as_json, std::ostream& out);
// The exit statuses (cli/exit_codes.h), as a table or a JSON array.
int command_exit_codes(bool as_json, std::ostream& out);
int command_renderers(bool as_json, std::ostream& out);
int command_render(const RenderArgs& a, std::ostream& out, std::ostream& err);
int command_export(const ExportArgs& a, std::ostream& out);
int command_compare(const CompareArgs& a, std::ostream& out, std::ostream& err);
int command_calibrate(const CalibrationOptions& options, bool quiet, std::ostream& out,
                      std::ostream& err);
int command_run(const RunArgs& a, std::ostream& out, std::ostream& err);
// An array task of a Slurm study (study/slurm.h).
int command_run_batch(const RunBatchArgs& a, std::ostream& out, std::ostream& err);
// What a study folder's Slurm submissions have done so far.
int command_status(const std::string& folder, std::ostream& out);
// Redraws the figures and report.html of a study folder from its report.json (linked images, or
// embedded with self_contained).
int command_report(const std::string& folder, bool self_contained, std::ostream& out,
                   std::ostream& err);
int command_contour(const std::vector<std::string>& ids, double step, const std::string& output,
                    std::ostream& out);
// The throughput table; with povray_rounds > 0 instead the evaluator
// against POV-Ray on the same scene, paired, that many rounds.
int command_bench(int size, int spp, int povray_rounds, std::ostream& out);
int command_pyramid(const PyramidArgs& a, std::ostream& out);
int command_bake(const BakeArgs& a, std::ostream& out);
int command_filtering(const FilteringArgs& a, std::ostream& out, std::ostream& err);

}  // namespace penumbra
