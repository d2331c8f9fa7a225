// What the renderer tests share (tests/renderers/ and each external
// renderer's folder below it): a fixture with fakes, and the scenes they
// render. POV-Ray and Blender must be installed (the quick start and CI
// install them): a missing renderer fails these tests, it is never skipped
// as a pass.
#pragma once

#include <sys/stat.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "image/image_io.h"
#include "renderers/renderers.h"
#include "scene/scene_json.h"
#include "temp_dir_test.h"
#include "util/strict_json.h"

// In a namespace of their own, as are the tests that use them:
// study/rendering.h has a penumbra::Renderers too.
namespace penumbra::renderer_test {

namespace fs = std::filesystem;
using nlohmann::json;

inline const std::string kSource = PENUMBRA_SOURCE_DIR;

class Renderers : public TempDirTest {
 protected:
  // A shell script standing in for a renderer.
  std::string fake(const std::string& name, const std::string& body) const {
    const std::string p = path(name);
    std::ofstream(p) << "#!/bin/sh\n" << body << "\n";
    ::chmod(p.c_str(), 0755);
    return p;
  }
  // Settings for a fake Blender at path("blender") (the test writes it) and
  // path("good.exr"), an image of hostile_scene()'s size for it to answer with.
  RenderSettings fake_serving_blender_settings() const {
    Image good;
    good.width = good.height = 32;
    good.channels = {"R", "G", "B", "A"};
    good.pixels.assign(32 * 32 * 4, 0.5f);
    write_exr(good, path("good.exr"));
    RenderSettings settings;
    settings.log_path = path("render.log");
    settings.timeout_s = 30;
    settings.executable = path("blender");
    return settings;
  }
  std::vector<std::string> files() const {
    std::vector<std::string> found;
    for (const auto& e : std::filesystem::directory_iterator(dir_))
      found.push_back(e.path().filename().string());
    std::sort(found.begin(), found.end());
    return found;
  }
};

inline std::string read_text(const std::string& file) {
  std::ifstream in(file);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

inline nlohmann::json calibration_scene(const std::string& shape) {
  return read_json_file(kSource + "/scenes/calibration/" + shape + ".json");
}

// A scene whose name tries every way out of a comment or a string.
inline Scene hostile_scene() {
  nlohmann::json doc = calibration_scene("cylinder");
  doc["name"] =
      "x\" }\n#include \"/etc/passwd\"\n#declare Evil = 1; // ';\n__import__('os').system('id')";
  doc["representation"] = "bump";
  doc["camera"]["width"] = 32;
  doc["camera"]["height"] = 32;
  return scene_from_json(doc, "<hostile>");
}

// The 16-segment smooth-shaded UV sphere of scenes/lowpoly, shrunk for tests.
inline Scene lowpoly_sphere(std::vector<std::string> overrides) {
  std::vector<Override> parsed;
  for (const char* o : {"/camera/width=96", "/camera/height=96"})
    parsed.push_back(parse_override(o));
  for (const std::string& o : overrides) parsed.push_back(parse_override(o));
  return load_scene(kSource + "/scenes/lowpoly/sphere.json", parsed);
}

}  // namespace penumbra::renderer_test
