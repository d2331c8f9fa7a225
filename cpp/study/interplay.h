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

#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/intervals.h"
#include "analysis/metrics.h"
#include "study/cache.h"
#include "study/study_file.h"

namespace penumbra {

struct Renderers;  // study/rendering.h

// Reads /interplay of the study file `file` (InputError naming the pointer).
InterplaySection read_interplay_section(const nlohmann::json& section, const std::string& file,
                                        const std::string& base);

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

// Bakes the map into OUT/interplay/map.exr, renders what the cache lacks
// (the evaluator, one render at a time with `threads` threads, through
// render_into_cache like the study's other renders), compares. `log` gets
// progress lines.
InterplayResult run_interplay_section(const InterplaySection& section, const std::string& out_dir,
                                      const RenderCache& cache, const Renderers& renderers,
                                      int threads,
                                      const std::function<void(const std::string&)>& log);

// report.json's "interplay", or null without a section.
nlohmann::json interplay_report_json(const InterplaySection* section,
                                     const InterplayResult* result);

}  // namespace penumbra
