// A study expanded into typed jobs: one render each (a scene, a renderer),
// grouped by variant (a base scene with one combination of axis values).
// Every scene is parsed and its resources checked here, before anything is
// written or rendered.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "renderers/renderers.h"
#include "scene/scene.h"
#include "study/study_file.h"

namespace penumbra {

// The most renders one study may expand to; larger sweeps are refused before
// expansion (split them into several studies).
inline constexpr long kMaxStudyRenders = 1000000;

struct Job {
  std::size_t variant = 0;
  RendererKind renderer = RendererKind::kEvaluator;
  Representation representation = Representation::kBump;
  bool truth = false;         // the section's ground truth (displacement, or the analytic surface)
  std::string method;         // label: the method or offset, "none" or "analytic" for the truth
  nlohmann::json scene_json;  // canonical: overrides applied, no name
  Scene scene;
  std::string label;   // "v003-blender-bump-chiang2019": file names, logs
  std::string origin;  // the scene file and variant, for error messages
  std::string key;     // the cache key (RenderCache::assign_keys)
  ResourceEstimate resources;
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
