// The options the study tests run with: two jobs into a folder, no figures,
// and optionally the log lines that start with `prefix` collected in *log.
#pragma once

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "study/study.h"

namespace penumbra {

inline StudyOptions test_study_options(const std::string& output_dir,
                                       std::vector<std::string>* log = nullptr,
                                       const std::string& prefix = "") {
  StudyOptions o;
  o.output_dir = output_dir;
  o.figures = false;
  o.parallelism = resolve_parallelism(2);
  if (log)
    o.log = [log, prefix](const std::string& line) {
      if (line.rfind(prefix, 0) == 0) log->push_back(line);
    };
  return o;
}

// A study folder's report.json without its provenance (the date it was
// written, the machine): what two runs of one study must agree on, byte for
// byte.
inline std::string report_without_provenance(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  nlohmann::json doc = nlohmann::json::parse(text.str(), nullptr, false);
  if (doc.is_discarded()) return text.str();
  doc.erase("provenance");
  return doc.dump(1);
}

}  // namespace penumbra
