// `penumbra fit`: what is achievable on a finished study (study/fit.h).
#include <chrono>
#include <filesystem>

#include <fmt/format.h>

#include "cli/command.h"
#include "study/fit.h"

namespace penumbra {

namespace {

struct FitArgs {
  std::string folder, output;
  int resamples = 2000;
};

void print_summary(const FitResult& r, std::ostream& out) {
  const auto pct = [](const PooledError& e) {
    return fmt::format("{:.2f} % [{:.2f}, {:.2f}]", 100 * e.value, 100 * e.interval.low,
                       100 * e.interval.high);
  };
  out << fmt::format(
      "study {}: {} variants fitted ({} skipped, {} re-traced differ from the cache); terminator "
      "RMSE pooled over variants, % of albedo*E/pi, 95 % bootstrap intervals over variants\n",
      r.study, r.variants.size(), r.skipped, r.retraced_different);
  out << fmt::format("  raw bump {}; floor of any light,deviation factor {}\n",
                     pct(r.study_floor.none), pct(r.study_floor.floor));
  out << fmt::format("  fitted table, each scene family held out: {}\n", pct(r.held_out_pooled));
  for (const MethodShare& s : r.shares)
    out << fmt::format("  {:<26} {}   share of the achievable {:.0f} % [{:.0f}, {:.0f}]\n",
                       s.method, pct(s.error), 100 * s.share.value, 100 * s.share.interval.low,
                       100 * s.share.interval.high);
}

int fit(const FitArgs& a, const CommandContext& c) {
  FitOptions options;
  options.folder = a.folder;
  options.resamples = a.resamples;
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
  return kExitOk;
}

}  // namespace

Command add_fit_command(CLI::App& app, SharedOptions&) {
  auto a = std::make_shared<FitArgs>();
  CLI::App* cmd = app.add_subcommand(
      "fit",
      "what any terminator factor of the light and deviation angles could achieve on a finished "
      "study, each method's share of it, and a table fitted without the family it is measured on");
  cmd->add_option("folder", a->folder, "finished study output folder (report.json, cache/)")
      ->required();
  cmd->add_option("-o,--output", a->output, "folder for fit.json, fit.csv and table.json")
      ->required();
  cmd->add_option("--resamples", a->resamples, "bootstrap resamples over variants")
      ->check(CLI::Range(100, 100000))
      ->capture_default_str();
  return {cmd, [a](const CommandContext& c) { return fit(*a, c); }};
}

}  // namespace penumbra
