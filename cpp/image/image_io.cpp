#include "image/image_io.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include "util/files.h"
#include "util/hash.h"

namespace penumbra {
namespace fs = std::filesystem;
namespace {

void commit(const std::string& temporary, const std::string& path) {
  std::error_code ec;
  fs::rename(temporary, path, ec);
  if (ec) {
    fs::remove(temporary, ec);
    throw OutputError(
        fmt::format("{}: cannot move the finished file into place: {}", path, ec.message()));
  }
}

void write_buffer(OIIO::ImageBuf& buffer, const std::string& path) {
  const std::string temporary = temporary_name(path);
  if (!buffer.write(temporary)) {
    std::error_code ec;
    fs::remove(temporary, ec);
    throw OutputError(fmt::format("{}: cannot write: {}", path, buffer.geterror()));
  }
  commit(temporary, path);
}

}  // namespace

void check_writable(const std::string& path) {
  const fs::path p(path);
  const fs::path dir = p.parent_path().empty() ? fs::path(".") : p.parent_path();
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw OutputError(fmt::format("{}: the folder {} does not exist", path, dir.string()));
  if (::access(dir.c_str(), W_OK) != 0)
    throw OutputError(fmt::format("{}: the folder {} is not writable: {}", path, dir.string(),
                                  std::strerror(errno)));
  if (fs::is_directory(p, ec)) throw OutputError(fmt::format("{}: is a folder, not a file", path));
  // access() answers yes to root almost everywhere, and some folders (/proc)
  // take no new files at all: create and remove a probe file instead.
  const std::string probe = temporary_name(path);
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0)
    throw OutputError(fmt::format("{}: cannot create a file in {}: {}", path, dir.string(),
                                  std::strerror(errno)));
  ::close(fd);
  ::unlink(probe.c_str());
}

void write_exr(const Image& image, const std::string& path,
               const std::vector<std::pair<std::string, std::string>>& metadata) {
  OIIO::ImageSpec spec(image.width, image.height, static_cast<int>(image.channels.size()),
                       OIIO::TypeDesc::FLOAT);
  spec.channelnames = image.channels;
  spec.alpha_channel = 3;
  spec.attribute("compression", "zip");
  spec.attribute("oiio:ColorSpace", "Linear");
  for (const auto& [key, value] : metadata) spec.attribute(key, value);
  // OpenImageIO stamps the current time as capDate unless a DateTime is
  // given; an empty one writes none, so the same render gives the same bytes.
  spec.attribute("DateTime", "");
  const std::string temporary = temporary_name(path);
  auto output = OIIO::ImageOutput::create(temporary);
  const bool ok = output && output->open(temporary, spec) &&
                  output->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data()) &&
                  output->close();
  if (!ok) {
    const std::string why = output ? output->geterror() : OIIO::geterror();
    output.reset();
    std::error_code ec;
    fs::remove(temporary, ec);
    throw OutputError(fmt::format("{}: cannot write: {}", path, why));
  }
  output.reset();
  commit(temporary, path);
}

void write_preview_png(const Image& image, const std::string& path) {
  OIIO::ImageSpec spec(image.width, image.height, static_cast<int>(image.channels.size()),
                       OIIO::TypeDesc::FLOAT);
  spec.channelnames = image.channels;
  OIIO::ImageBuf source(spec, const_cast<float*>(image.pixels.data()));
  const int rgb[] = {0, 1, 2};
  // Composited over black: premultiplied RGB is exactly that, and the PNG
  // carries no alpha (a viewer would otherwise show a transparent background).
  OIIO::ImageBuf linear = OIIO::ImageBufAlgo::channels(source, 3, rgb);
  OIIO::ImageBuf encoded = OIIO::ImageBufAlgo::colorconvert(linear, "linear", "sRGB", false);
  if (encoded.has_error())
    throw std::runtime_error(
        fmt::format("{}: colour conversion failed: {}", path, encoded.geterror()));
  encoded.set_write_format(OIIO::TypeDesc::UINT8);
  write_buffer(encoded, path);
}

void write_png_rgb8(const std::string& path, int width, int height,
                    const std::vector<unsigned char>& rgb) {
  OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
  OIIO::ImageBuf buffer(spec);
  buffer.set_pixels(OIIO::ROI::All(), OIIO::TypeDesc::UINT8, rgb.data());
  write_buffer(buffer, path);
}

void write_binary_file(const std::string& path, const void* data, std::size_t bytes) {
  const std::string temporary = temporary_name(path);
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out.write(static_cast<const char*>(data), static_cast<std::streamsize>(bytes));
    out.flush();
    if (!out) {
      std::error_code ec;
      fs::remove(temporary, ec);
      throw OutputError(fmt::format("{}: cannot write: {}", path, std::strerror(errno)));
    }
  }
  commit(temporary, path);
}

void write_text_file(const std::string& path, const std::string& text) {
  write_binary_file(path, text.data(), text.size());
}

std::string image_checksum(const Image& image) {
  // Channel by channel in name order: OpenEXR stores channels sorted, so an
  // image read back has another order than the one written.
  std::vector<std::size_t> order(image.channels.size());
  for (std::size_t c = 0; c < order.size(); ++c) order[c] = c;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return image.channels[a] < image.channels[b]; });
  std::uint64_t h = fnv1a(fmt::format("{}x{}", image.width, image.height));
  const std::size_t nc = image.channels.size();
  const std::size_t pixels = std::size_t(image.width) * image.height;
  for (std::size_t c : order) {
    h = fnv1a(image.channels[c] + "\n", h);
    for (std::size_t i = 0; i < pixels; ++i) h = fnv1a(&image.pixels[i * nc + c], sizeof(float), h);
  }
  return fmt::format("{:016x}", h);
}

std::string read_image_attribute(const std::string& path, const std::string& name) {
  auto input = OIIO::ImageInput::open(path);
  if (!input) throw std::runtime_error(fmt::format("{}: cannot read: {}", path, OIIO::geterror()));
  return input->spec().get_string_attribute(name);
}

Image read_image(const std::string& path, std::map<std::string, std::string>* attributes) {
  // ImageInput rather than ImageBuf: ImageBuf reads through OpenImageIO's
  // shared ImageCache, which serves a file's old pixels after it was replaced
  // (cache entries are rewritten by rename).
  auto input = OIIO::ImageInput::open(path);
  if (!input) throw std::runtime_error(fmt::format("{}: cannot read: {}", path, OIIO::geterror()));
  const OIIO::ImageSpec spec = input->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
    throw std::runtime_error(fmt::format("{}: an empty image ({}x{}, {} channels)", path,
                                         spec.width, spec.height, spec.nchannels));
  Image image;
  image.width = spec.width;
  image.height = spec.height;
  image.channels = spec.channelnames;
  image.pixels.resize(std::size_t(spec.width) * spec.height * spec.nchannels);
  if (!input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data()))
    throw std::runtime_error(fmt::format("{}: cannot read: {}", path, input->geterror()));
  if (attributes)
    for (const OIIO::ParamValue& p : spec.extra_attribs)
      if (p.type() == OIIO::TypeDesc::STRING) (*attributes)[p.name().string()] = p.get_string();
  return image;
}

}  // namespace penumbra
