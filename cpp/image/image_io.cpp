#include "image/image_io.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>

#include <dlfcn.h>
#include <fmt/format.h>

#include "image/exr_file.h"
#include "image/oiio_module.h"
#include "util/data_files.h"
#include "util/files.h"
#include "util/hash.h"

namespace penumbra {
namespace fs = std::filesystem;
namespace {

// `fill` writes `path`'s content (write_atomically): whatever fails, the
// file is left as it was, and the reason is an OutputError naming it.
void write_output(const std::string& path, const std::function<void(CheckedFile&)>& fill) {
  try {
    write_atomically(path, fill);
  } catch (const std::exception& e) {
    throw OutputError(fmt::format("{}: cannot write: {}", path, e.what()));
  }
}

// Where the module lies: beside the executable in a build folder, under
// PREFIX/lib once installed; the same two places as data_file() looks in.
const OiioModule* load_oiio_module() {
  const fs::path exe_dir = executable_folder();
  std::string tried;
  for (const fs::path& folder : {exe_dir / "lib", exe_dir.parent_path() / "lib"}) {
    const fs::path file = (folder / "penumbra" / "libpenumbra_oiio.so").lexically_normal();
    void* handle = ::dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
      tried += fmt::format("\n  {}", ::dlerror());
      continue;
    }
    using Entry = const OiioModule* (*)();
    const auto entry = reinterpret_cast<Entry>(::dlsym(handle, "penumbra_oiio_module"));
    const OiioModule* module = entry ? entry() : nullptr;
    if (module && module->abi == kOiioModuleAbi) return module;
    tried += fmt::format("\n  {}: not a module of this Penumbra build", file.string());
  }
  throw std::runtime_error(
      "image formats other than OpenEXR need Penumbra's OpenImageIO module "
      "(libpenumbra_oiio.so), which could not be loaded:" +
      tried);
}

// Loaded once, on the first non-EXR file; a failed load is retried on the
// next call (a throwing static initialiser runs again).
const OiioModule& oiio() {
  static const OiioModule* module = load_oiio_module();
  return *module;
}

// The sRGB transfer function of IEC 61966-2-1, to 8 bits with rounding.
unsigned char encode_srgb8(float linear) {
  const double v = std::clamp(double(linear), 0.0, 1.0);
  const double encoded = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
  return static_cast<unsigned char>(std::lround(encoded * 255.0));
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

void load_image_formats() {
  oiio();
}

void write_exr(const Image& image, const std::string& path,
               const std::vector<std::pair<std::string, std::string>>& metadata) {
  write_output(path, [&](CheckedFile& file) { write_exr_file(image, file, metadata); });
}

void write_preview_png(const Image& image, const std::string& path) {
  const int r = image.channel_index("R"), g = image.channel_index("G"),
            b = image.channel_index("B");
  if (r < 0 || g < 0 || b < 0)
    throw std::runtime_error(fmt::format("{}: a preview needs channels R, G and B", path));
  // Premultiplied RGB is the image composited over black, so the PNG carries
  // no alpha (a viewer would otherwise show a transparent background).
  std::vector<unsigned char> rgb(std::size_t(image.width) * image.height * 3);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      unsigned char* out = &rgb[(std::size_t(y) * image.width + x) * 3];
      out[0] = encode_srgb8(image.at(x, y, r));
      out[1] = encode_srgb8(image.at(x, y, g));
      out[2] = encode_srgb8(image.at(x, y, b));
    }
  write_png_rgb8(path, image.width, image.height, rgb);
}

void write_png_rgb8(const std::string& path, int width, int height,
                    const std::vector<unsigned char>& rgb) {
  std::vector<unsigned char> bytes;
  const std::string why = oiio().encode_rgb8(path, width, height, rgb.data(), &bytes);
  if (!why.empty()) throw OutputError(fmt::format("{}: cannot write: {}", path, why));
  write_binary_file(path, bytes.data(), bytes.size());
}

void write_binary_file(const std::string& path, const void* data, std::size_t bytes) {
  write_output(path, [&](CheckedFile& file) { file.write(data, bytes); });
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

std::map<std::string, std::string> read_image_attributes(const std::string& path) {
  if (is_exr_file(path)) return read_exr_attributes(path);
  std::map<std::string, std::string> attributes;
  read_image(path, &attributes);
  return attributes;
}

std::string read_image_attribute(const std::string& path, const std::string& name) {
  const auto attributes = read_image_attributes(path);
  const auto it = attributes.find(name);
  return it == attributes.end() ? std::string() : it->second;
}

Image read_image(const std::string& path, std::map<std::string, std::string>* attributes) {
  if (is_exr_file(path)) return read_exr_file(path, attributes);
  Image image;
  const std::string why = oiio().read(path, &image, attributes);
  if (!why.empty()) throw std::runtime_error(fmt::format("{}: cannot read: {}", path, why));
  if (image.width <= 0 || image.height <= 0 || image.channels.empty())
    throw std::runtime_error(fmt::format("{}: an empty image ({}x{}, {} channels)", path,
                                         image.width, image.height, image.channels.size()));
  return image;
}

}  // namespace penumbra
