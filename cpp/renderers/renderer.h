// The interface every renderer is behind. A RendererEntry is a renderer's
// row (what it is, where it comes from, what it can render and why not more)
// and the calls the study and the command line make, as plain functions:
// the evaluator's entry is renderers/evaluator_entry.cpp, each external
// renderer's is in its folder, renderers/external/<id>/. The registry
// (renderers/registry.h) finds the entry of a RendererKind; nothing else
// switches over renderers. Every renderer returns the same kind of image:
// linear float R G B A (radiance in W m^-2 sr^-1, alpha = coverage), the
// scene camera's size and orientation, plus the analysis channels of the
// evaluator's geometry pass for the same camera (the pixels align, so theta
// and deviation are those of the same base-surface points).
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "core/shadow_origin.h"
#include "core/terminator.h"
#include "evaluator/evaluator.h"
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
// The scene uses something the target renderer cannot express (a method it
// does not implement, a point light, a glossy lobe...). Bad input.
class ExportError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class BlenderSessions;  // renderers/external/blender/blender_sessions.h

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

struct RendererRun {
  Image image;
  RenderStats stats;              // the evaluator's, for the evaluator
  double seconds = 0.0;           // wall time of the external process (or the evaluator)
  double geometry_seconds = 0.0;  // the evaluator's geometry pass, external renderers
};

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

// One kind of render's cost in core-seconds (cores x wall time, what Slurm
// bills): fixed + per_msample x 10^6 pixel samples + per_mtriangle x 10^6
// mesh triangles. The dry run's model (study/cost.h).
struct RenderCostModel {
  double fixed = 0.0;
  double per_msample = 0.0;
  double per_mtriangle = 0.0;
  double core_seconds(double msamples, double mtriangles) const {
    return fixed + per_msample * msamples + per_mtriangle * mtriangles;
  }
};

// A renderer's measured price of one representation on analytic or
// tessellated shapes.
struct BuiltInCost {
  Representation representation;
  bool tessellated;
  RenderCostModel model;
};

// A renderer's row of the renderer table: what it is, where it comes from,
// and what it can render. The exporters, the study's "missing" rows, the
// command line's choices, `penumbra renderers` and docs/renderers.md read it.
// A row names what its renderer has; the rest is empty or false.
struct RendererInfo {
  const char* id = "";    // what users type and reports print: "povray"
  const char* name = "";  // "POV-Ray 3.7"
  // External renderers: the Debian package, the executable it installs and
  // the environment variable that points Penumbra at another one. Empty for
  // the built-in evaluator.
  const char* debian_package = "";
  const char* executable = "";
  const char* executable_variable = "";
  // A line of `EXECUTABLE --version` that contains this names the version.
  const char* version_marker = "";
  const char* note = "";  // how it renders bump and the ground truth (reports, docs)
  // Terminator methods (scene /terminator/method) per representation; the
  // evaluator offers every method of the method table.
  bool all_methods = false;
  std::vector<TerminatorMethod> bump_methods = {};
  std::vector<TerminatorMethod> other_methods = {};  // smooth and displacement
  const char* methods_why_not = "";                  // why the others are missing
  // Shadow-ray offsets (scene /offset/method).
  bool all_offsets = false;
  std::vector<OffsetMethod> offsets = {};
  const char* offsets_why_not = "";
  bool props = false;                    // extra spheres in the scene (/props)
  const char* props_why_not = "";        // "" when props are offered
  bool specular = false;                 // the GGX lobe (/material/specular_weight > 0)
  const char* specular_why_not = "";     // "" when it is offered
  bool height_maps = false;              // /height/type "height-map"
  const char* height_maps_why_not = "";  // "" when they are offered
  bool normal_maps = false;              // /height/type "normal-map"
  const char* normal_maps_why_not = "";  // "" when they are offered
  bool plane = false;                    // /shape/type "plane"
  const char* plane_why_not = "";        // "" when it is offered
  // /shape/tessellation/shading "consistent" (core/consistent_normal.h)
  bool consistent_normals = false;
  const char* consistent_normals_why_not = "";  // "" when they are offered
  // Bump on a mesh shape (/shape/type "mesh") by a height, differentiated
  // over the flat triangle as the evaluator does (facet_bump_gradient in
  // core/mesh_surface.h); normal maps are `normal_maps`.
  bool mesh_bump = false;
  const char* mesh_bump_why_not = "";  // "" when it is offered
  // Bump methods whose reference normal this renderer takes as the
  // interpolated Ni whatever /terminator/reference_normal says (Cycles'
  // Bump node and Normal Map node carry Chiang's term against Ni). On a
  // mesh with the reference Ng they are not the evaluator's method.
  std::vector<TerminatorMethod> reference_ni_methods = {};

  // Runs a program of its own (and so writes a log and needs a geometry
  // pass for its analysis channels); false for the built-in evaluator.
  bool external() const { return *executable != '\0'; }
};

struct RendererEntry {
  RendererInfo info;
  // Renders `scene`; render_with (renderers/renderers.h) checks the image.
  // Throws ExportError (the scene cannot be expressed) or RendererError.
  RendererRun (*render)(const Scene& scene, const RenderSettings& settings) = nullptr;
  // "POV-Ray 3.7.0.10" / "Blender 3.4.1" / "penumbra 0.3.0": part of cache
  // keys (an external renderer's is external::probe_version).
  std::string (*version)(const RendererInfo& info, const RenderSettings& settings) = nullptr;
  // A digest of the code and scripts that produce its pixels
  // (renderers/code_digest.h); part of cache keys.
  std::string (*pixel_code_digest)(const RenderSettings& settings) = nullptr;
  // Memory and output of a render of `scene` (estimate_render_resources).
  ResourceEstimate (*estimate_resources)(const Scene& scene) = nullptr;
  // `penumbra export`: writes what the renderer reads into `folder` (which
  // exists) and returns what it wrote and how to render it; null when there
  // is nothing to export (the evaluator). `export_file` is the file it
  // writes first, checked for writing before the scene is exported.
  std::string (*export_files)(const Scene& scene, const std::string& folder) = nullptr;
  const char* export_file = "";
  // What the dry run prices its renders at while the study's cache holds
  // none of them (study/cost.h; study/cost.cpp says how they were measured):
  // every representation, on analytic and on tessellated shapes.
  std::vector<BuiltInCost> costs = {};
  // Core-seconds to start a process that serves its renders, once per
  // worker (Blender's); 0 for a renderer that starts with each render.
  double start_seconds = 0.0;
};

// What a renderer can render, from its row.
std::vector<TerminatorMethod> methods_offered(const RendererInfo& info,
                                              Representation representation);
std::vector<OffsetMethod> offsets_offered(const RendererInfo& info);
bool offers(const RendererInfo& info, Representation representation, TerminatorMethod method);
bool offers(const RendererInfo& info, OffsetMethod offset);

// Why the row's renderer does not render `method`'s bump of a mesh shape
// whose reference normal is `reference` ("" when it does):
// reference_ni_methods under Ng.
std::string mesh_method_why_not(const RendererInfo& info, TerminatorMethod method,
                                ReferenceNormal reference);

// Refuses, with the row's reason, the scene features the row says its
// renderer (exported as `name`) cannot render: height or normal maps, the
// plane, consistent normal interpolation, bump on a mesh or a method whose
// reference normal there is not the scene's.
void refuse_unoffered(const Scene& scene, const RendererInfo& info, const char* name);

// The estimate of a render that holds the evaluator's image plus
// `extra_image_bytes` (POV-Ray's supersampled one) and, where the scene is
// tessellated or displaced or `always_meshed` (Blender's fine grids for the
// analytic shapes), its mesh.
ResourceEstimate estimate_render_resources(const Scene& scene, double extra_image_bytes,
                                           bool always_meshed);

// InputError (bad input, exit 2) naming `origin` and the dominant pointer when
// the estimate exceeds `max_memory_bytes`; OutputError when `output_folder`
// (if not empty) has less free space than the output may take.
void check_resources(const ResourceEstimate& estimate, double max_memory_bytes,
                     const std::string& origin, const std::string& output_folder = "");

}  // namespace penumbra
