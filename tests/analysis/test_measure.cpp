// measure() (analysis/measure.h): the metrics it gives are those of the
// functions it calls, bit for bit, whatever else is asked for; an image
// without analysis channels borrows the other's; and the coverage of an image
// without an A channel comes from the mask, then the threshold, or is refused.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "analysis/measure.h"
#include "small_sphere.h"

namespace penumbra {
namespace {

// Only R, G, B (and A where `alpha`): an image as another renderer gives it.
Image colour_only(const Image& image, bool alpha) {
  Image out;
  out.width = image.width, out.height = image.height;
  out.channels = {"R", "G", "B"};
  if (alpha) out.channels.push_back("A");
  const std::size_t nc = out.channels.size();
  out.pixels.resize(std::size_t(out.width) * out.height * nc);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      for (std::size_t c = 0; c < nc; ++c)
        out.pixels[(std::size_t(y) * out.width + x) * nc + c] =
            image.at(x, y, image.channel_index(out.channels[c]));
  return out;
}

// `geometry` with the R, G, B and A of `colour`: one render's pixels on the
// other's analysis channels.
Image rgba_on(const Image& colour, const Image& geometry) {
  Image out = geometry;
  for (const char* name : {"R", "G", "B", "A"}) {
    const int from = colour.channel_index(name), to = out.channel_index(name);
    for (int y = 0; y < out.height; ++y)
      for (int x = 0; x < out.width; ++x) out.at(x, y, to) = colour.at(x, y, from);
  }
  return out;
}

class Measure : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    bump_ = new Image(render_small_sphere("bump"));
    truth_ = new Image(render_small_sphere("displacement"));
    scale_ = radiance_scale(load_scene(kSmallSphere));
  }
  static void TearDownTestSuite() {
    delete bump_;
    delete truth_;
  }
  static MeasureOptions options() {
    MeasureOptions o;
    o.scale = scale_;
    return o;
  }
  static const Image* bump_;
  static const Image* truth_;
  static double scale_;
};
const Image* Measure::bump_ = nullptr;
const Image* Measure::truth_ = nullptr;
double Measure::scale_ = 0.0;

TEST_F(Measure, GivesTheMetricsOfTheFunctionsItCallsBitForBit) {
  MeasureOptions o = options();
  o.shadows = true;
  const Measurement m = measure(*bump_, *truth_, o);
  EXPECT_EQ(m.profile_missing, ProfileMissing::kNo);
  const ProfileMetrics profile =
      compare_profiles(terminator_profile(*bump_, scale_), terminator_profile(*truth_, scale_));
  EXPECT_TRUE(same_bytes(m.profile, profile));
  EXPECT_GT(m.profile.rmse_terminator, 0.0);  // a real difference, not two zeros
  EXPECT_TRUE(same_bytes(m.image, compare_images(*bump_, *truth_)));
  EXPECT_TRUE(same_bytes(m.view, view_metrics(view_error_profile(*bump_, *truth_, scale_))));
  EXPECT_TRUE(same_bytes(m.intervals, comparison_intervals(*bump_, *truth_, scale_)));
  ASSERT_TRUE(m.shadow.has_value());
  EXPECT_TRUE(same_bytes(*m.shadow, compare_shadows(*bump_, *truth_, scale_)));
}

TEST_F(Measure, WhatIsNotAskedForStaysZeroAndTheRestIsUnchanged) {
  MeasureOptions o = options();
  o.intervals = o.image = o.view = false;
  const Measurement profile_only = measure(*bump_, *truth_, o);
  const Measurement full = measure(*bump_, *truth_, options());
  EXPECT_TRUE(same_bytes(profile_only.profile, full.profile));
  EXPECT_TRUE(same_bytes(profile_only.image, ImageMetrics{}));
  EXPECT_TRUE(same_bytes(profile_only.view, ViewMetrics{}));
  EXPECT_TRUE(same_bytes(profile_only.intervals, ComparisonIntervals{}));
  EXPECT_FALSE(full.shadow.has_value());
}

TEST_F(Measure, AnImageWithoutAnalysisChannelsBorrowsTheOthers) {
  // What borrowing means: the other render's analysis channels (theta, view)
  // under this one's R, G, B and A.
  const Measurement borrowed = measure(colour_only(*bump_, true), *truth_, options());
  const Measurement relit = measure(rgba_on(*bump_, *truth_), *truth_, options());
  EXPECT_EQ(borrowed.profile_missing, ProfileMissing::kNo);
  EXPECT_TRUE(same_bytes(borrowed.profile, relit.profile));
  EXPECT_TRUE(same_bytes(borrowed.intervals, relit.intervals));
  EXPECT_TRUE(same_bytes(borrowed.view, relit.view));
  const Measurement reversed = measure(*bump_, colour_only(*truth_, true), options());
  EXPECT_TRUE(
      same_bytes(reversed.profile, measure(*bump_, rgba_on(*truth_, *bump_), options()).profile));
  EXPECT_EQ(
      measure(colour_only(*bump_, true), colour_only(*truth_, true), options()).profile_missing,
      ProfileMissing::kNoTheta);
}

TEST_F(Measure, CoverageComesFromTheAlphaChannelTheMaskThenTheThreshold) {
  const Image bare = colour_only(*bump_, false);
  MeasureOptions o = options();
  EXPECT_EQ(coverage_source(*bump_, o), CoverageSource::kAlpha);
  EXPECT_EQ(coverage_source(bare, o), CoverageSource::kMissing);
  EXPECT_THROW(measure(bare, *truth_, o), std::invalid_argument);
  o.every_pixel = true;
  EXPECT_EQ(coverage_source(bare, o), CoverageSource::kEveryPixel);
  EXPECT_EQ(measure(bare, *truth_, o).profile_missing, ProfileMissing::kNoCoverage);
  o.threshold = 0.05;
  EXPECT_EQ(coverage_source(bare, o), CoverageSource::kThreshold);
  o.mask = truth_;  // its A channel
  EXPECT_EQ(coverage_source(bare, o), CoverageSource::kMask);
  // With the bump's own coverage as the mask, the bare bump is the bump's
  // R, G, B and A (with the truth's analysis channels, as it has none).
  o.mask = bump_;
  o.every_pixel = false;
  const Measurement masked = measure(bare, *truth_, o);
  EXPECT_EQ(masked.test_coverage, CoverageSource::kMask);
  EXPECT_TRUE(
      same_bytes(masked.profile, measure(colour_only(*bump_, true), *truth_, options()).profile));
  MeasureOptions no_scale;
  no_scale.threshold = 0.05;
  EXPECT_EQ(coverage_source(bare, no_scale), CoverageSource::kNoScale);
}

TEST_F(Measure, AThresholdCoversThePixelsAtLeastThatBright) {
  MeasureOptions o = options();
  o.threshold = 0.5;
  const Image bare = colour_only(*bump_, false);
  const Image difference = difference_image(bare, bare, o);
  const double level = threshold_level(o);
  EXPECT_DOUBLE_EQ(level, 0.5 * scale_);
  const int r = bare.channel_index("R"), g = bare.channel_index("G"), b = bare.channel_index("B");
  for (int y = 0; y < bare.height; ++y)
    for (int x = 0; x < bare.width; ++x) {
      const double v = (bare.at(x, y, r) + bare.at(x, y, g) + bare.at(x, y, b)) / 3.0;
      EXPECT_EQ(difference.at(x, y, 3), v >= level ? 1.0f : 0.0f) << x << "," << y;
      EXPECT_EQ(difference.at(x, y, 0), 0.0f);
    }
}

TEST_F(Measure, EveryPixelGivesTheUsualSsimAndNoMaskedInterval) {
  MeasureOptions o = options();
  o.every_pixel = true;
  const Measurement m = measure(*bump_, *truth_, o);
  EXPECT_TRUE(std::isnan(m.image.mask_iou));
  EXPECT_DOUBLE_EQ(m.image.ssim, ssim_unmasked(*bump_, *truth_, m.image.peak));
  EXPECT_EQ(m.image.pixels, std::size_t(bump_->width) * bump_->height);
  EXPECT_TRUE(std::isnan(m.intervals.image_rmse.low));
  EXPECT_TRUE(same_bytes(m.profile, measure(*bump_, *truth_, options()).profile));
}

TEST(SceneDifferences, NameWhatMakesTwoRendersIncomparable) {
  const nlohmann::json a = {{"camera", {{"width", 32}, {"spp", 4}, {"right", {1, 0, 0}}}},
                            {"light", {{"direction", {-1, 0, 0}}}},
                            {"shape", {{"type", "sphere"}, {"tessellation", {{"segments", 8}}}}},
                            {"height", {{"amplitude", 0.01}}},
                            {"representation", "bump"}};
  nlohmann::json b = a;
  b["camera"]["spp"] = 64;
  b["shape"]["tessellation"]["segments"] = 16;
  b["representation"] = "displacement";
  EXPECT_TRUE(scene_differences(a, b).empty());
  b["camera"]["right"][0] = 2;
  b["height"]["amplitude"] = 0.02;
  b["shape"]["type"] = "cylinder";
  EXPECT_EQ(scene_differences(a, b),
            (std::vector<std::string>{"/shape/type", "/camera/right", "/height/amplitude"}));
}

}  // namespace
}  // namespace penumbra
