#include "image/image.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

namespace penumbra {

int Image::channel_index(const std::string& name) const {
  for (std::size_t i = 0; i < channels.size(); ++i)
    if (channels[i] == name) return static_cast<int>(i);
  return -1;
}

Image box_downsample(const Image& image, int nx, int ny) {
  if (nx == 1 && ny == 1) return image;
  Image out;
  out.width = image.width / nx;
  out.height = image.height / ny;
  out.channels = image.channels;
  const std::size_t nc = image.channels.size();
  out.pixels.assign(std::size_t(out.width) * out.height * nc, 0.0f);
  const double weight = 1.0 / (nx * ny);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      for (std::size_t c = 0; c < nc; ++c) {
        double sum = 0.0;  // fixed order: the same bits every time
        for (int sy = 0; sy < ny; ++sy)
          for (int sx = 0; sx < nx; ++sx)
            sum += image.at(x * nx + sx, y * ny + sy, static_cast<int>(c));
        out.pixels[(std::size_t(y) * out.width + x) * nc + c] = static_cast<float>(sum * weight);
      }
  return out;
}

Image with_channels_from(const Image& base, const Image& source,
                         const std::vector<std::string>& names) {
  if (base.width != source.width || base.height != source.height)
    throw ImageMismatch(fmt::format("a {}x{} image, expected {}x{}", source.width, source.height,
                                    base.width, base.height));
  Image out = base;
  for (const std::string& name : names) {
    const int to = out.channel_index(name), from = source.channel_index(name);
    if (from < 0) throw ImageMismatch(fmt::format("no {} channel", name));
    if (to < 0) throw ImageMismatch(fmt::format("no {} channel to replace", name));
    for (int y = 0; y < out.height; ++y)
      for (int x = 0; x < out.width; ++x) out.at(x, y, to) = source.at(x, y, from);
  }
  return out;
}

std::size_t count_nonfinite(const Image& image) {
  return static_cast<std::size_t>(std::count_if(image.pixels.begin(), image.pixels.end(),
                                                [](float v) { return !std::isfinite(v); }));
}

}  // namespace penumbra
