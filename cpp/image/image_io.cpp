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
#include <mutex>

#include <dlfcn.h>
#include <fmt/format.h>

#include "image/exr_file.h"
#include "image/oiio_module.h"
#include "util/data_files.h"
#include "util/files.h"
#include "util/hash.h"
#include "util/strict_json.h"

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
      tried += fmt::format("; {}", ::dlerror());
      continue;
    }
    using Entry = const OiioModule* (*)();
    const auto entry = reinterpret_cast<Entry>(::dlsym(handle, "penumbra_oiio_module"));
    const OiioModule* module = entry ? entry() : nullptr;
    if (module && module->abi == kOiioModuleAbi) return module;
    tried += fmt::format("; {}: not a module of this Penumbra build", file.string());
  }
  throw std::runtime_error(
      "image formats other than OpenEXR need Penumbra's OpenImageIO module "
      "lib/penumbra/libpenumbra_oiio.so, which could not be loaded from beside the executable "
      "or from its parent folder" +
      tried);
}

// Loaded once, on the first non-EXR file; a failed load is retried on the
// next call (a throwing static initialiser runs again).
const OiioModule& oiio() {
  static const OiioModule* module = load_oiio_module();
  return *module;
}

// What libpng and other decoders print to stderr while a call runs: taken
// out of the stream and handed to the caller, so that a bad file gives one
// line. Reads are serialised here, since fd 2 is the process's.
class StderrCapture {
 public:
  StderrCapture() : lock_(mutex()) {
    std::fflush(stderr);
    file_ = std::tmpfile();
    saved_ = file_ ? ::dup(STDERR_FILENO) : -1;
    if (saved_ >= 0) ::dup2(::fileno(file_), STDERR_FILENO);
  }
  ~StderrCapture() {
    restore();
    if (file_) std::fclose(file_);
  }
  StderrCapture(const StderrCapture&) = delete;
  StderrCapture& operator=(const StderrCapture&) = delete;

  // Restores stderr and returns what was printed meanwhile.
  std::string take() {
    restore();
    std::string text;
    if (!file_) return text;
    std::rewind(file_);
    char buffer[512];
    std::size_t n = 0;
    while (text.size() < 4096 && (n = std::fread(buffer, 1, sizeof buffer, file_)) > 0)
      text.append(buffer, n);
    return text;
  }

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  void restore() {
    if (saved_ < 0) return;
    std::fflush(stderr);
    ::dup2(saved_, STDERR_FILENO);
    ::close(saved_);
    saved_ = -1;
  }
  std::lock_guard<std::mutex> lock_;
  std::FILE* file_ = nullptr;
  int saved_ = -1;
};

// A decoder's messages as part of one line: lines joined with "; ".
std::string one_line(std::string text) {
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  std::string out;
  for (char c : text) out += c == '\n' ? std::string("; ") : std::string(1, c);
  return out;
}

double& read_limit() {
  static double limit = kMaxImageReadBytes;
  return limit;
}

// Reads a non-EXR file through the module, its header first.
Image read_with_module(const std::string& path, std::map<std::string, std::string>* attributes) {
  const OiioModule& module = oiio();
  Image image;
  StderrCapture capture;
  std::string why = module.read_header(path, &image);
  if (why.empty()) {
    check_declared_image(path, image.width, image.height, image.channels.size());
    why = module.read(path, &image, attributes);
  }
  const std::string printed = one_line(capture.take());
  if (why.empty()) {
    if (!printed.empty()) std::fprintf(stderr, "%s\n", printed.c_str());
    return image;
  }
  why = one_line(why);
  if (!printed.empty() && why.find(printed) == std::string::npos) why += " (" + printed + ")";
  throw InputError(path, "", "cannot read it as an image: " + why);
}

// The sRGB transfer function of IEC 61966-2-1, to 8 bits with rounding.
unsigned char encode_srgb8(float linear) {
  const double v = std::clamp(double(linear), 0.0, 1.0);
  const double encoded = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
  return static_cast<unsigned char>(std::lround(encoded * 255.0));
}

}  // namespace

ImageReadLimit::ImageReadLimit(double max_bytes) : previous_(read_limit()) {
  read_limit() = std::min(previous_, max_bytes);
}

ImageReadLimit::~ImageReadLimit() {
  read_limit() = previous_;
}

void check_declared_image(const std::string& path, long long width, long long height,
                          std::size_t channels) {
  if (width <= 0 || height <= 0 || channels == 0)
    throw InputError(path, "",
                     fmt::format("declares an empty image ({}x{} pixels, {} channels); expected "
                                 "at least 1x1 with a channel",
                                 width, height, channels));
  const double bytes = double(width) * double(height) * double(channels) * sizeof(float);
  if (bytes > read_limit())
    throw InputError(path, "",
                     fmt::format("declares {}x{} pixels with {} channels, {:.3g} GiB as float; "
                                 "expected at most {:.3g} GiB (the image-size limit, or "
                                 "--max-memory); not decoded",
                                 width, height, channels, bytes / double(1 << 30),
                                 read_limit() / double(1 << 30)));
}

void check_finite_output(const Image& image, const std::string& path) {
  const std::size_t bad = count_nonfinite(image);
  if (bad > 0)
    throw OutputError(fmt::format("{}: would hold {} NaN or Inf values (of {}); not written",
                                  printable(path, 240), bad, image.pixels.size()));
}

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
  check_finite_output(image, path);
  write_output(path, [&](CheckedFile& file) { write_exr_file(image, file, metadata); });
}

void write_preview_png(const Image& image, const std::string& path) {
  const int r = image.channel_index("R"), g = image.channel_index("G"),
            b = image.channel_index("B");
  if (r < 0 || g < 0 || b < 0)
    throw std::runtime_error(fmt::format("{}: a preview needs channels R, G and B", path));
  check_finite_output(image, path);
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
  if (const std::string problem = input_file_problem(path); !problem.empty())
    throw InputError(path, "", problem);
  if (is_exr_file(path)) return read_exr_file(path, attributes);
  return read_with_module(path, attributes);
}

}  // namespace penumbra
