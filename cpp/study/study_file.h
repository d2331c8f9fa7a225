// The study file: base scenes x sweep axes x methods x renderers, read
// strictly (unknown keys, wrong types, unknown methods or renderers are
// InputErrors naming the file and the JSON pointer). See README, "Writing a
// study".
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/filtering.h"
#include "renderers/registry.h"

namespace penumbra {

inline constexpr int kStudyFormatVersion = 1;

// One sweep axis: a scene value by JSON pointer and the values it takes; or
// a compound axis, whose values each set several pointers together (a
// glossy material with the lobes a factor scales, say).
struct StudyAxis {
  // The JSON pointer; for a compound axis its name (no leading '/'), which
  // plots, CSV columns and report.json use in its place.
  std::string pointer;
  std::string label;  // for plots and tables; default: the pointer
  // The values; for a compound axis each value's label.
  std::vector<nlohmann::json> values;
  // Compound axes only: per value, the (pointer, value) pairs it sets.
  std::vector<std::vector<std::pair<std::string, nlohmann::json>>> sets;
  // Compound axes only: per value, its short id ("lambert"; "" when the
  // study gives none): CSV cells and file names (plan.h axis_value_ids).
  std::vector<std::string> ids;
};

// A method as the study names it: an id and optional parameter values.
struct StudyMethod {
  std::string id;
  nlohmann::json parameters;  // object or null
  std::string label;          // "shading-offset(s=0.3)"
};

// A metric drawn over two axes (indices into the bump section's axes).
struct StudyPlot {
  std::string metric;  // "profile.rmse_terminator", "image.ssim", ...
  int x = 0, y = 1;
  std::string kind = "contour";  // or "heatmap"
  std::string renderer = "evaluator";
};

// The two kinds of section differ in what varies and what counts as truth:
//   bump      the terminator method on a bump-mapped scene; truth: the same
//             scene displaced (representation "displacement", method none);
//   low-poly  the shadow-ray offset on a tessellated scene; truth: the same
//             scene's analytic, untessellated surface.
enum class SectionKind { kBump, kLowPoly };

// Base scenes x axis values x renderers x (truth + each method it offers).
struct Section {
  SectionKind kind = SectionKind::kBump;
  std::vector<std::string> scenes;                // paths, resolved against the study file's folder
  nlohmann::json set = nlohmann::json::object();  // pointer -> value, for every scene
  std::vector<StudyAxis> axes;
  std::vector<StudyMethod> methods;  // terminator methods (bump), offset methods (low-poly)
  std::vector<RendererKind> renderers;
  int convergence_axis = -1;  // low-poly: index into axes of the tessellation level
};

// How far the evaluator's ground truth of each bump variant is refined
// (study/convergence.h). JSON: "ground_truth": {"tolerance": 0.001,
// "max_edge_refinements": 2, "max_spp_refinements": 3}.
struct GroundTruthSettings {
  // Largest accepted change, fraction of albedo*E/pi; (0, 1].
  double tolerance = 0.001;
  // Check renders go down to edge_length / 2^n and up to spp * 4^m; each in
  // [0, 5]. Edge checks cost 4x the memory per step (a 0.0015 sphere mesh
  // needs 2.6 GB), samples only time. 0 checks nothing along that setting,
  // and every truth is reported unconverged.
  int max_edge_refinements = 2;
  int max_spp_refinements = 3;
};

// The bump-map filtering experiment (analysis/filtering.h) as a study
// section: each map x each run. JSON: "filtering": {"maps": [...], "runs":
// [...], "alphas", "filters", "max_level", "footprints", "view_deg",
// "sweep_step_deg", "seed"}; README, "The filtering study".
struct FilteringMapSpec {
  std::string name;  // plain name: the report's label and the output folder
  // Either an analytic scene's /height baked over the plane [0, extent)^2
  // at size x size texels (image/bump_maps.h bake_height_map; heights in
  // scene units), or a height map file with its channel and scales.
  std::string bake_scene;  // resolved against the study file's folder
  int size = 1024;
  double extent = 1.0;  // scene units
  std::string file, channel;
  double texel_size = 0.0;  // scene units per texel; 0: 1 / width (file) or extent / size (bake)
  double height_scale = 1.0;
  MapEdge edge = MapEdge::kClamp;  // default: clamp for a bake, wrap for a file
};
struct FilteringRunSpec {
  std::string name;  // plain name
  FilteringOptions::Lookup lookup = FilteringOptions::Lookup::kBox;
  double shift = 0.0;  // pixels, [0, 1)
  bool random_shift = false;
};
struct FilteringSection {
  std::vector<FilteringMapSpec> maps;
  std::vector<FilteringRunSpec> runs;  // default: one "box" run, aligned
  FilteringOptions options;            // lookup, shift and jobs set per run
};

// The terminator-interplay section (study/interplay.h): a scene's analytic
// heights baked into a map, rendered in bump through a roughness filter at
// fixed levels with each method, against the map's displacement.
struct InterplaySection {
  std::string scene;                 // resolved against the study file's folder; analytic /height
  int size = 1024;                   // texels around the shape (penumbra bake --on shape --size)
  std::string filter = "pixar2014";  // roughness filter id
  std::vector<std::optional<int>> levels;         // nullopt: unfiltered; else a fixed level
  std::vector<std::string> methods;               // terminator method ids
  nlohmann::json set = nlohmann::json::object();  // pointer -> value, applied to the scene
};

struct Study {
  std::string name;
  std::string file;           // as given (error messages name it so)
  std::string absolute_file;  // the report's: the same however `file` was spelled
  Section bump;               // no scenes: a low-poly-only or filtering-only study
  std::optional<Section> lowpoly;
  std::optional<FilteringSection> filtering;
  std::optional<InterplaySection> interplay;
  int blender_spp = 32;
  GroundTruthSettings ground_truth;
  std::vector<StudyPlot> plots;
  // The methods (labels) the figures show beside raw bump and the leaders
  // (JSON "figures": {"methods": [...]}); empty: the automatic pick.
  std::vector<std::string> figure_methods;
  // What the reader changed or assumed that the user must hear (a raw-bump
  // baseline added, say): printed by `run` and shown by the report.
  std::vector<std::string> notices;
};

Study load_study(const std::string& path);

// Renders the study expands to, counted without expanding it.
double planned_render_count(const Study& study);

}  // namespace penumbra
