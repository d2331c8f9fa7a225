// The files a study leaves for people and programs: report.json (every
// render, comparison and ranking; the figures are drawn from it alone;
// described by harness/report.schema.json), metrics.csv (bump comparisons)
// and lowpoly.csv (low-poly comparisons), each CSV from one column list
// documented in harness/csv-columns.json. tests/study/test_report_files.py
// holds the files to both, so a new key or column needs its documentation.
#pragma once

#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "study/compare.h"
#include "study/convergence.h"
#include "study/filtering_study.h"
#include "study/interplay.h"
#include "study/plan.h"
#include "study/study_file.h"

namespace penumbra {

inline constexpr int kReportFormatVersion = 1;

// What the report needs besides the plan and the comparisons.
struct ReportInputs {
  const Study& study;
  const Plan& plan;
  const Comparisons& comparisons;
  const std::map<RendererKind, std::string>& versions;  // probed renderers only
  const std::vector<std::string>& errors;               // per job; "" when done
  const std::vector<char>& done;                        // per job
  const std::vector<VariantConvergence>& convergence;   // bump variants with an evaluator truth
  const std::vector<FilteringEntry>& filtering;         // the filtering section's entries
  const InterplayResult* interplay;                     // null without an interplay section
};

// Writes report.json, metrics.csv and (with a low-poly section) lowpoly.csv
// into `folder`.
void write_report_files(const ReportInputs& in, const std::string& folder);

// The longest string `penumbra report` takes from a report.json: the
// figures lay text out in time that grows faster than its length, and no
// label, headline or message Penumbra writes comes near it.
inline constexpr std::size_t kMaxReportString = 64 * 1024;

// Reads `path` as `penumbra report` takes it: strict JSON whose strings are
// at most kMaxReportString bytes; InputError naming the file and the
// pointer otherwise.
nlohmann::json read_report_json(const std::string& path);

// Removes what write_report_files writes: a run stopped before its figures
// are drawn leaves the folder as one stopped while rendering does.
void remove_report_files(const std::string& folder);

}  // namespace penumbra
