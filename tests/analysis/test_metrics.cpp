// Profile and image metrics on synthetic inputs with known answers, and the
// contour grid of Chiang et al. Fig. 5.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <vector>

#include "analysis/contour.h"
#include "analysis/metrics.h"
#include "core/vec.h"

namespace penumbra {
namespace {

Profile synthetic(const std::function<double(double)>& f) {
  Profile p;
  p.value.resize(180);
  p.count.assign(180, 100);
  for (std::size_t k = 0; k < 180; ++k) p.value[k] = f(p.centre(k));
  return p;
}
double cosine(double deg) {
  return std::max(0.0, std::cos(radians(deg)));
}

TEST(ProfileMetrics, CosineAgainstItselfHasNoErrorAndTheAnalyticPosition) {
  const Profile p = synthetic(cosine);
  const ProfileMetrics m = compare_profiles(p, p);
  EXPECT_EQ(m.rmse_overall, 0.0);
  EXPECT_EQ(m.rmse_terminator, 0.0);
  EXPECT_EQ(m.max_error, 0.0);
  EXPECT_EQ(m.lit_bias, 0.0);
  EXPECT_EQ(m.position_error, 0.0);
  // acos(0.05) = 87.134 degrees; linear interpolation between bin centres
  // of a curve this smooth is within 0.01 degrees.
  EXPECT_NEAR(m.position, degrees(std::acos(kDarkLevel)), 0.01);
  // Width from 0.9 to 0.1 of L(60.5 deg): acos(0.1 c) - acos(0.9 c).
  const double c = cosine(60.5);
  EXPECT_NEAR(m.width, degrees(std::acos(0.1 * c)) - degrees(std::acos(0.9 * c)), 0.02);
  // Largest step of a cosine in [60,100) with 1-degree bins: near 90 deg,
  // sin(1 deg) = 0.01745.
  EXPECT_NEAR(m.max_step, std::sin(radians(1.0)), 1e-4);
}

TEST(ProfileMetrics, KnownStepIsMeasuredExactly) {
  const Profile ground = synthetic(cosine);
  const Profile step = synthetic([](double t) { return t < 80.0 ? cosine(t) : 0.0; });
  const ProfileMetrics m = compare_profiles(step, ground);
  EXPECT_NEAR(m.max_step, cosine(79.5), 1e-12);   // the cliff at 80 degrees
  EXPECT_NEAR(m.max_error, cosine(80.5), 1e-12);  // first dark bin
  EXPECT_EQ(m.lit_bias, 0.0);                     // nothing changes below 60
  // Crossing of 0.05 between the centres 79.5 (cos 79.5) and 80.5 (0).
  const double expected = 79.5 + (cosine(79.5) - kDarkLevel) / cosine(79.5);
  EXPECT_NEAR(m.position, expected, 1e-9);
  // Terminator RMSE: sqrt(mean over 60.5..99.5 of the removed cosine^2).
  double sum = 0.0;
  for (int k = 80; k < 100; ++k) sum += std::pow(cosine(k + 0.5), 2);
  EXPECT_NEAR(m.rmse_terminator, std::sqrt(sum / 40.0), 1e-12);
}

TEST(ProfileMetrics, ShiftedProfileHasThatPositionError) {
  const Profile ground = synthetic(cosine);
  const Profile shifted = synthetic([](double t) { return cosine(t - 5.0); });
  const ProfileMetrics m = compare_profiles(shifted, ground);
  EXPECT_NEAR(m.position_error, 5.0, 0.01);
  EXPECT_GT(m.lit_bias, 0.0);  // shifted right: brighter everywhere it is lit
}

TEST(ImageMetrics, NaNAndInfAreCounted) {
  Image a;
  a.width = 2, a.height = 1;
  a.channels = {"R", "G", "B", "A"};
  a.pixels = {1, 1, 1, 1, 1, 1, 1, 1};
  Image b = a;
  b.pixels[0] = NAN;
  b.pixels[5] = INFINITY;
  EXPECT_EQ(compare_images(b, a).nonfinite, 2u);
  EXPECT_EQ(compare_images(a, a).nonfinite, 0u);
  EXPECT_DOUBLE_EQ(compare_images(a, a).ssim, 1.0);
}

// Chiang 2019, Fig. 5, read off the grid the contour command plots.
TEST(Contour, GridReproducesFigure5Relations) {
  const ContourGrid grid = make_contour_grid(
      {{TerminatorMethod::kChiang2019, 0.0}, {TerminatorMethod::kEstevez2019, 0.0}}, 1.0);
  ASSERT_EQ(grid.light_deg.size(), 91u);
  ASSERT_EQ(grid.deviation_deg.size(), 90u);
  const auto& chiang = grid.g[0];
  const auto& estevez = grid.g[1];
  bool estevez_less_somewhere_small = false, estevez_more_somewhere_large = false;
  for (std::size_t i = 0; i < grid.deviation_deg.size(); ++i)
    for (std::size_t j = 0; j < grid.light_deg.size(); ++j) {
      const double d = grid.deviation_deg[i], t = grid.light_deg[j];
      if (t >= 90.0) continue;
      if (d == 0.0) {  // no deviation: both leave shading alone
        EXPECT_NEAR(chiang[i][j], 1.0, 1e-12) << t;
        EXPECT_NEAR(estevez[i][j], 1.0, 1e-12) << t;
      }
      if (d > t && t > 0.0) {  // normal tilted past the light (t = 0: tan = 0, G = 1)
        EXPECT_NEAR(chiang[i][j], 1.0, 1e-12) << t << " " << d;
        EXPECT_LT(estevez[i][j], 1.0) << t << " " << d;
      }
      if (d > 0 && d <= 10 && t > 80 && estevez[i][j] > chiang[i][j] + 1e-3)
        estevez_less_somewhere_small = true;  // Estevez shadows less
      if (d >= 40 && t > d && estevez[i][j] < chiang[i][j] - 1e-3)
        estevez_more_somewhere_large = true;  // Estevez shadows more
    }
  EXPECT_TRUE(estevez_less_somewhere_small);
  EXPECT_TRUE(estevez_more_somewhere_large);
}

}  // namespace
}  // namespace penumbra
