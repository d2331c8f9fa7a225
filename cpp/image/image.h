// The image every stage passes around: interleaved 32-bit float pixels with
// named channels, plus the few operations on whole images that several
// stages need (resampling, channel copies). No I/O here: see image_io.h.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

namespace penumbra {

// Interleaved float image with named channels.
struct Image {
  int width = 0, height = 0;
  std::vector<std::string> channels;
  std::vector<float> pixels;  // width * height * channels.size()

  int channel_index(const std::string& name) const;
  float at(int x, int y, int channel) const {
    return pixels[(std::size_t(y) * width + x) * channels.size() + channel];
  }
  float& at(int x, int y, int channel) {
    return pixels[(std::size_t(y) * width + x) * channels.size() + channel];
  }
};

// The colour channels every renderer returns: radiance R G B and coverage A.
inline const std::vector<std::string>& rgba_channels() {
  static const std::vector<std::string> names{"R", "G", "B", "A"};
  return names;
}

// Two images do not fit together (size, a missing channel). what() names it.
class ImageMismatch : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Mean over each nx x ny block of pixels: the box filter that turns a
// supersampled render into the final image. Sums in a fixed order, so the
// same input gives the same bits.
Image box_downsample(const Image& image, int nx, int ny);

// `base` with the channels `names` replaced by those of `source` (same size).
// Used to put a renderer's colour onto the evaluator's analysis channels of
// the same camera. ImageMismatch when the sizes differ or a channel is missing
// from either image.
Image with_channels_from(const Image& base, const Image& source,
                         const std::vector<std::string>& names);

// Number of NaN or Inf values over every channel.
std::size_t count_nonfinite(const Image& image);

}  // namespace penumbra
