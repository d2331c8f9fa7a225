#include "study/previews.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <vector>

#include "analysis/flip.h"
#include "analysis/magma.h"
#include "image/image_io.h"
#include "renderers/code_digest.h"
#include "util/hash.h"

namespace penumbra {
namespace fs = std::filesystem;

namespace {

constexpr const char* kStampName = "images/.inputs";

// The stamp: one line per picture, "KEY PATH", KEY 16 hex digits. Any line
// not of that form makes the whole stamp count as absent.
std::map<std::string, std::uint64_t> read_stamp(const fs::path& path) {
  std::map<std::string, std::uint64_t> keys;
  std::ifstream in(path, std::ios::binary);
  for (std::string line; std::getline(in, line);) {
    const std::size_t space = line.find(' ');
    if (space != 16 || line.size() == 17 || line.find_first_not_of("0123456789abcdef") < space)
      return {};
    keys[line.substr(17)] = std::stoull(line.substr(0, 16), nullptr, 16);
  }
  return keys;
}

std::uint64_t drawing_key(char kind, std::uint64_t digest) {
  std::uint64_t h = fnv1a(std::string_view(&kind, 1));
  h = fnv1a(std::string_view(build_code_digests().previews), h);
  return fnv1a(&digest, sizeof digest, h);
}

}  // namespace

void write_difference_png(const Image& test, const Image& reference, double scale,
                          const std::string& path) {
  std::vector<unsigned char> rgb(std::size_t(test.width) * test.height * 3);
  const int a1 = test.channel_index("A"), a2 = reference.channel_index("A");
  const int r1 = test.channel_index("R"), r2 = reference.channel_index("R");
  for (int y = 0; y < test.height; ++y)
    for (int x = 0; x < test.width; ++x) {
      unsigned char* p = &rgb[(std::size_t(y) * test.width + x) * 3];
      if (test.at(x, y, a1) < 0.5f || reference.at(x, y, a2) < 0.5f) {
        p[0] = p[1] = p[2] = 96;
        continue;
      }
      const double d = (test.at(x, y, r1) - reference.at(x, y, r2)) / scale;
      const double v = std::clamp(d / 0.25, -1.0, 1.0);
      const auto c = [](double t) { return static_cast<unsigned char>(std::lround(255.0 * t)); };
      if (v >= 0)
        p[0] = 255, p[1] = c(1 - v), p[2] = c(1 - v);
      else
        p[0] = c(1 + v), p[1] = c(1 + v), p[2] = 255;
    }
  write_png_rgb8(path, test.width, test.height, rgb);
}

PreviewFolder::PreviewFolder(const fs::path& study_folder) : folder_(study_folder) {
  last_ = read_stamp(folder_ / kStampName);
  std::error_code ignored;
  fs::remove(folder_ / kStampName, ignored);
}

bool PreviewFolder::needs_drawing(const std::string& relative, std::uint64_t key) {
  const auto it = last_.find(relative);
  // A picture someone removed or emptied is drawn again.
  std::error_code ec;
  const bool current =
      it != last_.end() && it->second == key && fs::file_size(folder_ / relative, ec) > 0 && !ec;
  std::lock_guard<std::mutex> lock(mutex_);
  if (current) {
    now_[relative] = key;
    ++kept_;
  }
  return !current;
}

void PreviewFolder::preview(const Image& image, std::uint64_t digest, const std::string& relative) {
  const std::uint64_t key = drawing_key('p', digest);
  if (!needs_drawing(relative, key)) return;
  write_preview_png(image, (folder_ / relative).string());
  std::lock_guard<std::mutex> lock(mutex_);
  now_[relative] = key;
  ++drawn_;
}

void PreviewFolder::difference(const Image& test, std::uint64_t test_digest, const Image& reference,
                               std::uint64_t reference_digest, double scale,
                               const std::string& relative) {
  std::uint64_t inputs = fnv1a(&test_digest, sizeof test_digest);
  inputs = fnv1a(&reference_digest, sizeof reference_digest, inputs);
  inputs = fnv1a(&scale, sizeof scale, inputs);
  const std::uint64_t key = drawing_key('d', inputs);
  if (!needs_drawing(relative, key)) return;
  write_difference_png(test, reference, scale, (folder_ / relative).string());
  std::lock_guard<std::mutex> lock(mutex_);
  now_[relative] = key;
  ++drawn_;
}

bool PreviewFolder::flip(const Image& test, std::uint64_t test_digest, const Image& reference,
                         std::uint64_t reference_digest, const std::string& relative,
                         const FlipImage& given) {
  std::uint64_t inputs = fnv1a(&test_digest, sizeof test_digest);
  inputs = fnv1a(&reference_digest, sizeof reference_digest, inputs);
  const std::uint64_t key = drawing_key('f', inputs);
  if (!needs_drawing(relative, key)) return true;
  FlipImage computed;
  if (given.error.empty()) try {
      // The options measure_comparison's mean FLIP uses (analysis/measure.cpp).
      FlipOptions options;
      options.range = FlipRange::kHdr;
      computed = flip_map(test, reference, options);
    } catch (const ImageMismatch&) {
      return false;
    }
  const FlipImage& map = given.error.empty() ? computed : given;
  write_png_rgb8((folder_ / relative).string(), map.width, map.height, magma_rgb8(map.error));
  std::lock_guard<std::mutex> lock(mutex_);
  now_[relative] = key;
  ++drawn_;
  return true;
}

void PreviewFolder::save() const {
  std::string text;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [relative, key] : now_) text += fmt::format("{:016x} {}\n", key, relative);
  }
  write_text_file((folder_ / kStampName).string(), text);
}

std::size_t PreviewFolder::drawn() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return drawn_;
}

std::size_t PreviewFolder::kept() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return kept_;
}

}  // namespace penumbra
