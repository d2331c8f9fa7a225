// `penumbra bench`: the evaluator's throughput table, or with --povray its
// CPU time per render against POV-Ray's, from study/bench.h.
#include <unistd.h>

#include <algorithm>
#include <filesystem>

#include <fmt/format.h>
#include <tbb/global_control.h>

#include "cli/command.h"
#include "cli/stop_signals.h"
#include "core/ray_packet.h"
#include "study/bench.h"

namespace penumbra {

namespace fs = std::filesystem;

namespace {

struct BenchArgs {
  int size = 512, spp = 16;
  int povray_rounds = 0;  // > 0: the evaluator against POV-Ray, this many rounds
};

std::size_t active_threads() {
  return tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
}

// One line of the table: wall and CPU seconds, samples per second.
void print_line(const BenchTiming& t, std::ostream& out) {
  out << fmt::format("{:<30} {:>8} {:>8.3f} {:>8.3f} {:>14.2f} {:>17.2f}\n", t.label,
                     t.packets ? "packets" : "scalar", t.wall_seconds, t.cpu_seconds,
                     t.msamples / t.wall_seconds, t.msamples / t.cpu_seconds);
}

// The rounds' ratios, each printed as it is measured: a render of each per
// round, the two alternating so that both see the machine alike. POV-Ray
// renders on `threads` threads (--threads).
std::vector<double> povray_rounds(const BenchArgs& a, int threads, const fs::path& folder,
                                  std::ostream& out) {
  const nlohmann::json document = bench_scene(a.size, a.spp);
  std::vector<double> ratios;
  for (int r = 1; r <= a.povray_rounds; ++r) {
    const double evaluator = render_cpu_seconds(RendererKind::kEvaluator, document, folder.string(),
                                                threads, StopSignals::interrupted());
    if (!(evaluator > 0.0))
      throw UsageError(fmt::format(
          "bench --povray: the evaluator's render took no measurable CPU time at {0}x{0}, {1} "
          "spp; give a larger --size or --spp",
          a.size, a.spp));
    const double povray = render_cpu_seconds(RendererKind::kPovray, document, folder.string(),
                                             threads, StopSignals::interrupted());
    ratios.push_back(povray / evaluator);
    out << fmt::format("{:<6} {:>10.3f} {:>10.3f} {:>7.1f}x\n", r, evaluator, povray,
                       ratios.back());
  }
  return ratios;
}

int bench_povray(const BenchArgs& a, int threads, std::ostream& out) {
  const StopSignals stop;  // Ctrl-C ends POV-Ray too; the folder is removed below
  const fs::path folder = fs::temp_directory_path() / fmt::format("penumbra-bench-{}", ::getpid());
  fs::create_directories(folder);
  out << fmt::format(
      "penumbra bench --povray: {0}x{0}, {1} spp, bump cylinder (grating, A = 0.01), method none; "
      "CPU seconds per render, the EXR written (POV-Ray: its processes too, parsing included), {2} "
      "threads\n{3:<6} {4:>10} {5:>10} {6:>8}\n",
      a.size, a.spp, active_threads(), "round", "evaluator", "povray", "ratio");
  std::vector<double> ratios;
  try {
    ratios = povray_rounds(a, threads, folder, out);
  } catch (...) {
    fs::remove_all(folder);
    throw;
  }
  fs::remove_all(folder);
  std::sort(ratios.begin(), ratios.end());
  const std::size_t n = ratios.size();
  const double median = n % 2 ? ratios[n / 2] : 0.5 * (ratios[n / 2 - 1] + ratios[n / 2]);
  out << fmt::format(
      "POV-Ray's CPU time over the evaluator's: {:.1f}x to {:.1f}x, median {:.1f}x\n",
      ratios.front(), ratios.back(), median);
  return kExitOk;
}

// The 1M-triangle mesh file, written into a folder of this process's that
// is removed afterwards, as bench_povray's is.
void print_mesh_file_line(const BenchArgs& a, std::ostream& out) {
  const fs::path folder =
      fs::temp_directory_path() / fmt::format("penumbra-bench-mesh-{}", ::getpid());
  fs::create_directories(folder);
  MeshFileTiming m;
  try {
    m = bench_mesh_file(a.size, a.spp, folder.string());
  } catch (...) {
    fs::remove_all(folder);
    throw;
  }
  fs::remove_all(folder);
  out << fmt::format(
      "mesh file (binary PLY, {:.0f} MiB): {} triangles read in {:.3f} s, resident set {:.0f} -> "
      "{:.0f} MiB; bump render: build {:.3f} s, total {:.3f} s wall, {:.2f} M samples/s; peak "
      "RSS {:.0f} MiB\n",
      m.file_mib, m.triangles, m.read_seconds, m.rss_mib_before, m.rss_mib_read, m.build_seconds,
      m.seconds, m.msamples_per_second, m.peak_rss_mib);
}

int bench(const BenchArgs& a, const CommandContext& c) {
  std::ostream& out = c.out;
  if (a.povray_rounds > 0) return bench_povray(a, c.parallelism.threads(), out);
  out << fmt::format(
      "penumbra bench: {}x{}, {} spp, bump cylinder (grating, A = 0.01), {} threads, packets on "
      "{}\n",
      a.size, a.size, a.spp, active_threads(), packet_target());
  out << fmt::format("{:<30} {:>8} {:>8} {:>8} {:>14} {:>17}\n", "method", "path", "wall s",
                     "CPU s", "M samples/s", "M samples/CPU-s");
  for (const MethodInfo& m : all_methods())
    if (!m.needs_table && !m.user_defined) print_line(bench_method(m, a.size, a.spp, true), out);
  print_line(bench_shared_pass(a.size, a.spp, true), out);
  out << "  (one pass: each camera sample counted once per method, as separate renders would "
         "count it)\nthe scalar path, for comparison (same bits):\n";
  print_line(bench_method(all_methods().front(), a.size, a.spp, false), out);
  print_line(bench_shared_pass(a.size, a.spp, false), out);
  const DisplacementTiming d = bench_displacement(a.size, a.spp);
  out << fmt::format(
      "displacement (edge {:.5f}): {} triangles, build {:.3f} s, total {:.3f} s wall, {:.2f} M "
      "samples/s; peak RSS {:.0f} MiB (before: {:.0f} MiB)\n",
      d.edge_length, d.triangles, d.build_seconds, d.seconds, d.msamples_per_second, d.peak_rss_mib,
      d.peak_rss_mib_before);
  const SharedTruthTiming t = bench_shared_truths(a.size, a.spp);
  out << fmt::format(
      "displacement truths of {} lightings (3 light directions x 2 materials): alone {:.3f} s "
      "wall, {:.3f} CPU-s; in one pass {:.3f} s wall, {:.3f} CPU-s ({:.2f}x the CPU-s alone)\n",
      t.lightings, t.alone_seconds, t.alone_cpu_seconds, t.pass_seconds, t.pass_cpu_seconds,
      t.pass_cpu_seconds / t.alone_cpu_seconds);
  const ExtendedTruthTiming e = bench_extended_truth(a.size, a.spp);
  if (e.nested) {
    out << fmt::format(
        "the truth at {} spp (a convergence check): from scratch {:.3f} CPU-s; extending the "
        "sums of {} spp {:.3f} CPU-s ({:.2f}x)\n",
        e.extended_spp, e.scratch_cpu_seconds, e.spp, e.extended_cpu_seconds,
        e.extended_cpu_seconds / e.scratch_cpu_seconds);
  } else {
    out << fmt::format("the truth at {} spp: does not nest {} spp, not timed\n", e.extended_spp,
                       e.spp);
  }
  print_mesh_file_line(a, out);
  return kExitOk;
}

}  // namespace

Command add_bench_command(CLI::App& app, SharedOptions&) {
  auto a = std::make_shared<BenchArgs>();
  CLI::App* cmd = app.add_subcommand("bench", "print evaluator throughput figures");
  cmd->add_option("--size", a->size, "image size in pixels")->check(CLI::Range(16, 4096));
  cmd->add_option("--spp", a->spp, "samples per pixel")->check(CLI::Range(1, 1024));
  cmd->add_option("--povray", a->povray_rounds,
                  "instead of the table: the evaluator against POV-Ray on the same scene, CPU "
                  "seconds per render, this many paired rounds (needs POV-Ray)")
      ->check(CLI::Range(1, 100));
  return {cmd, [a](const CommandContext& c) { return bench(*a, c); }};
}

}  // namespace penumbra
