// `penumbra fit`: what is achievable on a finished study (study/fit.h).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include <fmt/format.h>

#include "analysis/factor_emit.h"
#include "cli/command.h"
#include "image/image_io.h"
#include "scene/factor_table_file.h"
#include "study/fit.h"

namespace penumbra {

namespace {

struct FitArgs {
  std::string folder, output;
  std::string inputs = kFitInputSets[0];
  std::vector<std::string> steps;  // AXIS=DEGREES (with_steps)
  int resamples = 2000;
  std::vector<double> smoothness = FitOptions().smoothness;
  std::vector<std::string> emit;  // languages (factor_emit.h)
  std::string table;              // emit this table.json without fitting
};

EmitLanguage emit_language(const std::string& id) {
  for (const auto& [name, value] : kEmitLanguageNames)
    if (id == name) return value;
  throw UsageError("--emit: expected c, glsl or osl, got " + id);
}

std::string provenance(const std::string& source, const FactorTable& table) {
  return fmt::format("Fitted by penumbra fit ({}), table digest {}.", source,
                     factor_table_digest(table));
}

// --table FILE --emit LANG: the function of a table already fitted, on stdout.
int emit_only(const FitArgs& a, const CommandContext& c) {
  if (!a.folder.empty() || !a.output.empty())
    throw UsageError("--table emits a fitted table without fitting: give no folder and no -o");
  if (a.emit.size() != 1) throw UsageError("--table needs exactly one --emit c|glsl|osl");
  const auto table = load_factor_table(a.table);
  c.out << emit_factor_table(*table, emit_language(a.emit[0]), provenance(a.table, *table));
  return kExitOk;
}

// A refitted constant's error held out by `unit` (family, scene) against its
// published value, or why there is none.
std::string held_out_line(const FittedConstant& c, const std::string& unit) {
  if (!c.held_out_defined)
    return fmt::format("E {:.2f} % at {}; no held-out error: the variants are of one {}",
                       100 * c.at_published.value, c.reference, unit);
  const PairedError& d = c.held_out_minus_published;
  // An interval that excludes 0 must not print an end of 0.00 (it would read
  // as a tie): more decimals, up to 5, until its nearer end shows.
  const double low = 100 * d.difference.interval.low, high = 100 * d.difference.interval.high;
  int digits = 2;
  while (!d.tie && digits < 5 &&
         std::min(std::abs(low), std::abs(high)) < 0.5 * std::pow(10.0, -digits))
    ++digits;
  return fmt::format(
      "E {:.2f} % held out by {} against {:.2f} % at {}: {:.{}f} [{:.{}f}, {:.{}f}] percentage "
      "points{}",
      100 * c.held_out.value, unit, 100 * c.at_published.value, c.reference,
      100 * d.difference.value, digits, low, digits, high, digits, d.tie ? ", a tie" : "");
}

// A line per refitted constant, and one per method for the errors of its
// constants (fitted together).
void print_constants(const FitResult& r, std::ostream& out) {
  if (!r.constants.empty())
    out << "  refitted constants (dimensionless; 95 % bootstrap intervals):\n";
  for (std::size_t k = 0; k < r.constants.size(); ++k) {
    const FittedConstant& c = r.constants[k];
    out << fmt::format("    {:<24} {:<4} {:.4g} [{:.4g}, {:.4g}] against {} {:.4g}{}\n", c.method,
                       c.constant.substr(0, c.constant.find(' ')), c.fitted, c.interval.low,
                       c.interval.high, c.reference, c.published,
                       c.at_bound.empty() ? "" : " (at its range's end)");
    if (k + 1 < r.constants.size() && r.constants[k + 1].method == c.method) continue;
    out << "      " << held_out_line(c, "family") << "\n";
  }
}

// A line per low-poly offset's refitted parameter and one for its errors.
void print_offset_parameters(const FitResult& r, std::ostream& out) {
  if (r.offset_parameters.empty()) return;
  out << "  low-poly offsets' parameters, refitted among the rendered values (image RMSE against "
         "the analytic surface, % of albedo*E/pi; 95 % bootstrap intervals):\n";
  for (const FittedOffsetParameter& f : r.offset_parameters) {
    const FittedConstant& c = f.fit;
    out << fmt::format("    {:<24} {} {:.4g} [{:.4g}, {:.4g}] against {} {:.4g}{}; {} variants\n",
                       c.method, c.constant, c.fitted, c.interval.low, c.interval.high, c.reference,
                       c.published, c.at_bound.empty() ? "" : " (at the values' end)", f.variants);
    out << "      " << held_out_line(c, "scene") << "\n";
  }
}

void print_image_floors(const ImageFloors& f, std::ostream& out) {
  if (f.methods.empty() && !std::isfinite(f.none.value)) return;
  out << fmt::format(
      "  image RMSE, % of albedo*E/pi: raw bump {:.2f} [{:.2f}, {:.2f}]; each variant's own "
      "floor {:.2f} [{:.2f}, {:.2f}]\n",
      100 * f.none.value, 100 * f.none.interval.low, 100 * f.none.interval.high,
      100 * f.floor.value, 100 * f.floor.interval.low, 100 * f.floor.interval.high);
  for (const MethodShare& s : f.methods)
    out << fmt::format(
        "    {:<26} {:.2f} % [{:.2f}, {:.2f}]   share of the floors' gain {:.0f} % [{:.0f}, "
        "{:.0f}]\n",
        s.method, 100 * s.error.value, 100 * s.error.interval.low, 100 * s.error.interval.high,
        100 * s.share.value, 100 * s.share.interval.low, 100 * s.share.interval.high);
}

void print_summary(const FitResult& r, std::ostream& out) {
  const auto pct = [](const PooledError& e) {
    return fmt::format("{:.2f} % [{:.2f}, {:.2f}]", 100 * e.value, 100 * e.interval.low,
                       100 * e.interval.high);
  };
  out << fmt::format(
      "study {}: {} variants fitted ({} skipped, {} with a truth that did not converge left out, "
      "{} re-traced differ from the cache); terminator RMSE pooled over variants, % of "
      "albedo*E/pi, 95 % bootstrap intervals over variants\n",
      r.study, r.variants.size(), r.skipped, r.unconverged.size(), r.retraced_different);
  out << fmt::format("  raw bump {}; floor of any {} factor {}\n", pct(r.study_floor.none),
                     grid_inputs(r.grid), pct(r.study_floor.floor));
  for (const NestedFloor& n : r.nested) {
    const PairedError& d = n.gain;
    out << fmt::format(
        "    of a {} factor on the same grid {}; the added inputs lower it by {:.2f} [{:.2f}, "
        "{:.2f}] percentage points, paired{}\n",
        n.inputs, pct(n.floor.floor), -100 * d.difference.value, -100 * d.difference.interval.high,
        -100 * d.difference.interval.low, d.tie ? ": a tie" : "");
  }
  out << fmt::format("  fitted table, each scene family held out: {}\n", pct(r.held_out_pooled));
  if (!r.held_out.empty() && !r.best_method.empty()) {
    const PairedError& d = r.held_out_minus_best;
    out << fmt::format(
        "    minus the best shipped method, {}, paired: {:.2f} [{:.2f}, {:.2f}] "
        "percentage points: {}\n",
        r.best_method, 100 * d.difference.value, 100 * d.difference.interval.low,
        100 * d.difference.interval.high,
        d.tie                    ? "a tie"
        : d.difference.value < 0 ? "the table is lower"
                                 : "the method is lower");
  }
  for (const MethodShare& s : r.shares)
    out << fmt::format("  {:<26} {}   share of the achievable {:.0f} % [{:.0f}, {:.0f}]\n",
                       s.method, pct(s.error), 100 * s.share.value, 100 * s.share.interval.low,
                       100 * s.share.interval.high);
  print_image_floors(r.image, out);
  print_constants(r, out);
  print_offset_parameters(r, out);
}

int fit_into(const FitArgs& a, const CommandContext& c) {
  for (const std::string& id : a.emit) emit_language(id);
  FitOptions options;
  options.folder = a.folder;
  options.resamples = a.resamples;
  options.smoothness = a.smoothness;
  try {
    options.grid = with_steps(fit_grid(a.inputs), a.steps);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--step: ") + e.what());
  }
  options.jobs = c.parallelism.threads();
  const auto start = std::chrono::steady_clock::now();
  options.progress = [&c, start](const std::string& line) {
    const std::chrono::duration<double> s = std::chrono::steady_clock::now() - start;
    c.err << fmt::format("penumbra fit: [{:.1f} s] {}\n", s.count(), line) << std::flush;
  };
  const FitResult result = fit_study(options);
  write_fit(result, a.output);
  print_summary(result, c.out);
  c.out << fmt::format("wrote {0}/fit.json, {0}/fit.csv and {0}/table.json in {1:.1f} s\n",
                       a.output, result.seconds);
  for (const std::string& id : a.emit) {
    const EmitLanguage language = emit_language(id);
    const std::string file =
        (std::filesystem::path(a.output) / ("fitted" + std::string(emit_extension(language))))
            .string();
    write_text_file(file, emit_factor_table(result.table, language,
                                            provenance("study " + result.study, result.table)));
    c.out << fmt::format("wrote {}: penumbra_fitted_g, the table as {}\n", file, id);
  }
  return kExitOk;
}

int fit(const FitArgs& a, const CommandContext& c) {
  if (!a.table.empty()) return emit_only(a, c);
  if (a.folder.empty())
    throw UsageError("fit needs a finished study's folder (or --table FILE --emit LANG)");
  FitArgs args = a;
  // Beside the study, where `penumbra report` finds it for the report's
  // "What is achievable" section.
  if (args.output.empty()) args.output = (std::filesystem::path(a.folder) / "fit").string();
  return fit_into(args, c);
}

}  // namespace

Command add_fit_command(CLI::App& app, SharedOptions&) {
  auto a = std::make_shared<FitArgs>();
  CLI::App* cmd = app.add_subcommand(
      "fit",
      "what any terminator factor of the light and deviation angles (or more, --inputs) could "
      "achieve on a finished study, each method's share of it, and a table fitted without the "
      "family it is measured on");
  cmd->add_option("folder", a->folder, "finished study output folder (report.json, cache/)");
  cmd->add_option("-o,--output", a->output,
                  "folder for fit.json, fit.csv and table.json (default: FOLDER/fit, where the "
                  "study's report finds it)");
  cmd->add_option("--inputs", a->inputs,
                  "the angles the factor may depend on, each set on its own grid "
                  "(docs/achievable.md): light,deviation (Conty Estevez's and Deshmukh's), "
                  "light,deviation,shading (Chiang's), light,deviation,shading,view")
      ->check(CLI::Validator(
          [](std::string& inputs) {
            try {
              fit_grid(inputs);
              return std::string();
            } catch (const std::invalid_argument& e) {
              return std::string(e.what());
            }
          },
          "SET"))
      ->capture_default_str();
  cmd->add_option("--step", a->steps,
                  "resize the cells of an axis of the input set's grid, AXIS=DEGREES "
                  "(comma-separated; for example shading=6,view=15); the step must divide the "
                  "axis' range")
      ->delimiter(',');
  cmd->add_option("--emit", a->emit,
                  "also write the fitted table as a function a renderer can paste: "
                  "OUT/fitted.c, .glsl or .osl (repeatable)")
      ->check(CLI::IsMember({"c", "glsl", "osl"}));
  cmd->add_option("--table", a->table,
                  "print the function of this table.json (with one --emit) instead of fitting")
      ->check(CLI::ExistingFile);
  cmd->add_option("--smoothness", a->smoothness,
                  "candidate weights of the fitted table's smoothness prior, chosen among by "
                  "leave-one-family-out (comma-separated, each in [1e-6, 1e6]); fit.json says "
                  "which won: widen the list when it is an end")
      ->delimiter(',')
      ->check(CLI::Range(1e-6, 1e6))
      ->capture_default_str();
  cmd->add_option("--resamples", a->resamples, "bootstrap resamples over variants")
      ->check(CLI::Range(100, 100000))
      ->capture_default_str();
  return {cmd, [a](const CommandContext& c) { return fit(*a, c); }};
}

}  // namespace penumbra
