// One subcommand of `penumbra`: each cli/command_<name>.cpp declares its
// options on a CLI11 subcommand and returns the body that runs once the
// command line is parsed. cli.cpp sets up the app, the global options,
// dispatches and maps exceptions to exit codes (cli/exit_codes.h).
#pragma once

#include <functional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli/exit_codes.h"
#include "core/bump_pyramid.h"
#include "renderers/registry.h"
#include "scene/scene.h"
#include "scene/scene_json.h"
#include "util/parallel.h"

namespace penumbra {

// A command-line value that parses but makes no sense (exit 2).
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What a command's body runs with.
struct CommandContext {
  std::ostream& out;
  std::ostream& err;
  Parallelism parallelism;  // resolved from --jobs and --threads (util/parallel.h)
};

struct Command {
  CLI::App* app;
  std::function<int(const CommandContext&)> run;
};

// Options that run_cli resolves for every command: the global --threads and
// the --jobs of the commands that have one (add_jobs_option).
struct SharedOptions {
  int threads = 0;
  int jobs = 0;
};

// The check every floating-point option gets (cli.cpp adds it to each one):
// CLI11 reads "nan" and "inf" as numbers, and NaN passes every range check
// (each comparison with it is false), so a NaN would stand for "default"
// or make a bound unfailable.
const CLI::Validator& finite_number();
// Adds finite_number() to every floating-point option of `app` and of its
// subcommands, so that no command can forget it.
void require_finite_numbers(CLI::App& app);

// --jobs, with the one meaning it has in every command (util/parallel.h).
CLI::Option* add_jobs_option(CLI::App* cmd, SharedOptions& shared);

// The commands, in the order `penumbra --help` lists them.
Command add_methods_command(CLI::App& app, SharedOptions& shared);
Command add_renderers_command(CLI::App& app, SharedOptions& shared);
Command add_render_command(CLI::App& app, SharedOptions& shared);
Command add_export_command(CLI::App& app, SharedOptions& shared);
Command add_compare_command(CLI::App& app, SharedOptions& shared);
Command add_calibrate_command(CLI::App& app, SharedOptions& shared);
Command add_run_command(CLI::App& app, SharedOptions& shared);
Command add_run_batch_command(CLI::App& app, SharedOptions& shared);
Command add_status_command(CLI::App& app, SharedOptions& shared);
Command add_report_command(CLI::App& app, SharedOptions& shared);
Command add_figure_command(CLI::App& app, SharedOptions& shared);
Command add_table_command(CLI::App& app, SharedOptions& shared);
Command add_fit_command(CLI::App& app, SharedOptions& shared);
Command add_contour_command(CLI::App& app, SharedOptions& shared);
Command add_bench_command(CLI::App& app, SharedOptions& shared);
Command add_pyramid_command(CLI::App& app, SharedOptions& shared);
Command add_bake_command(CLI::App& app, SharedOptions& shared);
Command add_filtering_command(CLI::App& app, SharedOptions& shared);
Command add_exit_codes_command(CLI::App& app, SharedOptions& shared);
Command add_mesh_command(CLI::App& app, SharedOptions& shared);

// Helpers that several commands share (cli/command_options.cpp).

// Scene shortcuts shared by render and export: each is --set on one pointer.
struct SceneArgs {
  std::string method, offset, representation;
  int segments = 0, width = 0, height = 0, spp = 0;
  std::vector<std::string> sets;
};
void add_scene_options(CLI::App* cmd, SceneArgs& a);

// A scene file with the shortcuts and --set values applied; `origin` names
// it in messages ("FILE (after --set)" when anything was applied).
struct LoadedScene {
  nlohmann::json document;
  std::string origin;
  Scene scene;
};
LoadedScene read_scene(const std::string& path, const SceneArgs& a);
// The same for a document already read from `path` (the Python module's
// scenes as dicts; `path` resolves relative map files and names the origin).
LoadedScene read_scene_document(nlohmann::json document, const std::string& path,
                                const SceneArgs& a);

// The EXR attributes `penumbra render` writes with a render of `loaded`.
std::vector<std::pair<std::string, std::string>> render_attributes(const LoadedScene& loaded,
                                                                   RendererKind renderer);

// `penumbra methods --json`: every method, adjustment, offset and filter.
nlohmann::json methods_json();

// Refuses, before anything runs, a method or offset the renderer does not
// ship (the exporters refuse them too, but only after the mesh is built).
void check_offered(RendererKind renderer, const Scene& scene);

// `penumbra export`'s files for `scene` in the folder `output` (made if
// missing): what the exporter prints of them. UsageError for a renderer
// with nothing to export, OutputError for a folder that takes no files.
std::string export_scene_files(RendererKind renderer, const Scene& scene,
                               const std::string& output);

// The output formats, from the extension: only OpenEXR holds float radiance
// and the analysis channels; the preview is a PNG. `why` says so in the error.
void check_extension(const std::string& path, const char* extension, const char* option,
                     const char* why = "");

// A height map and how to read it: shared by `pyramid` and `filtering`.
struct MapArgs {
  std::string heights, output, channel;
  double texel_size = 0.0;  // 0: 1 / width (the map spans one scene unit)
  double height_scale = 1.0;
  std::string edge = "wrap";
  bool quiet = false;
};
void add_map_options(CLI::App* cmd, MapArgs& a);
// The edge mode, after checking the map options CLI11 cannot.
MapEdge check_map_args(const MapArgs& a);

}  // namespace penumbra
