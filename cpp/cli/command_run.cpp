// `penumbra run`: a study (study/study.h) here, or on Slurm; its dry run
// counts and prices the renders.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <mutex>
#include <thread>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "cli/command.h"
#include "cli/stop_signals.h"
#include "image/image_io.h"
#include "study/study.h"

namespace penumbra {

namespace fs = std::filesystem;

namespace {

struct RunArgs {
  std::string study, output;
  double timeout = 600.0;
  long max_renders = -1;
  bool no_figures = false, no_fit = false, quiet = false, dry_run = false;
  bool no_shared_truths = false;
  bool self_contained = false;  // report.html embeds its images
  double max_memory_gib = kDefaultMaxMemoryBytes / kGiB;
  std::vector<std::string> add_methods;  // --add-method, in the order given
  // --methods-from: main.cpp hands the command to Python before it gets here.
  std::vector<std::string> methods_from;
  std::string executor = "local";  // local or slurm
  SlurmOptions slurm;              // --partition, --array-limit, ... (chain: --slurm-chain)
};

std::string duration_text(double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  const long t = std::lround(s);
  return t >= 60 ? fmt::format("{}m{:02d}s", t / 60, t % 60) : fmt::format("{}s", t);
}

// The wall-time estimate, then one line per kind of render still to do,
// with where its rate comes from.
void print_cost(const CostEstimate& cost, std::ostream& out) {
  if (cost.lines.empty() && cost.first_checks == 0) return;
  out << fmt::format(
      "estimated time: about {} of wall time on {} cores: renders {:.0f} core-s, ground-truth "
      "convergence checks about {:.0f} core-s ({} in the first round, {:.0f} core-s, times {:g} "
      "for the later rounds, as measured on the shipped studies), comparisons and figures about "
      "{:.0f} s ({} comparisons); a model of this machine's cost per render, good to about a "
      "factor of 2 (core-hours, which Slurm bills: {:.3f})\n",
      duration_text(cost.wall_seconds), cost.cores, cost.core_seconds, cost.checks_core_seconds,
      cost.first_checks, cost.first_checks_core_seconds, kCheckRoundsRatio, cost.report_seconds,
      cost.comparisons, (cost.core_seconds + cost.checks_core_seconds) / 3600.0);
  for (const CostLine& line : cost.lines) {
    const std::string kind =
        fmt::format("{} {}{}", to_string(line.renderer), to_string(line.representation),
                    line.tessellated ? " (low-poly)" : "");
    const std::string basis =
        line.measured > 0
            ? fmt::format(
                  "per-sample rate: median of {} cached renders of this study; their range "
                  "{:.1f} to {:.1f} core-s",
                  line.measured, line.core_seconds_low, line.core_seconds_high)
            : "built-in, measured on a 2-core machine; none cached yet";
    out << fmt::format(
        "  {:<32} {:>7} renders {:>9.1f} core-s  ({:.3g} core-s each + {:.3g} per 10^6 pixel "
        "samples + {:.3g} per 10^6 triangles; {})\n",
        kind, line.renders, line.core_seconds, line.model.fixed, line.model.per_msample,
        line.model.per_mtriangle, basis);
  }
}

// The study's own sections, measured after the renders.
void print_sections(const Study& study, const std::string& dir, std::ostream& out) {
  if (study.filtering) {
    const FilteringSection& f = *study.filtering;
    out << fmt::format(
        "filtering: {} maps x {} runs, each {} footprints per level over levels 0 to {} x {} "
        "filters x {} base alphas (measured after the renders; unchanged entries in {}/filtering "
        "are reused; about 25 s per entry of a 1024^2 map at the defaults on 2 cores)\n",
        f.maps.size(), f.runs.size(), f.options.footprints, f.options.max_level,
        f.options.filters.size(), f.options.alphas.size(), dir);
  }
  if (study.interplay) {
    const InterplaySection& ip = *study.interplay;
    out << fmt::format(
        "interplay: {} baked at {} texels around, {} bump renders ({} levels x {} methods) and 2 "
        "displacement truths (the evaluator, after the renders; cached in {}/cache)\n",
        ip.scene, ip.size, ip.levels.size() * ip.methods.size(), ip.levels.size(),
        ip.methods.size(), dir);
  }
}

int print_dry_run(const Study& study, const StudyRunStats& stats, const std::string& dir,
                  double max_memory_gib, std::ostream& out) {
  std::string per;
  for (const auto& [renderer, count] : stats.planned)
    per += fmt::format("{}{} {}", per.empty() ? "" : ", ", count, renderer);
  out << fmt::format(
      "study {}: {} renders ({}); {} found in {}/cache, {} to render; nothing written (dry run)\n",
      study.name, stats.renders, per, stats.cached, dir, stats.renders - stats.cached);
  const std::string checks =
      stats.planned_checks == 0
          ? std::string("every ground-truth convergence check is cached")
          : fmt::format(
                "{} ground-truth convergence checks to render first (more may follow, up to 3 "
                "renders per variant and round)",
                stats.planned_checks);
  out << fmt::format(
      "cache: the renders to do write at most {:.3f} GiB (uncompressed EXR); the largest needs "
      "about {:.3f} GiB of memory (--max-memory {:.3g} GiB); {}\n",
      stats.planned_output_bytes / kGiB, stats.planned_peak_memory_bytes / kGiB, max_memory_gib,
      checks);
  print_cost(stats.cost, out);
  print_sections(study, dir, out);
  return kExitOk;
}

// The Slurm options of `penumbra run`, with the command its report job runs:
// this run again, by absolute paths, so that it runs from any folder.
SlurmOptions slurm_options(const RunArgs& a, const std::string& output_dir) {
  SlurmOptions s = a.slurm;
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot find the penumbra executable (/proc/self/exe)");
  s.continue_argv = {self.string(),
                     "run",
                     fs::absolute(a.study).string(),
                     "-o",
                     fs::absolute(output_dir).string(),
                     "--executor",
                     "slurm",
                     "--timeout",
                     fmt::format("{}", a.timeout),
                     "--max-memory",
                     fmt::format("{}", a.max_memory_gib),
                     "--array-limit",
                     std::to_string(s.array_limit),
                     "--renders-per-task",
                     std::to_string(s.renders_per_task)};
  if (a.no_figures) s.continue_argv.push_back("--no-figures");
  if (a.no_fit) s.continue_argv.push_back("--no-fit");
  if (a.self_contained) s.continue_argv.push_back("--self-contained");
  if (!s.partition.empty())
    s.continue_argv.insert(s.continue_argv.end(), {"--partition", s.partition});
  for (const std::string& arg : s.sbatch_args) s.continue_argv.push_back("--sbatch-arg=" + arg);
  return s;
}

int print_submission(const SlurmSubmission& sub, const std::string& dir, std::ostream& out) {
  if (sub.submitted > 0)
    out << fmt::format(
        "submitted {} renders to Slurm as array job {} ({} tasks{}); job {} writes the report "
        "when they end (or submits what is still missing); `penumbra status {}` shows progress\n",
        sub.submitted - sub.chains, sub.array_job, sub.tasks,
        sub.chains > 0 ? fmt::format(", with {} ground-truth convergence chains, each in a task of "
                                     "its own with its variant's evaluator renders",
                                     sub.chains)
                       : "",
        sub.report_job, dir);
  if (sub.still_queued > 0)
    out << fmt::format(
        "{} renders are still queued or running in an earlier submission; nothing submitted "
        "twice\n",
        sub.still_queued);
  return kExitOk;
}

// The progress bar and the lines worth showing on a terminal; every line,
// prefixed, elsewhere (a log file).
void set_progress(StudyOptions& o, bool quiet, bool tty, std::mutex& mutex, std::ostream& err) {
  if (quiet) return;
  if (!tty) {
    o.log = [&](const std::string& line) {
      std::lock_guard<std::mutex> lock(mutex);
      err << "penumbra run: " << line << "\n" << std::flush;
    };
    return;
  }
  o.progress = [&](std::size_t done, std::size_t total, double eta) {
    std::lock_guard<std::mutex> lock(mutex);
    const int width = 30;
    const int fill =
        static_cast<int>(width * double(done) / double(std::max<std::size_t>(total, 1)));
    err << fmt::format("\r[{}{}] {}/{} renders, ETA {}   ", std::string(fill, '#'),
                       std::string(width - fill, '.'), done, total, duration_text(eta))
        << std::flush;
  };
  o.log = [&](const std::string& line) {
    if (line.find("FAILED") != std::string::npos || line.find("renders:") != std::string::npos ||
        line.find("WARNING") != std::string::npos || line.rfind("figures:", 0) == 0 ||
        line.rfind("fit:", 0) == 0) {
      std::lock_guard<std::mutex> lock(mutex);
      err << "\r" << line << "\n" << std::flush;
    }
  };
}

StudyOptions study_options(const RunArgs& a, const Study& study, const CommandContext& c) {
  StudyOptions o;
  o.output_dir = a.output.empty() ? "results/" + study.name : a.output;
  o.parallelism = c.parallelism;
  o.timeout_s = a.timeout;
  o.max_new_renders = a.max_renders;
  o.figures = !a.no_figures;
  o.fit = !a.no_fit;
  o.shared_truths = !a.no_shared_truths;
  o.self_contained_html = a.self_contained;
  o.interrupted = &StopSignals::interrupted();
  o.dry_run = a.dry_run;
  o.max_memory_bytes = a.max_memory_gib * kGiB;
  if (a.executor == "slurm") o.slurm = slurm_options(a, o.output_dir);
  return o;
}

// The run's wall time against the least its renders allow on the cores
// they had (issue 45's efficiency figure): the render phase's ratio (what
// idle cores and the scheduling cost) and the whole run's, with the steps
// after the renders: the comparisons and report files, the fit and the figures.
void print_efficiency(const StudyRunStats& stats, int cores, std::ostream& out) {
  if (stats.render_core_seconds <= 0.0 || cores < 1) return;
  const double bound = stats.render_core_seconds / cores;
  const double after = stats.seconds - stats.render_phase_s;
  out << fmt::format(
      "time: renders {:.1f} core-s on {} cores (at least {:.1f} s of wall time); the render phase "
      "{:.1f} s: {:.2f}x that bound; then the comparisons and report files {:.1f} s, the fit "
      "{:.1f} s, the figures {:.1f} s; the run {:.1f} s: {:.2f}x the bound, {:.2f}x without the "
      "figures\n",
      stats.render_core_seconds, cores, bound, stats.render_phase_s, stats.render_phase_s / bound,
      std::max(0.0, after - stats.fit_s - stats.figures_s), stats.fit_s, stats.figures_s,
      stats.seconds, stats.seconds / bound, (stats.seconds - stats.figures_s) / bound);
}

// --add-method: each id joins the bump section's methods (after those the
// study names), measured and ranked like them; a user method registered
// from Python (core/user_method.h) is named this way.
void add_methods(const std::vector<std::string>& ids, Study* study) {
  if (ids.empty()) return;
  std::vector<StudyMethod>& methods = study->bump.methods;
  if (study->bump.scenes.empty())
    throw UsageError("--add-method: study " + study->file + " has no bump section");
  for (const std::string& id : ids) {
    const auto method = method_from_id(id);
    if (!method || method_info(*method).needs_table ||
        (*method == TerminatorMethod::kPython && !find_user_method(id))) {
      const std::vector<std::string> users = user_method_ids();
      throw UsageError(fmt::format(
          "--add-method: expected a built-in method id that needs no table or a user method "
          "registered in this process{}, got \"{}\"",
          users.empty() ? " (none is: register them with @penumbra.method in Python)"
                        : " (" + fmt::format("{}", fmt::join(users, ", ")) + ")",
          id));
    }
    const bool named = std::any_of(methods.begin(), methods.end(),
                                   [&](const StudyMethod& m) { return m.label == id; });
    if (!named) methods.push_back({id, nlohmann::json(), id});
  }
}

int run(const RunArgs& a, const CommandContext& c) {
  // A study writes PNG previews after its renders: a missing image module
  // (a binary copied without lib/penumbra/) is found now, not mid-run.
  if (!a.dry_run) load_image_formats();
  const ImageReadLimit image_limit(a.max_memory_gib * kGiB);  // the maps the study reads
  if (!a.methods_from.empty())
    throw UsageError(
        "--methods-from: run the penumbra binary, or python3 -m penumbra, which "
        "register the file's methods; in Python, import the file and pass "
        "extra_methods to penumbra.run");
  Study study = load_study(a.study);
  add_methods(a.add_methods, &study);
  // Slurm's array tasks run the penumbra binary, which has no Python.
  if (a.executor == "slurm")
    for (const StudyMethod& m : study.bump.methods)
      if (find_user_method(m.id))
        throw UsageError(fmt::format(
            "--executor slurm: \"{}\" is a user method, which only a Python process has "
            "(the array tasks run the penumbra binary); run the study with --executor local",
            m.id));
  StudyOptions o = study_options(a, study, c);
  const bool tty = ::isatty(STDERR_FILENO);
  std::mutex mutex;
  set_progress(o, a.quiet, tty, mutex, c.err);
  const StopSignals stop;
  const StudyRunStats stats = run_study(study, o);
  if (a.dry_run) return print_dry_run(study, stats, o.output_dir, a.max_memory_gib, c.out);
  if (!a.quiet && tty) c.err << "\n";
  c.out << fmt::format(
      "study {}: {} renders ({} rendered now, {} from the cache, {} failed, {} not started) in "
      "{:.1f} s\n",
      study.name, stats.renders, stats.rendered, stats.cached, stats.failed, stats.not_started,
      stats.seconds);
  for (const std::string& f : stats.failures) c.out << "  failed: " << f << "\n";
  print_efficiency(stats, o.parallelism.threads(), c.out);
  if (stats.slurm && stats.not_started > 0)
    return print_submission(*stats.slurm, o.output_dir, c.out);
  if (stats.not_started > 0) {
    c.out << fmt::format(
        "stopped before the end; run the same command again to resume (finished "
        "renders are cached in {}/cache)\n",
        o.output_dir);
    return StopSignals::interrupted().load() ? StopSignals::exit_code() : kExitFailure;
  }
  c.out << fmt::format("wrote {0}/report.json, {0}/metrics.csv{1}\n", o.output_dir,
                       stats.report_html.empty() ? "" : ", figures/ and report.html");
  if (!stats.report_html.empty()) c.out << "report: " << stats.report_html << "\n";
  return stats.failed > 0 ? kExitFailure : kExitOk;
}

void add_slurm_options(CLI::App* cmd, RunArgs& a) {
  cmd->add_option("--executor", a.executor,
                  "local: render here, --jobs at a time; slurm: submit the missing renders as "
                  "a Slurm job array and a report job that depends on it, then return")
      ->check(CLI::IsMember({"local", "slurm"}))
      ->capture_default_str();
  cmd->add_option("--partition", a.slurm.partition,
                  "slurm: partition of the array and report jobs (default: the cluster's)");
  cmd->add_option("--array-limit", a.slurm.array_limit, "slurm: array tasks running at once")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_option("--renders-per-task", a.slurm.renders_per_task,
                  "slurm: renders per array task, at most (a variant's ground-truth "
                  "convergence chain takes a task of its own; renders that share a mesh "
                  "share a task where they fit)")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_option("--sbatch-arg", a.slurm.sbatch_args,
                  "slurm: an argument for every sbatch call, as it is "
                  "(--sbatch-arg=--time=2:00:00; repeatable)");
  cmd->add_option("--slurm-chain", a.slurm.chain, "internal: the report job's chain of submissions")
      ->group("");
}

}  // namespace

Command add_run_command(CLI::App& app, SharedOptions& shared) {
  auto a = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand(
      "run", "run a study: renders (cached, resumable), metrics, report.json/csv/html, figures");
  cmd->add_option("study", a->study, "study JSON file")->required();
  cmd->add_option("-o,--output", a->output, "output folder (default results/NAME)");
  add_jobs_option(cmd, shared)->check(CLI::Range(1, 256));
  cmd->add_option("--timeout", a->timeout, "seconds per external render")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--max-renders", a->max_renders,
                  "start at most this many new renders, then stop (resume later)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--no-figures", a->no_figures, "skip matplotlib figures and report.html");
  cmd->add_flag("--no-fit", a->no_fit,
                "skip penumbra fit into OUT/fit (the report's What is achievable section)");
  cmd->add_flag("--no-shared-truths", a->no_shared_truths,
                "render each ground truth alone rather than in one pass with the truths of the "
                "other lights and materials on its mesh (same bits, slower: to measure what the "
                "pass saves)");
  cmd->add_flag("--self-contained", a->self_contained,
                "report.html embeds every image (one file to mail; default: it links "
                "images/ and figures/ beside it)");
  cmd->add_flag("--dry-run", a->dry_run,
                "validate and count the renders (and cache hits); write nothing");
  cmd->add_option("--max-memory", a->max_memory_gib,
                  "refuse a study with a render estimated to need more memory (GiB, per render)")
      ->check(CLI::Range(0.001, 1e6))
      ->capture_default_str();
  cmd->add_flag("-q,--quiet", a->quiet, "no progress");
  cmd->add_option("--add-method", a->add_methods,
                  "also measure this method in the bump section (repeatable): a built-in id, or a "
                  "user method registered from Python (docs/python.md; `python3 -m penumbra run "
                  "STUDY --methods-from FILE.py` registers a file's)");
  cmd->add_option("--methods-from", a->methods_from,
                  "a Python file of user methods (@penumbra.method): the study runs as "
                  "`python3 -m penumbra run ...`, which registers them and measures each like "
                  "--add-method (repeatable; docs/python.md)");
  add_slurm_options(cmd, *a);
  return {cmd, [a](const CommandContext& c) { return run(*a, c); }};
}

}  // namespace penumbra
