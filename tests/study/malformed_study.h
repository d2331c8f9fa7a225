// Study files that must be refused: each case edits a copy of a good study
// (or one of its sections) and names the JSON pointer and the words the
// error must carry; load_study must throw an InputError naming the file.
#pragma once

#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "study/study_file.h"
#include "util/strict_json.h"

namespace penumbra {

struct MalformedCase {
  std::function<void(nlohmann::json&)> edit;
  std::string pointer, words;
};

// `section` "" edits the whole document; `write` saves it and returns the path.
inline void expect_refused(const nlohmann::json& good, const std::string& section,
                           const std::vector<MalformedCase>& cases,
                           const std::function<std::string(const nlohmann::json&)>& write) {
  for (const MalformedCase& c : cases) {
    nlohmann::json j = good;
    c.edit(section.empty() ? j : j[section]);
    const std::string file = write(j);
    try {
      load_study(file);
      ADD_FAILURE() << "accepted: " << j.dump();
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), file);
      EXPECT_EQ(e.pointer(), c.pointer) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.words), std::string::npos) << e.what();
    }
  }
}

}  // namespace penumbra
