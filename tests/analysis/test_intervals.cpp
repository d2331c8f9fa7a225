// Intervals of a comparison's metrics (analysis/intervals.h): a render
// compared with itself has no error and an interval of zero width; and the
// default study's scenes give the same terminator RMSE, within each other's
// intervals, when the camera moves half a pixel or the resolution doubles.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "analysis/intervals.h"
#include "evaluator/evaluator.h"
#include "scene/scene_json.h"

namespace penumbra {
namespace {

const std::string kScenes = std::string(PENUMBRA_SOURCE_DIR) + "/scenes";

// The default study's settings (scenes/studies/default.json), light
// [-1, 0, -0.2], at `width` pixels, the camera moved by `shift` pixels of
// 128 along its right vector.
Image render_variant(const std::string& scene, const char* representation, const char* method,
                     double amplitude, int width, double shift) {
  std::vector<Override> o;
  for (const char* s : {"/camera/spp=16", "/camera/jitter=false", "/displacement/edge_length=0.006",
                        "/light/direction=[-1,0,-0.2]"})
    o.push_back(parse_override(s));
  const std::string file = kScenes + "/" + scene + ".json";
  const Scene base = load_scene(file, o);
  const Vec3 moved = base.camera.position + base.camera.right * (shift / 128.0);
  o.push_back({"/height/amplitude", amplitude});
  o.push_back({"/terminator/method", method});
  o.push_back({"/camera/width", width});
  o.push_back({"/camera/height", width});
  o.push_back({"/representation", representation});
  o.push_back({"/camera/position", {moved.x, moved.y, moved.z}});
  return render(load_scene(file, o));
}

TEST(Intervals, ARenderAgainstItselfHasZeroErrorAndAZeroWidthInterval) {
  const Image a = render_variant("sphere-weave", "bump", "none", 0.01, 32, 0.0);
  const ComparisonIntervals ci = comparison_intervals(a, a, 0.8);
  EXPECT_EQ(ci.rmse_terminator.low, 0.0);
  EXPECT_EQ(ci.rmse_terminator.high, 0.0);
  EXPECT_TRUE(ci.image_rmse.contains(0.0));
  EXPECT_EQ(ci.bands, kIntervalBands);
}

struct Measured {
  double terminator, view;
  Interval terminator_interval, view_interval;
};

Measured method_error(const std::string& scene, const char* method, double amplitude, int width,
                      double shift) {
  const Image truth = render_variant(scene, "displacement", "none", amplitude, width, shift);
  const Image bump = render_variant(scene, "bump", method, amplitude, width, shift);
  const double scale = 0.8;  // albedo 0.8, irradiance pi: albedo * E / pi
  const ComparisonIntervals ci = comparison_intervals(bump, truth, scale);
  return {compare_profiles(terminator_profile(bump, scale), terminator_profile(truth, scale))
              .rmse_terminator,
          view_metrics(view_error_profile(bump, truth, scale)).rmse_grazing, ci.rmse_terminator,
          ci.view_rmse_grazing};
}

// Both ways: each value inside the other's interval, for the terminator and
// the viewer metric, for raw bump and two methods at the largest amplitude
// (the hardest terminators) and raw bump at the default's middle one.
TEST(Intervals, HalfPixelShiftAndDoubleResolutionStayInsideEachOthersIntervals) {
  struct Case {
    const char* method;
    double amplitude;
  };
  for (const char* scene : {"cylinder-grating", "cylinder-weave", "sphere-grating", "sphere-weave"})
    for (const Case& c : {Case{"none", 0.01}, Case{"none", 0.02}, Case{"chiang2019", 0.02},
                          Case{"estevez2019-reciprocal", 0.02}}) {
      const Measured base = method_error(scene, c.method, c.amplitude, 128, 0.0);
      const Measured shifted = method_error(scene, c.method, c.amplitude, 128, 0.5);
      const Measured fine = method_error(scene, c.method, c.amplitude, 256, 0.0);
      for (const Measured* other : {&shifted, &fine}) {
        const std::string what = std::string(scene) + " " + c.method +
                                 " A=" + std::to_string(c.amplitude) +
                                 (other == &shifted ? " shifted" : " 256 px");
        EXPECT_TRUE(base.terminator_interval.contains(other->terminator))
            << what << ": terminator " << other->terminator << " outside ["
            << base.terminator_interval.low << ", " << base.terminator_interval.high << "]";
        EXPECT_TRUE(other->terminator_interval.contains(base.terminator))
            << what << ": terminator " << base.terminator << " outside ["
            << other->terminator_interval.low << ", " << other->terminator_interval.high << "]";
        EXPECT_TRUE(base.view_interval.contains(other->view))
            << what << ": view " << other->view << " outside [" << base.view_interval.low << ", "
            << base.view_interval.high << "]";
        EXPECT_TRUE(other->view_interval.contains(base.view))
            << what << ": view " << base.view << " outside [" << other->view_interval.low << ", "
            << other->view_interval.high << "]";
      }
    }
}

}  // namespace
}  // namespace penumbra
