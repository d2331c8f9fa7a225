// A study expanded into typed jobs: one render each (a scene, a renderer),
// grouped by variant (a base scene with one combination of axis values).
// Every scene is parsed and its resources checked here, before anything is
// written or rendered.
#pragma once

#include <array>
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "renderers/renderers.h"
#include "scene/scene.h"
#include "scene/scene_json.h"
#include "study/study_file.h"

namespace penumbra {

// The most renders one study may expand to; larger sweeps are refused before
// expansion (split them into several studies).
inline constexpr long kMaxStudyRenders = 1000000;

// Where the scenes of a variant's jobs come from: a document (a scene file
// as read, shared by its variants, or a whole scene), the variant's
// overrides, and the origin that error messages name. A study of 10^6
// renders would otherwise hold 10^6 documents of a few KB each.
struct SceneSource {
  std::shared_ptr<const nlohmann::json> document;
  // Relative map files are from its folder; empty: a whole scene, canonical.
  std::string scene_file;
  std::vector<Override> overrides;  // the study's set and the variant's axis values
  std::string origin;               // "scenes/a.json (study s.json, variant v003)"
};

using OverrideList = std::shared_ptr<const std::vector<Override>>;

// The fields of a scene that a section's method sets. The reader takes each
// from its own keys (/representation, /terminator, /offset,
// /shape/tessellation), so the rest of a scene reads the same for every method.
struct MethodParts {
  Representation representation = Representation::kBump;
  TerminatorSettings terminator;
  OffsetSettings offset;
  std::optional<Tessellation> tessellation;
};

// What a job needs (ResourceEstimate without the explanation, which is only
// read when a plan is refused, at planning).
struct JobResources {
  double memory_bytes = 0.0;
  double output_bytes = 0.0;  // uncompressed EXR: the most the file can take
  double triangles = 0.0;     // of the mesh the render builds (0: none)
};
JobResources job_resources(const ResourceEstimate& estimate);

struct Job {
  std::size_t variant = 0;
  RendererKind renderer = RendererKind::kEvaluator;
  Representation representation = Representation::kBump;
  bool truth = false;  // the section's ground truth (displacement, or the analytic surface)
  std::string method;  // label: the method or offset, "none" or "analytic" for the truth
  std::string label;   // "v003-blender-bump-chiang2019": file names, logs
  std::string key;     // the cache key (RenderCache::assign_keys)
  JobResources resources;

  // The scene file and variant, for error messages.
  const std::string& origin() const;
  // The canonical scene: overrides applied, map files resolved, no name.
  nlohmann::json scene_json() const;
  // scene_json() with the scene file's name: what the reader reads (the
  // name enters Scene::name, which exports show, not the cache key).
  nlohmann::json document() const;
  // The scene as the reader gives it for scene_json().
  Scene scene() const;

  // A whole scene: `canonical` as scene_json() gives it, `scene` its reading.
  void set_scene(nlohmann::json canonical, Scene scene, std::string origin);
  // A planned scene: `source` with the method's and the renderer's overrides
  // (null: none), read as `shared` (what every job of the source and renderer
  // shares) with `parts`.
  void set_scene(std::shared_ptr<const SceneSource> source, OverrideList method_overrides,
                 OverrideList renderer_overrides, std::shared_ptr<const Scene> shared,
                 std::shared_ptr<const MethodParts> parts);
  // The scene with `settings` applied last (the ground truth's edge length
  // and samples, which no method part depends on): read again and its
  // resources estimated. `*shared` holds the shared part of jobs refined
  // alike (null: this one's is taken); `shared` null: none is kept, and the
  // scene is read again whenever asked for (checks, which render once).
  void refine(OverrideList settings, std::shared_ptr<const Scene>* shared);

 private:
  std::shared_ptr<const SceneSource> source_;
  std::array<OverrideList, 3> overrides_;  // the method's, the renderer's, refine's
  std::shared_ptr<const Scene> shared_;
  std::shared_ptr<const MethodParts> parts_;
};

struct Variant {
  SectionKind section = SectionKind::kBump;
  std::string id, scene, label;  // "v003", base scene name, "cylinder, A=0.02"
  std::vector<nlohmann::json> axis_values;
  std::vector<std::size_t> jobs;  // indices into Plan::jobs
};

// A renderer left out of a scene because it cannot render something in it.
struct SkippedRenderer {
  SectionKind section = SectionKind::kBump;
  RendererKind renderer = RendererKind::kEvaluator;
  std::string scene, why;
  // The variant it cannot render; "" when it cannot render the scene at all.
  std::string variant;
  bool operator==(const SkippedRenderer&) const = default;
};

struct Plan {
  std::vector<Variant> variants;
  std::vector<Job> jobs;
  std::vector<SkippedRenderer> skipped;

  // The job of variant `v` with this renderer and method label, or -1.
  long find(std::size_t v, RendererKind r, const std::string& method) const;
  // The ground truth of variant `v` for renderer `r`, or -1.
  long truth(std::size_t v, RendererKind r) const;
};

// Expands the study (bump section, then low-poly) and validates every scene
// and its resources: InputError before anything is written.
Plan plan_study(const Study& study, double max_memory_bytes);

// An axis value as figures and tables show it: a light direction
// (/light/direction, three numbers) as "azimuth A°, elevation E°"
// (study/light_angles.h), a number as %g, anything else as compact JSON.
std::string axis_value_text(const std::string& pointer, const nlohmann::json& value);

// Short ids of an axis's values, unique within the axis, for CSV cells, file
// names and compact labels: a compound value's own id; a number as %g; a
// light direction as "az<A>-el<E>" (whole degrees); a string or anything else
// as lower-case letters, digits and '-' ("v<k>" when that leaves nothing).
// A repeated id gets "-<k>" appended.
std::vector<std::string> axis_value_ids(const StudyAxis& axis);

// The key of the jobs that render one after another on one worker (a local
// worker, or one Slurm array task): the evaluator's displacement renders of
// one geometry (they share its mesh while the process holds it:
// evaluator/displaced_mesh.h; the checks of a truth, the variants that differ
// in light or material), and Blender's renders of one scene but for its
// light, material and method (a serving Blender keeps the mesh, and the
// material when that is the same too: harness/blender_render.py). "" for the
// rest.
std::string render_group_key(const Job& job);

}  // namespace penumbra
