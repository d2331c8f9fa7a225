// Batch studies: base scenes x sweep axes x methods x renderers, rendered in
// parallel into a content-addressed cache, compared with the displacement
// ground truth (bump methods) or the analytic smooth surface (low-poly
// meshes and shadow-ray offsets), and written as report.json, metrics.csv and (through
// harness/report.py) figures and report.html.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "renderers/renderers.h"

namespace penumbra {

inline constexpr int kStudyFormatVersion = 1;
inline constexpr int kReportFormatVersion = 1;
// The most renders one study may expand to; larger sweeps are refused before
// expansion (split them into several studies).
inline constexpr long kMaxStudyRenders = 1000000;

// One sweep axis: a scene value by JSON pointer and the values it takes.
struct StudyAxis {
  std::string pointer;
  std::string label;  // for plots and tables; default: the pointer
  std::vector<nlohmann::json> values;
};

// A method as the study names it: an id and optional parameter values.
struct StudyMethod {
  std::string id;
  nlohmann::json parameters;  // object or null
  std::string label;          // "shading-offset(s=0.3)"
};

// A metric drawn over two axes (indices into Study::axes).
struct StudyPlot {
  std::string metric;  // "profile.rmse_terminator", "image.ssim", ...
  int x = 0, y = 1;
  std::string kind = "contour";  // or "heatmap"
  std::string renderer = "evaluator";
};

// The low-poly section: tessellated scenes, each rendered with every offset
// method a renderer offers and compared with the same scene's analytic
// smooth surface (the ground truth of the smooth-shading terminator).
struct LowPolyPart {
  std::vector<std::string> scenes;
  nlohmann::json set = nlohmann::json::object();
  std::vector<StudyAxis> axes;
  std::vector<StudyMethod> offsets;  // offset method ids with parameters
  std::vector<RendererKind> renderers;
  int convergence_axis = -1;  // index into axes: the tessellation level, for convergence plots
};

struct Study {
  std::string name;
  std::string file;
  std::vector<std::string> scenes;                // paths, resolved against the study file's folder
  nlohmann::json set = nlohmann::json::object();  // pointer -> value, for every scene
  std::vector<StudyAxis> axes;
  std::vector<StudyMethod> methods;
  std::vector<RendererKind> renderers;
  int blender_spp = 32;
  std::vector<StudyPlot> plots;
  std::optional<LowPolyPart> lowpoly;
};

// Strict: unknown keys, wrong types, unknown methods/renderers and pointers
// that do not name a scene value are InputErrors with the file and pointer.
Study load_study(const std::string& path);

struct StudyOptions {
  std::string output_dir;
  int jobs = 1;
  double timeout_s = 600.0;
  // Stop starting renders after this many new (uncached) ones; -1: no limit.
  // Resuming later finishes the rest. Tests use it to simulate an interrupt.
  long max_new_renders = -1;
  const std::atomic<bool>* interrupted = nullptr;  // set by a SIGINT handler
  std::function<void(const std::string&)> log;     // progress lines
  std::function<void(std::size_t done, std::size_t total, double eta_s)> progress;
  bool figures = true;  // run harness/report.py (figures and report.html)
  // Plan and validate only: count renders and cache hits, write nothing.
  bool dry_run = false;
  // Per render; a render estimated above it is refused (bad input) before
  // anything is written.
  double max_memory_bytes = kDefaultMaxMemoryBytes;
  std::string python;  // default: PENUMBRA_PYTHON, /usr/bin/python3, python3
};

struct StudyRunStats {
  std::size_t renders = 0;            // in the study
  std::size_t rendered = 0;           // rendered by this run
  std::size_t cached = 0;             // reused from the cache
  std::size_t failed = 0;             // failed in this run (kept out of the cache)
  std::size_t not_started = 0;        // interrupted or --max-renders
  std::vector<std::string> failures;  // "label: error"
  double seconds = 0.0;
  std::string report_html;                     // path, when written
  std::map<std::string, std::size_t> planned;  // dry run: renders per renderer
  std::vector<std::string> warnings;           // damaged cache entries, stale files removed
  std::size_t stale_removed = 0;
  bool complete() const { return failed == 0 && not_started == 0; }
};

// Runs the study; writes report.json and metrics.csv (and figures and
// report.html when options.figures) only when every render is accounted for
// (done or failed), never after an interruption.
StudyRunStats run_study(const Study& study, const StudyOptions& options);

// Runs harness/report.py with `arguments` (matplotlib figures, report.html),
// its output in `log_path`. Python: `python`, else PENUMBRA_PYTHON, else
// /usr/bin/python3 (Debian's, which has python3-matplotlib), else python3.
void run_plot_script(const std::vector<std::string>& arguments, const std::string& log_path,
                     const std::string& python = "", double timeout_s = 600.0);

// The 128-bit content key of a render: canonical scene JSON, renderer,
// renderer version, Penumbra version (FNV-1a, two seeds), as 32 hex digits.
std::string render_key(const nlohmann::json& canonical_scene, const std::string& renderer,
                       const std::string& renderer_version);

}  // namespace penumbra
