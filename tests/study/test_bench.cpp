// The measurements of `penumbra bench` (study/bench.h): each counts the
// samples it rendered, once per method, and times them.
#include <gtest/gtest.h>

#include "study/bench.h"

namespace penumbra {
namespace {

TEST(Bench, TimingsCountTheSamplesOncePerMethod) {
  const BenchTiming one = bench_method(all_methods().front(), 16, 2, true);
  EXPECT_EQ(one.label, std::string(all_methods().front().id));
  EXPECT_DOUBLE_EQ(one.msamples, 16 * 16 * 2 / 1e6);
  EXPECT_GT(one.wall_seconds, 0.0);
  EXPECT_GE(one.cpu_seconds, 0.0);
  const BenchTiming scalar = bench_method(all_methods().front(), 16, 2, false);
  EXPECT_FALSE(scalar.packets);
  const BenchTiming pass = bench_shared_pass(16, 2, true);
  const std::size_t methods = std::stoul(pass.label);
  EXPECT_GT(methods, 1u);
  EXPECT_EQ(pass.label, std::to_string(methods) + " methods, one pass");
  EXPECT_DOUBLE_EQ(pass.msamples, double(methods) * 16 * 16 * 2 / 1e6);
  const DisplacementTiming d = bench_displacement(16, 2);
  EXPECT_GT(d.triangles, 0u);
  EXPECT_GE(d.peak_rss_mib, d.peak_rss_mib_before);
}

}  // namespace
}  // namespace penumbra
