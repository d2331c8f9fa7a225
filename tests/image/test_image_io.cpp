// Image files: OpenEXR written and read by Penumbra's own code, checked
// against OpenImageIO's tools (an independent reader and writer), and the
// OpenImageIO module loaded only when a format other than EXR is used.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#include "image/image_io.h"
#include "temp_dir_test.h"

namespace penumbra {
namespace {

// Runs a shell command; returns its standard output and error.
std::string run(const std::string& command, int* status = nullptr) {
  std::string output;
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return output;
  char buffer[4096];
  while (std::fgets(buffer, sizeof buffer, pipe)) output += buffer;
  const int s = ::pclose(pipe);
  if (status) *status = s;
  return output;
}

std::uint32_t bits(float f) {
  std::uint32_t b;
  std::memcpy(&b, &f, sizeof b);
  return b;
}

// Channels in an order OpenEXR does not keep (it stores them sorted), and
// values that a lossy path would change: -0, a denormal, huge, tiny.
Image awkward_image() {
  Image image;
  image.width = 5;
  image.height = 3;
  image.channels = {"analysis.theta", "R", "G", "B", "A", "Z"};
  const float specials[] = {-0.0f, std::numeric_limits<float>::denorm_min(), 3.0e38f, 1e-30f, 0.1f};
  image.pixels.resize(std::size_t(image.width) * image.height * image.channels.size());
  for (std::size_t i = 0; i < image.pixels.size(); ++i)
    image.pixels[i] = i % 7 == 0 ? specials[(i / 7) % 5] : float(i) * 0.37f - 2.0f;
  return image;
}

class ImageIo : public TempDirTest {};

TEST_F(ImageIo, ExrKeepsEveryChannelBitForBitAndPutsRgbaFirst) {
  const Image image = awkward_image();
  write_exr(image, path("a.exr"), {{"penumbra:scene", "{\"x\":1}"}, {"note", "ü ok"}});
  std::map<std::string, std::string> attributes;
  const Image back = read_image(path("a.exr"), &attributes);
  ASSERT_EQ(back.width, 5);
  ASSERT_EQ(back.height, 3);
  // OpenImageIO's order, which earlier versions of Penumbra read.
  EXPECT_EQ(back.channels, (std::vector<std::string>{"R", "G", "B", "A", "Z", "analysis.theta"}));
  for (std::size_t c = 0; c < image.channels.size(); ++c) {
    const int b = back.channel_index(image.channels[c]);
    for (int y = 0; y < image.height; ++y)
      for (int x = 0; x < image.width; ++x)
        ASSERT_EQ(bits(back.at(x, y, b)), bits(image.at(x, y, static_cast<int>(c))))
            << image.channels[c] << " at " << x << "," << y;
  }
  EXPECT_EQ(attributes["penumbra:scene"], "{\"x\":1}");
  EXPECT_EQ(attributes["note"], "ü ok");
  EXPECT_EQ(read_image_attribute(path("a.exr"), "penumbra:scene"), "{\"x\":1}");
  EXPECT_EQ(read_image_attribute(path("a.exr"), "absent"), "");
  EXPECT_EQ(image_checksum(back), image_checksum(image));
}

TEST_F(ImageIo, OpenImageIoReadsWhatPenumbraWrites) {
  write_exr(awkward_image(), path("a.exr"), {{"penumbra:key", "abc"}});
  int status = 0;
  const std::string info = run("oiiotool --info -v " + path("a.exr"), &status);
  ASSERT_EQ(status, 0) << info;
  EXPECT_NE(info.find("6 channel, float openexr"), std::string::npos) << info;
  EXPECT_NE(info.find("compression: \"zip\""), std::string::npos) << info;
  EXPECT_NE(info.find("penumbra:key: \"abc\""), std::string::npos) << info;
  // Pixel (1, 2) as OpenImageIO reads it, channel by channel in its order,
  // which is the order read_image gives.
  const std::string dump = run("oiiotool --dumpdata " + path("a.exr"));
  const std::string tag = "Pixel (1, 2):";
  const std::size_t at = dump.find(tag);
  ASSERT_NE(at, std::string::npos) << dump;
  std::istringstream values(dump.substr(at + tag.size()));
  const Image back = read_image(path("a.exr"));
  for (std::size_t c = 0; c < back.channels.size(); ++c) {
    double v = 0.0;
    ASSERT_TRUE(values >> v) << dump.substr(at, 200);
    const double expected = back.at(1, 2, static_cast<int>(c));
    EXPECT_NEAR(v, expected, 1e-9 + 1e-8 * std::abs(expected)) << back.channels[c];
  }
}

TEST_F(ImageIo, ExrFromOpenImageIoWithHalfChannelsAndAnOffsetWindowReadsAsFloat) {
  int status = 0;
  const std::string out =
      run("oiiotool --pattern constant:color=0.25,0.5,2 4x3 3 --origin +2+5 -d half -o " +
              path("h.exr"),
          &status);
  ASSERT_EQ(status, 0) << out;
  const Image image = read_image(path("h.exr"));
  ASSERT_EQ(image.width, 4);
  ASSERT_EQ(image.height, 3);
  ASSERT_EQ(image.channels, (std::vector<std::string>{"R", "G", "B"}));
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x) {
      EXPECT_EQ(image.at(x, y, 0), 0.25f);  // exact in half
      EXPECT_EQ(image.at(x, y, 1), 0.5f);
      EXPECT_EQ(image.at(x, y, 2), 2.0f);
    }
}

TEST_F(ImageIo, PreviewIsSrgbOverBlackWithinOneLevelOfOpenImageIo) {
  Image image;
  image.width = 64;
  image.height = 1;
  image.channels = {"R", "G", "B", "A"};
  for (int x = 0; x < 64; ++x) {
    const float v = x < 60 ? std::pow(float(x) / 59.0f, 2.2f) : 1.0f + float(x - 60);
    image.pixels.insert(image.pixels.end(), {v, 0.5f * v, 0.001f * float(x), 0.5f});
  }
  write_exr(image, path("p.exr"));
  write_preview_png(image, path("p.png"));
  const std::string out =
      run("oiiotool " + path("p.exr") + " --ch R,G,B --colorconvert linear sRGB -d uint8 -o " +
          path("ref.png"));
  const Image mine = read_image(path("p.png")), ref = read_image(path("ref.png"));
  ASSERT_EQ(mine.channels.size(), 3u) << "no alpha: composited over black";
  ASSERT_EQ(ref.width, 64) << out;
  for (int x = 0; x < 64; ++x)
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(mine.at(x, 0, c), ref.at(x, 0, c), 1.0 / 255 + 1e-6) << x << "," << c;
}

TEST_F(ImageIo, BadFilesAreNamedWithTheReason) {
  try {
    read_image(path("missing.exr"));
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path("missing.exr")), std::string::npos) << e.what();
  }
  // An EXR cut short after its header.
  write_exr(awkward_image(), path("a.exr"));
  std::ifstream in(path("a.exr"), std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(path("cut.exr"), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  EXPECT_THROW(read_image(path("cut.exr")), std::runtime_error);
  std::ofstream(path("junk.png")) << "not an image";
  EXPECT_THROW(read_image(path("junk.png")), std::runtime_error);
  EXPECT_THROW(write_exr(awkward_image(), path("no/such/folder/x.exr")), OutputError);
}

// OpenImageIO's ~260 libraries stay out of a process that only writes EXR
// (they cost 0.3 s and 120 MiB per start); a PNG preview loads the module.
TEST_F(ImageIo, OpenImageIoIsLoadedOnlyForOtherFormats) {
  const std::string binary = PENUMBRA_BINARY;
  const std::string scene = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/calibration/sphere.json";
  const std::string render = "LD_DEBUG=libs " + binary + " render " + scene +
                             " --width 8 --height 8 --spp 1 -q -o " + path("a.exr");
  int status = 0;
  std::string log = run(render, &status);
  ASSERT_EQ(status, 0) << log;
  EXPECT_EQ(log.find("libOpenImageIO"), std::string::npos);
  log = run(render + " --preview " + path("a.png"), &status);
  ASSERT_EQ(status, 0) << log;
  EXPECT_NE(log.find("libpenumbra_oiio.so"), std::string::npos);
  EXPECT_NE(log.find("libOpenImageIO"), std::string::npos);
  EXPECT_EQ(read_image(path("a.png")).width, 8);
}

}  // namespace
}  // namespace penumbra
