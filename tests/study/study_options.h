// The options the study tests run with: two jobs into a folder, no figures,
// and optionally the log lines that start with `prefix` collected in *log.
#pragma once

#include <string>
#include <vector>

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

}  // namespace penumbra
