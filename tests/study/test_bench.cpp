// The measurements of `penumbra bench` (study/bench.h): each counts the
// samples it rendered, once per method, and times them.
#include <gtest/gtest.h>

#include "study/bench.h"
#include "temp_dir_test.h"

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

// The large-mesh figure reads a file of the 1024-segment UV sphere: 1024
// triangles around each pole and two per quad between, 1024 x 510 x 2 +
// 2 x 1024 (no triangle of zero area to drop), 24 bytes of position and
// normal per vertex.
class BenchMesh : public TempDirTest {};
TEST_F(BenchMesh, AMillionTriangleFileIsReadAndRendered) {
  const MeshFileTiming m = bench_mesh_file(16, 1, path(""));
  EXPECT_EQ(m.triangles, 1024u * 510u * 2u + 2u * 1024u);
  EXPECT_GT(m.file_mib, (1024.0 * 511 + 2) * 24 / (1024.0 * 1024.0));
  EXPECT_GT(m.read_seconds, 0.0);
  EXPECT_GT(m.rss_mib_read, 0.0);
  EXPECT_GT(m.seconds, 0.0);
  EXPECT_GE(m.peak_rss_mib, m.rss_mib_read);
}

}  // namespace
}  // namespace penumbra
