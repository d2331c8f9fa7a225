// Intervals of a comparison's metrics (analysis/intervals.h): a render
// compared with itself has no error and an interval of zero width; and the
// default study's scenes give the same terminator RMSE, within each other's
// intervals, when the camera moves half a pixel or the resolution doubles.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "analysis/intervals.h"
#include "render/evaluator.h"
#include "scene/scene_json.h"

namespace penumbra {
namespace {

const std::string kScenes = std::string(PENUMBRA_SOURCE_DIR) + "/scenes";

// The default study's settings (scenes/studies/default.json), amplitude
// 0.01, light [-1, 0, -0.2], at `width` pixels, the camera moved by `shift`
// scene units along its right vector.
Image render_variant(const std::string& scene, const char* representation, int width,
                     double shift) {
  std::vector<Override> o;
  for (const char* s :
       {"/camera/spp=16", "/camera/jitter=false", "/displacement/edge_length=0.006",
        "/height/amplitude=0.01", "/light/direction=[-1,0,-0.2]", "/terminator/method=none"})
    o.push_back(parse_override(s));
  o.push_back({"/camera/width", width});
  o.push_back({"/camera/height", width});
  o.push_back({"/representation", representation});
  o.push_back({"/camera/position", {shift, 0.0, -5.0}});
  return render(load_scene(kScenes + "/" + scene + ".json", o));
}

TEST(Intervals, ARenderAgainstItselfHasZeroErrorAndAZeroWidthInterval) {
  const Image a = render_variant("sphere-weave", "bump", 32, 0.0);
  const ComparisonIntervals ci = comparison_intervals(a, a, 0.8);
  EXPECT_EQ(ci.rmse_terminator.low, 0.0);
  EXPECT_EQ(ci.rmse_terminator.high, 0.0);
  EXPECT_TRUE(ci.image_rmse.contains(0.0));
  EXPECT_EQ(ci.bands, kIntervalBands);
}

struct Measured {
  double value;
  Interval interval;
};

Measured raw_bump_error(const std::string& scene, int width, double shift) {
  const Image truth = render_variant(scene, "displacement", width, shift);
  const Image bump = render_variant(scene, "bump", width, shift);
  const double scale = 0.8;  // albedo 0.8, irradiance pi: albedo * E / pi
  return {compare_profiles(terminator_profile(bump, scale), terminator_profile(truth, scale))
              .rmse_terminator,
          comparison_intervals(bump, truth, scale).rmse_terminator};
}

// Half a pixel is 2.5 / 128 / 2 scene units (the camera's right vector spans
// 2.5 units). Both ways: each value inside the other's interval.
TEST(Intervals, HalfPixelShiftAndDoubleResolutionStayInsideEachOthersIntervals) {
  for (const char* scene :
       {"cylinder-grating", "cylinder-weave", "sphere-grating", "sphere-weave"}) {
    const Measured base = raw_bump_error(scene, 128, 0.0);
    const Measured shifted = raw_bump_error(scene, 128, 2.5 / 256.0);
    const Measured fine = raw_bump_error(scene, 256, 0.0);
    for (const Measured& other : {shifted, fine}) {
      EXPECT_TRUE(base.interval.contains(other.value))
          << scene << ": " << other.value << " outside [" << base.interval.low << ", "
          << base.interval.high << "]";
      EXPECT_TRUE(other.interval.contains(base.value))
          << scene << ": " << base.value << " outside [" << other.interval.low << ", "
          << other.interval.high << "]";
    }
  }
}

}  // namespace
}  // namespace penumbra
