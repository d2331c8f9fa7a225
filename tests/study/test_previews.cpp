// A study's preview, difference and FLIP PNGs (study/previews.h): a picture drawn
// from the same pixels is kept, byte for byte what drawing it again would
// give; anything else that feeds it, and a picture that is gone, draws it
// again; a run stopped while drawing keeps nothing.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "analysis/flip.h"
#include "analysis/magma.h"
#include "image/image_io.h"
#include "study/comparison_store.h"
#include "study/previews.h"
#include "temp_dir_test.h"
#include "util/files.h"

namespace penumbra {
namespace {

namespace fs = std::filesystem;

// A 6x4 RGBA image: a ramp over an object in the middle columns.
Image ramp(float gain) {
  Image image;
  image.width = 6, image.height = 4;
  image.channels = {"R", "G", "B", "A"};
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const float v = gain * float(x + y) / 8.0f, a = (x > 0 && x < 5) ? 1.0f : 0.0f;
      image.pixels.insert(image.pixels.end(), {v * a, v * a, v * a, a});
    }
  return image;
}

class PreviewFolderTest : public TempDirTest {
 protected:
  void SetUp() override {
    TempDirTest::SetUp();
    fs::create_directories(dir_ / "images");
  }
  // Draws the preview of `test` and its difference from `reference`; returns
  // how many pictures were drawn.
  std::size_t draw(const Image& test, const Image& reference, double scale, bool save = true) {
    PreviewFolder folder(dir_);
    folder.preview(test, pixel_digest(test), "images/t.png");
    folder.difference(test, pixel_digest(test), reference, pixel_digest(reference), scale,
                      "images/t-diff.png");
    EXPECT_EQ(folder.drawn() + folder.kept(), 2u);
    if (save) folder.save();
    return folder.drawn();
  }
  void mark(const std::string& relative) const {
    std::ofstream(dir_ / relative, std::ios::binary) << "kept";
  }
  std::string text(const std::string& relative) const { return read_file(path(relative)); }
  // The bytes of the pictures drawn afresh, outside the folder.
  std::string fresh_preview(const Image& image) const {
    write_preview_png(image, path("fresh.png"));
    return text("fresh.png");
  }
  std::string fresh_difference(const Image& test, const Image& reference, double scale) const {
    write_difference_png(test, reference, scale, path("fresh-diff.png"));
    return text("fresh-diff.png");
  }
};

TEST_F(PreviewFolderTest, KeepsWhatWasDrawnFromTheSamePixels) {
  const Image test = ramp(1.0f), truth = ramp(0.9f);
  EXPECT_EQ(draw(test, truth, 0.25), 2u);
  EXPECT_EQ(text("images/t.png"), fresh_preview(test));
  EXPECT_EQ(text("images/t-diff.png"), fresh_difference(test, truth, 0.25));
  // Marked files show whether the second run drew them again.
  mark("images/t.png"), mark("images/t-diff.png");
  EXPECT_EQ(draw(test, truth, 0.25), 0u);
  EXPECT_EQ(text("images/t.png"), "kept");
  EXPECT_EQ(text("images/t-diff.png"), "kept");
  // The same pixels in another Image (as a later run reads them back) count too.
  const Image copy = ramp(1.0f);
  EXPECT_EQ(draw(copy, truth, 0.25), 0u);
}

TEST_F(PreviewFolderTest, DrawsAgainWhatChanged) {
  const Image test = ramp(1.0f), truth = ramp(0.9f);
  draw(test, truth, 0.25);
  mark("images/t.png"), mark("images/t-diff.png");

  Image changed = test;  // one bit of one pixel
  std::uint32_t bits;
  std::memcpy(&bits, &changed.pixels[13], sizeof bits);
  bits ^= 1u;
  std::memcpy(&changed.pixels[13], &bits, sizeof bits);
  EXPECT_EQ(draw(changed, truth, 0.25), 2u) << "the test's pixels feed both pictures";
  EXPECT_EQ(text("images/t.png"), fresh_preview(changed));
  EXPECT_EQ(text("images/t-diff.png"), fresh_difference(changed, truth, 0.25));

  mark("images/t.png"), mark("images/t-diff.png");
  EXPECT_EQ(draw(changed, ramp(0.8f), 0.25), 1u) << "the truth feeds the difference only";
  EXPECT_EQ(text("images/t.png"), "kept");
  EXPECT_EQ(text("images/t-diff.png"), fresh_difference(changed, ramp(0.8f), 0.25));

  mark("images/t-diff.png");
  EXPECT_EQ(draw(changed, ramp(0.8f), 0.5), 1u) << "so does the scale";
  EXPECT_EQ(text("images/t-diff.png"), fresh_difference(changed, ramp(0.8f), 0.5));
}

// The FLIP map is drawn from the pixels of both renders, is the magma PNG of
// the map the study's mean FLIP is taken from (HDR, the default viewer), and
// is kept like the others.
TEST_F(PreviewFolderTest, FlipMapsAreTheMeasuredMapsAndAreKeptLikeTheOthers) {
  const Image test = ramp(1.0f), truth = ramp(0.9f);
  const auto flip = [&](const Image& t, const Image& r, std::size_t* drawn) {
    PreviewFolder folder(dir_);
    const bool made = folder.flip(t, pixel_digest(t), r, pixel_digest(r), "images/t-flip.png");
    folder.save();
    *drawn = folder.drawn();
    return made;
  };
  const auto fresh = [&](const Image& t, const Image& r) {
    FlipOptions options;
    options.range = FlipRange::kHdr;
    const FlipImage map = flip_map(t, r, options);
    write_png_rgb8(path("fresh-flip.png"), map.width, map.height, magma_rgb8(map.error));
    return text("fresh-flip.png");
  };
  std::size_t drawn = 0;
  ASSERT_TRUE(flip(test, truth, &drawn));
  EXPECT_EQ(drawn, 1u);
  EXPECT_EQ(text("images/t-flip.png"), fresh(test, truth));
  mark("images/t-flip.png");
  EXPECT_TRUE(flip(test, truth, &drawn));
  EXPECT_EQ(drawn, 0u);
  EXPECT_EQ(text("images/t-flip.png"), "kept");
  EXPECT_TRUE(flip(test, ramp(0.8f), &drawn));
  EXPECT_EQ(drawn, 1u) << "the truth feeds the map";
  EXPECT_EQ(text("images/t-flip.png"), fresh(test, ramp(0.8f)));

  // FLIP is defined against an all-black truth too (flip.h: its exposures
  // are then [0, 0]), so such a render still gets its map.
  EXPECT_TRUE(flip(test, ramp(0.0f), &drawn));
  EXPECT_EQ(text("images/t-flip.png"), fresh(test, ramp(0.0f)));

  // A study hands the preview the map its comparison computed
  // (study/compare.cpp) rather than computing it twice: measure_comparison
  // gives the map behind its mean FLIP, and the picture drawn from it is the
  // same bytes.
  FlipImage measured;
  const Measurement m = measure_comparison(test, truth, 1.0, ComparisonExtent::kFull, &measured);
  ASSERT_EQ(measured.error.size(), std::size_t(test.width * test.height));
  EXPECT_EQ(m.image.flip, mean_flip(measured));
  fs::remove(path("images/t-flip.png"));
  PreviewFolder folder(dir_);
  ASSERT_TRUE(folder.flip(test, pixel_digest(test), truth, pixel_digest(truth), "images/t-flip.png",
                          measured));
  EXPECT_EQ(text("images/t-flip.png"), fresh(test, truth));
  // Profile-only comparisons compute no map, and say so by leaving it empty.
  FlipImage none;
  measure_comparison(test, truth, 1.0, ComparisonExtent::kProfileOnly, &none);
  EXPECT_TRUE(none.error.empty());
}

TEST_F(PreviewFolderTest, DrawsAgainWhatIsGoneOrEmpty) {
  const Image test = ramp(1.0f), truth = ramp(0.9f);
  draw(test, truth, 0.25);
  fs::remove(dir_ / "images/t.png");
  std::ofstream(dir_ / "images/t-diff.png", std::ios::trunc);
  EXPECT_EQ(draw(test, truth, 0.25), 2u);
  EXPECT_EQ(text("images/t.png"), fresh_preview(test));
  EXPECT_EQ(text("images/t-diff.png"), fresh_difference(test, truth, 0.25));
}

TEST_F(PreviewFolderTest, ARunStoppedWhileDrawingOrADamagedStampKeepsNothing) {
  const Image test = ramp(1.0f), truth = ramp(0.9f);
  draw(test, truth, 0.25);
  draw(test, truth, 0.25, /*save=*/false);  // as if stopped before the stamp
  EXPECT_FALSE(fs::exists(dir_ / "images/.inputs"));
  EXPECT_EQ(draw(test, truth, 0.25), 2u);

  std::ofstream(dir_ / "images/.inputs", std::ios::app) << "not a key images/x.png\n";
  EXPECT_EQ(draw(test, truth, 0.25), 2u);
  EXPECT_EQ(draw(test, truth, 0.25), 0u);
}

}  // namespace
}  // namespace penumbra
