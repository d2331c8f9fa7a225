// The terminator-interplay section of a study: a scene's analytic heights
// baked into an image height map over its shape, rendered in bump through a
// roughness filter at fixed pyramid levels (a surface seen from farther and
// farther away) with each terminator method, and compared with the
// displacement of the same map. It asks whether a method that softens the
// terminator from the shading normal's deviation keeps working when the
// normal is filtered (README, "Filtered rendering").
//
// JSON: "interplay": {"scene": FILE, "size": 1024, "filter": "pixar2014",
// "levels": [null, 2, 4, 6], "methods": ["none", "estevez2019"], "set": {...}}
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/intervals.h"
#include "analysis/metrics.h"
#include "study/plan.h"
#include "study/sections.h"
#include "study/study_file.h"

namespace penumbra {

struct InterplayRow {
  std::optional<int> level;
  std::string method;
  std::string key;  // the render's cache key
  ProfileMetrics profile;
  ComparisonIntervals intervals;
};

struct InterplayResult {
  std::string map_file;  // relative to the study folder
  int map_width = 0, map_height = 0;
  std::string map_digest;
  double edge_length = 0.0;  // of the truth's grid, scene units
  std::string truth_key;
  // The truth against one at half the edge length: terminator RMSE between
  // their profiles (fraction of albedo*E/pi) and its interval.
  double truth_change = 0.0;
  Interval truth_change_interval;
  std::vector<InterplayRow> rows;  // level-major, then method
  std::size_t rendered = 0, reused = 0;
  std::vector<std::string> findings;
};

// The section's part of the run's render phase: its map baked into
// OUT/interplay/map.exr, and the evaluator jobs that render with the
// study's own (study/sections.h): the truth (the map's displacement), the
// truth at half its edge length, then one bump render per level and method,
// level-major. Keyed; `result` holds what is known before they render.
struct InterplayJobs {
  std::vector<Job> jobs;
  InterplayResult result;
};
InterplayJobs plan_interplay_section(const InterplaySection& section, const StepContext& context);

// Measures the section's renders, in the order of `planned.jobs`, against
// the truth. Throws RendererError with the error of a render that failed.
InterplayResult measure_interplay_section(const InterplaySection& section,
                                          const InterplayJobs& planned,
                                          const SectionRenders& renders,
                                          const StepContext& context);

// report.json's "interplay", or null without a section.
nlohmann::json interplay_report_json(const InterplaySection* section,
                                     const InterplayResult* result);

}  // namespace penumbra
