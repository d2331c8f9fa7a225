// Small scenes for tests. A small render of the calibration sphere with its bumps (bump or
// displacement) and a byte comparison, for the tests that measure one render
// against another (analysis/measure.h, study/comparison_store.h).
#pragma once

#include <cstring>
#include <string>
#include <vector>

#include "evaluator/evaluator.h"
#include "scene/scene_json.h"

namespace penumbra {

inline const std::string kSmallSphere =
    std::string(PENUMBRA_SOURCE_DIR) + "/scenes/calibration/sphere.json";

// The unit sphere with its grating (scenes/sphere-grating.json) and
// --set overrides such as "/camera/spp=16", as the CLI reads them.
inline Scene sphere_grating_with(const std::vector<std::string>& sets) {
  std::vector<Override> overrides;
  for (const std::string& s : sets) overrides.push_back(parse_override(s));
  return load_scene(std::string(PENUMBRA_SOURCE_DIR) + "/scenes/sphere-grating.json", overrides);
}

// 32x32 at 4 spp, amplitude 0.02; `representation`: bump or displacement.
inline Image render_small_sphere(const char* representation) {
  return render(load_scene(kSmallSphere, {parse_override("/camera/width=32"),
                                          parse_override("/camera/height=32"),
                                          parse_override("/camera/spp=4"),
                                          parse_override("/height/amplitude=0.02"),
                                          parse_override("/displacement/edge_length=0.02"),
                                          {"/representation", representation}}));
}

// The same bits: metrics are plain structs of numbers (NaN == NaN here).
template <typename T>
bool same_bytes(const T& a, const T& b) {
  return std::memcmp(&a, &b, sizeof(T)) == 0;
}

}  // namespace penumbra
