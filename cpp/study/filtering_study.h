// The filtering section of a study: Schilling's Figs. 8-11 and the Ray
// Tracing Gems chapter's Fig. 12-6 (analysis/filtering.h) over each map and
// each run of the study file, written beside the study's report and listed
// in report.json's "filtering" array.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "study/sections.h"
#include "study/study_file.h"

namespace penumbra {

// One (map, run) of the section, measured or reused.
struct FilteringEntry {
  std::string map, run;
  std::string source;  // where the heights came from, in words
  // Relative to the study's output folder: FOLDER/filtering.json (the
  // experiment's full result, analysis/filtering.h) and FOLDER/filtering.csv.
  std::string folder;
  bool reused = false;  // read back: its inputs and code are those of the files there
  double seconds = 0.0;
  std::vector<std::string> findings;
};

// The section's step of the run (study/sections.h): measures every map x
// run into OUT/filtering/MAP/RUN/, reusing a folder whose key (the heights,
// the options, Penumbra's version and the digest of the experiment's code)
// is unchanged, with the run's parallelism; the log gets a line per entry.
// It renders nothing, so it adds no jobs to the render phase, and its
// results are JSON and CSV files kept by their own key file rather than
// images in the render cache.
std::vector<FilteringEntry> run_filtering_section(const FilteringSection& section,
                                                  const StepContext& context);

// report.json's "filtering": one object per entry (map, run, source, json,
// csv), or null without a section.
nlohmann::json filtering_report_json(const std::vector<FilteringEntry>& entries, bool has_section);

}  // namespace penumbra
