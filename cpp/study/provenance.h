// Where a report's numbers come from: the program (version, git commit),
// when, on what machine, with which renderer versions, and the exact study
// file (its SHA-256). report.json and report.html carry it; the figures do
// not depend on it (study/figures.cpp leaves it out of their input digest),
// so a warm run that only changes the date keeps them.
#pragma once

#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include "renderers/registry.h"

namespace penumbra {

struct Provenance {
  std::string version;  // kPenumbraVersion
  std::string commit;   // 40 hex digits, or "not from a git checkout"
  int dirty = -1;       // 1: built from a changed tree; 0: not; -1: unknown
  std::string date;     // UTC, ISO 8601, when the report was written (or SOURCE_DATE_EPOCH)
  std::string cpu;      // /proc/cpuinfo's model name, "unknown" elsewhere
  unsigned cores = 0;   // std::thread::hardware_concurrency
  std::string system;   // uname: "Linux 6.1.0-18-amd64 x86_64"
  std::map<RendererKind, std::string> renderers;  // probed versions
  std::string study_sha256;
};

Provenance collect_provenance(const std::string& study_file,
                              const std::map<RendererKind, std::string>& renderer_versions);

nlohmann::json provenance_json(const Provenance& p);

// A JSON file's text without the keys that change every run and no output
// depends on (report.json's provenance, fit.json's seconds): what digests
// of a study's outputs hash. Text that is not a JSON object comes back as it is.
std::string without_run_keys(const std::string& text);

}  // namespace penumbra
