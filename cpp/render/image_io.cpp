#include "render/image_io.h"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

namespace penumbra {
namespace fs = std::filesystem;
namespace {

std::string temporary_name(const std::string& path) {
  const fs::path p(path);
  // Keep the extension: OpenImageIO picks the format from it.
  return (p.parent_path() /
          fmt::format(".{}.tmp{}{}", p.stem().string(), ::getpid(), p.extension().string()))
      .string();
}

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
  OIIO::ImageBuf buffer(spec, const_cast<float*>(image.pixels.data()));
  write_buffer(buffer, path);
}

void write_preview_png(const Image& image, const std::string& path) {
  OIIO::ImageSpec spec(image.width, image.height, static_cast<int>(image.channels.size()),
                       OIIO::TypeDesc::FLOAT);
  spec.channelnames = image.channels;
  OIIO::ImageBuf source(spec, const_cast<float*>(image.pixels.data()));
  const int rgba[] = {0, 1, 2, 3};
  OIIO::ImageBuf linear = OIIO::ImageBufAlgo::channels(source, 4, rgba);
  // The preview is composited over black, so premultiplied RGB is what shows.
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

std::string read_image_attribute(const std::string& path, const std::string& name) {
  auto input = OIIO::ImageInput::open(path);
  if (!input) throw std::runtime_error(fmt::format("{}: cannot read: {}", path, OIIO::geterror()));
  return input->spec().get_string_attribute(name);
}

Image read_image(const std::string& path) {
  OIIO::ImageBuf buffer(path);
  if (!buffer.read(0, 0, true, OIIO::TypeDesc::FLOAT))
    throw std::runtime_error(fmt::format("{}: cannot read: {}", path, buffer.geterror()));
  const OIIO::ImageSpec& spec = buffer.spec();
  Image image;
  image.width = spec.width;
  image.height = spec.height;
  image.channels = spec.channelnames;
  image.pixels.resize(std::size_t(spec.width) * spec.height * spec.nchannels);
  buffer.get_pixels(OIIO::ROI::All(), OIIO::TypeDesc::FLOAT, image.pixels.data());
  return image;
}

}  // namespace penumbra
