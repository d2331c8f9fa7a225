// What the renderer tests share (tests/renderers/ and each external
// renderer's folder below it): a fixture with fakes, and the scenes they
// render. POV-Ray and Blender must be installed (the quick start and CI
// install them): a missing renderer fails these tests, it is never skipped
// as a pass.
#pragma once

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/metrics.h"
#include "core/tessellation.h"
#include "image/image_io.h"
#include "mesh_files.h"
#include "renderers/external/external.h"
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

// A mesh shape read from a file the test writes: the calibration sphere's
// 24-segment UV tessellation as a PLY (scenes/calibration/sphere.json, its
// weave at A = 0.01), 96 x 96 px at 4 samples on the strata's centres, its
// truth split at edge length 0.02 (about 0.2 M triangles: what another
// renderer loads in seconds). `representation`: smooth, bump or displacement.
inline json mesh_sphere_doc(const std::string& ply, const std::string& representation,
                            const std::vector<std::string>& overrides = {}) {
  json doc = calibration_scene("sphere");
  const Scene analytic = scene_from_json(doc, "calibration sphere");
  Tessellation t;
  t.segments = 24;
  write_ply(tessellate(analytic.shape, t), ply);
  doc["shape"] = {{"type", "mesh"}, {"file", ply}};
  doc["representation"] = representation;
  doc["displacement"] = {{"edge_length", 0.02}};
  doc["camera"]["width"] = doc["camera"]["height"] = 96;
  doc["camera"]["spp"] = 4;
  std::vector<Override> parsed;
  for (const std::string& o : overrides) parsed.push_back(parse_override(o));
  apply_overrides(doc, parsed, "mesh sphere");
  return doc;
}
inline Scene mesh_sphere(const std::string& ply, const std::string& representation,
                         const std::vector<std::string>& overrides = {}) {
  return scene_from_json(mesh_sphere_doc(ply, representation, overrides), "mesh sphere");
}

// The triangles and normals `scene` exports as its truth
// (external::mesh_shape_triangles), written to `ply` and read back as a
// smooth-shaded mesh shape with offset `none`: what POV-Ray and Cycles are
// given, rendered by the evaluator as they render it (shading normals
// interpolated, shadow rays from the flat triangles).
// The terminator-profile RMSE of `test` against `reference` (fraction of
// albedo*E/pi), printed with `what`; the profiles must share 100 bins or more.
inline double mesh_profile_rmse(const Image& test, const Image& reference, double scale,
                                const char* what) {
  const ProfileMetrics m =
      compare_profiles(terminator_profile(test, scale), terminator_profile(reference, scale));
  std::printf(
      "[ mesh     ] %s: profile RMSE terminator %.6f overall %.6f, terminator at %.3f deg "
      "(reference %.3f)\n",
      what, m.rmse_terminator, m.rmse_overall, m.position, m.reference_position);
  EXPECT_GE(m.common_bins, 100u) << what;
  return m.rmse_terminator;
}

// `image` with `from`'s analysis channels: a mesh's analysis angles are
// measured from its own interpolated normals, so the exported truth read
// back as a smooth mesh (above) is binned by the truth's angles, not by its
// bumpy normals', to be compared with the truth.
inline Image with_analysis_of(Image image, const Image& from) {
  for (const char* name : {"analysis.theta", "analysis.view"}) {
    const int to = image.channel_index(name), source = from.channel_index(name);
    if (to < 0 || source < 0) continue;
    for (int y = 0; y < image.height; ++y)
      for (int x = 0; x < image.width; ++x) image.at(x, y, to) = from.at(x, y, source);
  }
  return image;
}

inline Scene exported_truth_as_mesh(json doc, const std::string& ply) {
  const Scene scene = scene_from_json(doc, "mesh sphere");
  write_ply(external::mesh_shape_triangles(scene, /*truth=*/true), ply);
  doc["shape"] = {{"type", "mesh"}, {"file", ply}};
  doc["representation"] = "smooth";
  doc["offset"] = {{"method", "none"}};
  return scene_from_json(doc, "exported truth");
}

}  // namespace penumbra::renderer_test
