// The filtering section of a study: Schilling's Figs. 8-11 and the Ray
// Tracing Gems chapter's Fig. 12-6 (analysis/filtering.h) over each map and
// each run of the study file, written beside the study's report and listed
// in report.json's "filtering" array.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "study/study_file.h"

namespace penumbra {

// Reads /filtering of the study file `file` (InputError naming the pointer);
// scene and map paths resolve against `base`, the study file's folder.
FilteringSection read_filtering_section(const nlohmann::json& section, const std::string& file,
                                        const std::string& base);

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

// Measures every map x run into OUT/filtering/MAP/RUN/, reusing a folder
// whose key (the heights, the options, Penumbra's version and the digest of
// the experiment's code) is unchanged. `log` gets a line per entry.
std::vector<FilteringEntry> run_filtering_section(
    const FilteringSection& section, const std::string& out_dir, int jobs,
    const std::function<void(const std::string&)>& log);

// report.json's "filtering": one object per entry (map, run, source, json,
// csv), or null without a section.
nlohmann::json filtering_report_json(const std::vector<FilteringEntry>& entries, bool has_section);

}  // namespace penumbra
