// Reading scenes from JSON: strict (unknown keys are errors), with errors that
// name the file, the JSON pointer and what was expected.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "scene/scene.h"

namespace penumbra {

// Bad input. what() is one line: "FILE: /json/pointer: expected ..., got ...".
class InputError : public std::runtime_error {
 public:
  InputError(const std::string& file, const std::string& pointer, const std::string& message);
  const std::string& file() const { return file_; }
  const std::string& pointer() const { return pointer_; }

 private:
  std::string file_, pointer_;
};

// "POINTER=VALUE" as given to --set: VALUE is JSON, or a bare string.
struct Override {
  std::string pointer;
  nlohmann::json value;
};
Override parse_override(const std::string& text);

// Applies overrides in order; `origin` names the source in errors.
void apply_overrides(nlohmann::json& document, const std::vector<Override>& overrides,
                     const std::string& origin);

nlohmann::json read_json_file(const std::string& path);
// Validates and converts. `origin` is the file name used in error messages.
Scene scene_from_json(const nlohmann::json& document, const std::string& origin);
Scene load_scene(const std::string& path, const std::vector<Override>& overrides = {});

// Names used in JSON and reports.
const char* to_string(Representation r);
const char* to_string(HeightFamily f);

}  // namespace penumbra
