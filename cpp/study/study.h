// Batch studies, in one direction:
//   study_file  (read the study)  ->  plan  (typed jobs, validated)
//   -> cache  (what is already rendered)  ->  execute  (render the rest)
//   -> compare  (rows against the ground truth)  ->  report_files, figures.
// Bump methods are compared with the displacement ground truth, low-poly
// meshes and shadow-ray offsets with the analytic smooth surface.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "renderers/renderers.h"
#include "study/cost.h"
#include "study/slurm.h"
#include "study/study_file.h"
#include "util/parallel.h"

namespace penumbra {

// The least time the figures and report.html may take (seconds).
inline constexpr double kFiguresTimeoutS = 3600.0;

struct StudyOptions {
  std::string output_dir;
  // Renders (cache reads, comparisons) at once and threads per render
  // (util/parallel.h); by default one render at a time on every core.
  Parallelism parallelism = resolve_parallelism(1);
  double timeout_s = 600.0;  // per render; the figures get at least kFiguresTimeoutS
  // Stop starting renders after this many new (uncached) ones; -1: no limit.
  // Resuming later finishes the rest. Tests use it to simulate an interrupt.
  long max_new_renders = -1;
  const std::atomic<bool>* interrupted = nullptr;  // set by a SIGINT handler
  std::function<void(const std::string&)> log;     // progress lines
  std::function<void(std::size_t done, std::size_t total, double eta_s)> progress;
  bool figures = true;  // run harness/report.py (figures and report.html)
  // Run `penumbra fit` into <output>/fit before the figures, so that the
  // report has its "What is achievable" section (study/fit.h); kept while
  // report.json and the evaluator's code are unchanged.
  bool fit = true;
  // The local executor renders the ground truths of one displaced mesh in
  // shared passes (study/rendering.h, MethodBatches); false: each alone.
  bool shared_truths = true;
  // report.html embeds its images as data: URIs (one file to mail) instead
  // of linking images/ and figures/ beside it.
  bool self_contained_html = false;
  // Plan and validate only: count renders and cache hits, write nothing.
  bool dry_run = false;
  // Per render; a render estimated above it is refused (bad input) before
  // anything is written.
  double max_memory_bytes = kDefaultMaxMemoryBytes;
  std::string python;  // default: PENUMBRA_PYTHON, /usr/bin/python3, python3
  // Render on a Slurm cluster instead of local threads (study/slurm.h): the
  // run submits what the cache lacks and returns; its report job continues.
  std::optional<SlurmOptions> slurm;
};

struct StudyRunStats {
  std::size_t renders = 0;            // in the study
  std::size_t rendered = 0;           // rendered by this run
  std::size_t cached = 0;             // reused from the cache
  std::size_t failed = 0;             // failed in this run (kept out of the cache)
  std::size_t not_started = 0;        // interrupted or --max-renders
  std::vector<std::string> failures;  // "label: error"
  double seconds = 0.0;
  // The renders this run did on this machine (local executor; ground-truth
  // checks included): wall seconds times threads, as their cache entries
  // record; with the cores they had, the least wall time they allow.
  double render_core_seconds = 0.0;
  std::string report_html;                     // path, when written
  std::map<std::string, std::size_t> planned;  // dry run: renders per renderer
  // Dry run: ground-truth convergence checks the cache lacks, in the rounds
  // the cache lets it replay (later rounds depend on these renders).
  std::size_t planned_checks = 0;
  // Dry run: the most the renders still to do may write into the cache
  // (uncompressed EXR), and the largest estimated memory of one render.
  double planned_output_bytes = 0.0, planned_peak_memory_bytes = 0.0;
  std::vector<std::string> warnings;  // damaged cache entries, stale files removed
  std::size_t stale_removed = 0;
  // Comparisons measured by this run, and those taken from the study's
  // comparison store (study/comparison_store.h).
  std::size_t comparisons_measured = 0, comparisons_kept = 0;
  // Preview and difference PNGs drawn, and kept from the last run (study/previews.h).
  std::size_t pictures_drawn = 0, pictures_kept = 0;
  // Passes that rendered several methods of one variant at once
  // (study/rendering.h, MethodBatches), and the renders they held.
  std::size_t method_batches = 0, batched_renders = 0;
  // Passes that rendered the displacement truths of several lights and
  // materials on one geometry (MethodBatches), and the renders they held.
  std::size_t truth_batches = 0, batched_truths = 0;
  double fit_s = 0.0;  // penumbra fit's wall time in this run (0: kept, or nothing to fit)
  // Wall seconds from the start to the end of the renders (truth checks
  // included), and of the figures and report.html (0: not drawn).
  double render_phase_s = 0.0, figures_s = 0.0;
  int blender_processes = 0;             // Blender processes started; each serves many renders
  std::optional<SlurmSubmission> slurm;  // what a Slurm run submitted
  CostEstimate cost;                     // dry run: of the renders to do
  bool complete() const { return failed == 0 && not_started == 0; }
};

// Runs the study; writes report.json and metrics.csv (and figures and
// report.html when options.figures) only when every render is accounted for
// (done or failed), never after an interruption.
StudyRunStats run_study(const Study& study, const StudyOptions& options);

}  // namespace penumbra
