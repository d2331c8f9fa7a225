// One entry point for the three renderers. Every renderer returns the same
// kind of image: linear float R G B A (radiance in W m^-2 sr^-1, alpha =
// coverage), the scene camera's size and orientation, plus the analysis
// channels of the evaluator's geometry pass for the same camera (the pixels
// align, so theta and deviation are those of the same base-surface points).
#pragma once

#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "evaluator/evaluator.h"
#include "scene/renderer_table.h"
#include "scene/scene.h"

namespace penumbra {

// An external renderer is missing, failed, or timed out. what() says which,
// names the log and quotes its last lines.
class RendererError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
// The render was stopped by cancel_processes() (Ctrl-C, SIGTERM): not a
// failure of the renderer; its work folder is removed.
class RenderCancelled : public RendererError {
 public:
  using RendererError::RendererError;
};

class BlenderSessions;

struct RenderSettings {
  double timeout_s = 600.0;  // per external render, wall clock
  int threads = 0;           // per render; 0: all cores (Blender: always 1, blender_driver.cpp)
  // Executable to run instead of `povray` / `blender` from PATH (tests point
  // these at fakes; users at a self-built renderer). Env: PENUMBRA_POVRAY,
  // PENUMBRA_BLENDER.
  std::string executable;
  // Blender: the fixed script; default <source>/harness/blender_render.py or
  // PENUMBRA_BLENDER_SCRIPT.
  std::string blender_script;
  // Stdout and stderr of the external renderer go here (required for external
  // renderers); the work folder is created beside it and removed on success.
  std::string log_path;
  RenderOptions progress;  // evaluator progress
  // Blender processes that render job after job (a study's); null: each
  // Blender render starts and ends its own.
  BlenderSessions* blender_sessions = nullptr;
};

// Blender processes kept running between renders (harness/blender_render.py
// --serve), so that Blender's start-up (about 1 s of a 1-4 s render) is paid
// once per process rather than per render. A render takes an idle process
// that its own thread started, or starts one: a process ends with the thread
// that started it (util/process.h), so each worker thread has its own. Each job starts
// from Blender's factory settings, so its pixels do not depend on what the
// process rendered before (tested). A process that fails, times out or was
// stopped is ended; the next render starts a fresh one. Their logs live in a
// work folder inside `folder`, removed by the destructor, which also ends the
// processes.
class BlenderSessions {
 public:
  explicit BlenderSessions(std::string folder);
  ~BlenderSessions();
  BlenderSessions(const BlenderSessions&) = delete;
  BlenderSessions& operator=(const BlenderSessions&) = delete;

  struct Session;
  // An idle process of this executable and script, or a new one (started
  // lazily by its first render).
  std::unique_ptr<Session> acquire(const std::string& executable, const std::string& script);
  void release(std::unique_ptr<Session> session);
  // Processes started so far (a benchmark and the tests read it).
  int started() const;

 private:
  std::string folder_, work_;
  mutable std::mutex mutex_;
  std::vector<std::unique_ptr<Session>> idle_;
  int started_ = 0, next_id_ = 0;
};

struct RendererRun {
  Image image;
  RenderStats stats;              // the evaluator's, for the evaluator
  double seconds = 0.0;           // wall time of the external process (or the evaluator)
  double geometry_seconds = 0.0;  // the evaluator's geometry pass, external renderers
};

// Renders `scene` with `renderer`. Throws ExportError (the scene cannot be
// expressed: bad input) or RendererError (the renderer failed, or returned an
// image of the wrong size, without R G B A, or with NaN or Inf values).
RendererRun render_with(RendererKind renderer, const Scene& scene, const RenderSettings& settings);

// The evaluator's renders of `scene` with each of `methods` in one pass
// (render_methods, evaluator/evaluator.h): images[k] has the bits render_with
// gives for methods[k]; errors[k] says why it cannot be used (NaN or Inf
// values, as render_with would throw), "" when it can.
struct MethodsRun {
  std::vector<Image> images;
  std::vector<std::string> errors;
  double seconds = 0.0;  // wall time of the whole pass
};
MethodsRun render_evaluator_methods(const Scene& scene,
                                    const std::vector<TerminatorSettings>& methods,
                                    const RenderSettings& settings);

// A digest of the code and scripts that produce `renderer`'s pixels (see
// renderers/code_digest.h); part of cache keys. For Blender it covers the
// script that settings (or PENUMBRA_BLENDER_SCRIPT) select.
std::string pixel_code_digest(RendererKind renderer, const RenderSettings& settings);

// "POV-Ray 3.7.0.10" / "Blender 3.4.1" / "penumbra 0.3.0": the first line
// the renderer prints for --version; part of cache keys. The probe is killed
// after min(60 s, settings.timeout_s).
std::string renderer_version(RendererKind renderer, const RenderSettings& settings);

// The executable `renderer` runs (settings, the PENUMBRA_* variable, then
// PATH); RendererError naming the Debian package when there is none. Empty
// for the evaluator.
std::string renderer_executable(RendererKind renderer, const RenderSettings& settings);

// What a render will need, estimated before it starts (rough upper bounds,
// within a factor of about 2): peak memory of the images, the ground-truth or
// low-poly mesh and its BVH, and the size of the EXR written.
struct ResourceEstimate {
  double memory_bytes = 0.0;
  double output_bytes = 0.0;  // uncompressed EXR: the most the file can take
  double triangles = 0.0;     // of the mesh the render builds (0: none)
  std::string pointer;        // the scene value that dominates memory
  std::string detail;         // "4096x4096 px: 1.6 GiB, 1.7 M triangles: 0.2 GiB"
};
inline constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;
// The default of --max-memory: a third of the 24 GiB the project's machines have.
inline constexpr double kDefaultMaxMemoryBytes = 8.0 * kGiB;

ResourceEstimate estimate_resources(RendererKind renderer, const Scene& scene);

// InputError (bad input, exit 2) naming `origin` and the dominant pointer when
// the estimate exceeds `max_memory_bytes`; OutputError when `output_folder`
// (if not empty) has less free space than the output may take.
void check_resources(const ResourceEstimate& estimate, double max_memory_bytes,
                     const std::string& origin, const std::string& output_folder = "");

}  // namespace penumbra
