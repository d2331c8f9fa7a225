// The comparison store (study/comparison_store.h): what it gives back is
// what was measured, bit for bit; a file it cannot trust is not read; and
// its key sees every pixel bit but not the order of the channels.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "analysis/metrics.h"
#include "evaluator/evaluator.h"
#include "scene/scene_json.h"
#include "small_sphere.h"
#include "study/comparison_store.h"
#include "temp_dir_test.h"
#include "util/files.h"
#include "util/hash.h"

namespace penumbra {
namespace {

class ComparisonStoreTest : public TempDirTest {};

TEST_F(ComparisonStoreTest, GivesBackTheMeasuredMetricsBitForBit) {
  const Image bump = render_small_sphere("bump"), truth = render_small_sphere("displacement");
  const double scale = radiance_scale(load_scene(kSmallSphere));
  const Measurement full = measure_comparison(bump, truth, scale, ComparisonExtent::kFullShadows);
  ASSERT_TRUE(full.shadow.has_value());
  ASSERT_GT(full.profile.rmse_terminator, 0.0);  // a real difference, not two zeros
  const Measurement profile_only =
      measure_comparison(bump, truth, scale, ComparisonExtent::kProfileOnly);
  const std::uint64_t k1 = comparison_key(pixel_digest(bump), pixel_digest(truth), scale,
                                          ComparisonExtent::kFullShadows);
  const std::uint64_t k2 = comparison_key(pixel_digest(bump), pixel_digest(truth), scale,
                                          ComparisonExtent::kProfileOnly);
  EXPECT_NE(k1, k2);
  EXPECT_NE(k1, comparison_key(pixel_digest(truth), pixel_digest(bump), scale,
                               ComparisonExtent::kFullShadows));  // test and reference differ
  {
    std::string warning;
    ComparisonStore store(path("comparisons.bin"), &warning);
    EXPECT_EQ(warning, "");
    EXPECT_FALSE(store.find(k1));
    store.insert(k1, full);
    store.insert(k2, profile_only);
    store.save();
  }
  std::string warning;
  ComparisonStore again(path("comparisons.bin"), &warning);
  EXPECT_EQ(warning, "");
  const auto a = again.find(k1), b = again.find(k2);
  ASSERT_TRUE(a && b);
  EXPECT_TRUE(same_bytes(a->profile, full.profile));
  EXPECT_TRUE(same_bytes(a->image, full.image));
  EXPECT_TRUE(same_bytes(a->view, full.view));
  EXPECT_TRUE(same_bytes(a->intervals, full.intervals));
  ASSERT_TRUE(a->shadow.has_value());
  EXPECT_TRUE(same_bytes(*a->shadow, *full.shadow));
  EXPECT_FALSE(b->shadow.has_value());
  EXPECT_TRUE(same_bytes(b->intervals, profile_only.intervals));
  EXPECT_EQ(again.found(), 2u);
  // Saving keeps only what this store used: here both, in the same bytes.
  const std::string before = read_file(path("comparisons.bin"));
  again.save();
  EXPECT_EQ(read_file(path("comparisons.bin")), before);
  ComparisonStore unused(path("comparisons.bin"), &warning);
  unused.save();
  ComparisonStore emptied(path("comparisons.bin"), &warning);
  EXPECT_FALSE(emptied.find(k1));
}

TEST_F(ComparisonStoreTest, AFileItCannotTrustIsNotRead) {
  const Image bump = render_small_sphere("bump"), truth = render_small_sphere("displacement");
  const double scale = radiance_scale(load_scene(kSmallSphere));
  const std::uint64_t key =
      comparison_key(pixel_digest(bump), pixel_digest(truth), scale, ComparisonExtent::kFull);
  {
    std::string warning;
    ComparisonStore store(path("c.bin"), &warning);
    store.insert(key, measure_comparison(bump, truth, scale, ComparisonExtent::kFull));
    store.save();
  }
  const std::string good = read_file(path("c.bin"));
  const auto reopened = [&](const std::string& bytes, std::string* warning) {
    std::ofstream(path("c.bin"), std::ios::binary | std::ios::trunc) << bytes;
    ComparisonStore store(path("c.bin"), warning);
    return store.find(key).has_value();
  };
  std::string warning;
  EXPECT_TRUE(reopened(good, &warning));
  EXPECT_EQ(warning, "");
  // Cut short: named, with what is wrong, and nothing read.
  EXPECT_FALSE(reopened(good.substr(0, good.size() - 3), &warning));
  EXPECT_NE(warning.find(path("c.bin")), std::string::npos) << warning;
  EXPECT_NE(warning.find("truncated"), std::string::npos) << warning;
  // Not a store at all.
  warning.clear();
  EXPECT_FALSE(reopened("garbage", &warning));
  EXPECT_NE(warning.find("not a comparison store"), std::string::npos) << warning;
  // Written by other comparison code: silently measured again.
  std::string foreign = good;
  foreign.replace(foreign.find("code ") + 5, 4, "zzzz");
  warning.clear();
  EXPECT_FALSE(reopened(foreign, &warning));
  EXPECT_EQ(warning, "");
}

TEST(PixelDigest, SeesEveryBitButNotTheOrderOfTheChannels) {
  const Image image = render_small_sphere("bump");
  const std::uint64_t digest = pixel_digest(image);
  // The last mantissa bit of one value in the middle of the image.
  Image flipped = image;
  std::uint32_t bits;
  float& value = flipped.pixels[flipped.pixels.size() / 2 + 1];
  std::memcpy(&bits, &value, sizeof bits);
  bits ^= 1u;
  std::memcpy(&value, &bits, sizeof bits);
  EXPECT_NE(pixel_digest(flipped), digest);
  // The same channels in reverse order, as a cache entry reads back.
  Image reversed = image;
  const std::size_t nc = image.channels.size();
  for (std::size_t c = 0; c < nc; ++c) {
    reversed.channels[c] = image.channels[nc - 1 - c];
    for (std::size_t i = 0; i < std::size_t(image.width) * image.height; ++i)
      reversed.pixels[i * nc + c] = image.pixels[i * nc + nc - 1 - c];
  }
  EXPECT_EQ(pixel_digest(reversed), digest);
  Image renamed = image;
  renamed.channels[0] = "X";
  EXPECT_NE(pixel_digest(renamed), digest);
}

// The definition, one channel plane at a time: each plane's 32-bit words
// through FNV-1a, then the size and the (name, plane hash) pairs in name
// order. The digest keys the comparisons kept on disk, so its value must
// not change with the way it is computed.
TEST(PixelDigest, IsEachChannelPlaneHashedThenFoldedInNameOrder) {
  const Image image = render_small_sphere("bump");
  const std::size_t nc = image.channels.size(), pixels = std::size_t(image.width) * image.height;
  std::vector<std::pair<std::string, std::uint64_t>> planes;
  for (std::size_t c = 0; c < nc; ++c) {
    std::vector<std::uint32_t> plane(pixels);
    for (std::size_t i = 0; i < pixels; ++i)
      std::memcpy(&plane[i], &image.pixels[i * nc + c], sizeof(std::uint32_t));
    std::uint64_t h = kFnvOffset;
    for (std::uint32_t word : plane) h = (h ^ word) * kFnvPrime;
    planes.emplace_back(image.channels[c], h);
  }
  std::sort(planes.begin(), planes.end());
  std::uint64_t want = fnv1a(std::to_string(image.width) + "x" + std::to_string(image.height));
  for (const auto& [name, h] : planes) {
    want = fnv1a(name + "\n", want);
    want = fnv1a(&h, sizeof h, want);
  }
  EXPECT_EQ(pixel_digest(image), want);
}

}  // namespace
}  // namespace penumbra
