#include "cli/cli.h"

#include <memory>
#include <optional>

#include <fmt/format.h>
#include <tbb/global_control.h>
#include <CLI/CLI.hpp>

#include "cli/command.h"
#include "cli/stop_signals.h"
#include "image/image_io.h"
#include "renderers/renderers.h"
#include "util/strict_json.h"
#include "util/version.h"

namespace penumbra {

namespace {

// The commands, in the order `penumbra --help` lists them (cli/command_*.cpp).
using AddCommand = Command (*)(CLI::App&, SharedOptions&);
constexpr AddCommand kCommands[] = {
    add_methods_command, add_renderers_command, add_render_command,    add_export_command,
    add_compare_command, add_calibrate_command, add_run_command,       add_run_batch_command,
    add_status_command,  add_report_command,    add_figure_command,    add_table_command,
    add_fit_command,     add_contour_command,   add_bench_command,     add_pyramid_command,
    add_bake_command,    add_mesh_command,      add_filtering_command, add_exit_codes_command};

// "penumbra rendr": name the unknown subcommand and list the real ones
// (CLI11 only says the argument was not expected).
std::optional<std::string> unknown_subcommand(CLI::App& app, int argc, const char* const* argv) {
  if (argc < 2 || argv[1][0] == '-') return std::nullopt;
  std::string names;
  for (const CLI::App* sub : app.get_subcommands({})) {
    if (sub->get_name() == argv[1]) return std::nullopt;
    names += (names.empty() ? "" : ", ") + sub->get_name();
  }
  return fmt::format("unknown subcommand \"{}\" (expected one of: {})", printable(argv[1], 60),
                     names);
}

// The app with its global options and every command; `footer` (the exit
// statuses) ends every --help.
std::vector<Command> declare_commands(CLI::App& app, SharedOptions& shared,
                                      const std::string& footer) {
  app.require_subcommand(1);
  app.set_version_flag("--version", kPenumbraVersion);
  app.footer(footer);
  // Global options (--threads) are accepted after the subcommand too.
  app.fallthrough();
  app.add_option("--threads", shared.threads,
                 "worker threads in all (default: all cores); a command's --jobs renders share "
                 "them")
      ->check(CLI::Range(1, 1024));
  std::vector<Command> commands;
  for (AddCommand add : kCommands) commands.push_back(add(app, shared));
  for (const Command& command : commands) command.app->footer(footer);
  require_finite_numbers(app);
  return commands;
}

// Messages hold file names, which may hold newlines and escape sequences:
// printed as InputError prints them, one line. Long enough for any message.
constexpr std::size_t kMaxErrorChars = 4000;

// The exit status of the exception being handled, its message printed.
int exit_code_of_exception(std::ostream& err) {
  try {
    throw;
  } catch (const InputError& e) {
    err << "penumbra: error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const ExportError& e) {
    err << "penumbra: error: cannot export: " << printable(e.what(), kMaxErrorChars) << "\n";
    return kExitBadInput;
  } catch (const UsageError& e) {
    err << "penumbra: error: " << printable(e.what(), kMaxErrorChars) << " (see penumbra --help)\n";
    return kExitBadInput;
  } catch (const OutputError& e) {
    err << "penumbra: error: " << printable(e.what(), kMaxErrorChars) << "\n";
    return kExitBadInput;
  } catch (const RenderCancelled& e) {
    err << "penumbra: stopped: " << printable(e.what(), kMaxErrorChars) << "; nothing written\n";
    return StopSignals::exit_code();
  } catch (const std::exception& e) {  // RendererError among them
    err << "penumbra: failed: " << printable(e.what(), kMaxErrorChars) << "\n";
    return kExitFailure;
  }
}

// Runs the command that was parsed, under --threads.
int dispatch(const std::vector<Command>& commands, const SharedOptions& shared, std::ostream& out,
             std::ostream& err) {
  std::unique_ptr<tbb::global_control> limit;
  if (shared.threads > 0)
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                  shared.threads);
  const CommandContext context{out, err, resolve_parallelism(shared.jobs, shared.threads)};
  try {
    for (const Command& command : commands)
      if (*command.app) return command.run(context);
  } catch (...) {
    return exit_code_of_exception(err);
  }
  return kExitBadInput;
}

}  // namespace

int run_cli(int argc, const char* const* argv, std::ostream& out, std::ostream& err) {
  CLI::App app{"Penumbra: shadow-terminator laboratory (reference evaluator)", "penumbra"};
  SharedOptions shared;
  const std::vector<Command> commands = declare_commands(app, shared, exit_status_text());
  if (const auto unknown = unknown_subcommand(app, argc, argv)) {
    err << "penumbra: error: " << *unknown << " (see penumbra --help)\n";
    return kExitBadInput;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e, out, err);  // --help, --version
    err << "penumbra: error: " << printable(e.what(), kMaxErrorChars) << " (see penumbra --help)\n";
    return kExitBadInput;
  }
  return dispatch(commands, shared, out, err);
}

}  // namespace penumbra
