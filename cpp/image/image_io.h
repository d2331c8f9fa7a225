// Image files: OpenEXR directly, other formats through OpenImageIO (loaded
// on demand, see oiio_module.h). Writes go to a temporary name in the
// target folder and are renamed into place, so a failed or interrupted write
// never leaves a file that looks like a result.
#pragma once

#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "image/image.h"

namespace penumbra {

// Cannot write an output (bad path, full disk): reported as bad input.
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The most memory an image file may take once read (every channel as 32-bit
// float: width x height x channels x 4 bytes), checked against the size its
// header declares before any pixel is decoded, since a 65-byte PNG can
// declare 65536 x 65536. docs/scene-format.md documents it.
inline constexpr double kMaxImageReadBytes = 2.0 * 1024 * 1024 * 1024;

// Lowers the limit while it lives, for a command's --max-memory; the limit
// in force is the smallest of kMaxImageReadBytes and every live scope's.
class ImageReadLimit {
 public:
  explicit ImageReadLimit(double max_bytes);
  ~ImageReadLimit();
  ImageReadLimit(const ImageReadLimit&) = delete;
  ImageReadLimit& operator=(const ImageReadLimit&) = delete;

 private:
  double previous_;
};

// InputError naming `path` when an image of this size would take more than
// the limit; also refuses a size or channel count of zero.
void check_declared_image(const std::string& path, long long width, long long height,
                          std::size_t channels);

// Throws OutputError naming the file when `image` holds NaN or Inf: every
// image writer calls it before the file is renamed into place, so that no
// command reports success over a non-finite output.
void check_finite_output(const Image& image, const std::string& path);

// Fails early, before a long render, when `path` cannot be created.
void check_writable(const std::string& path);

// Loads the OpenImageIO module that formats other than OpenEXR need, so that
// a command fails before its work rather than after; throws why it cannot.
void load_image_formats();

// Linear 32-bit float OpenEXR, ZIP compressed, with string metadata.
void write_exr(const Image& image, const std::string& path,
               const std::vector<std::pair<std::string, std::string>>& metadata = {});
// 8-bit sRGB PNG of R, G, B over black (no alpha) for a person to look at
// (values clamped to [0,1]).
void write_preview_png(const Image& image, const std::string& path);
// An 8-bit RGB PNG of display values (no colour conversion), row-major from the top.
void write_png_rgb8(const std::string& path, int width, int height,
                    const std::vector<unsigned char>& rgb);
// Any file, through the same temporary name and rename.
void write_binary_file(const std::string& path, const void* data, std::size_t bytes);
void write_text_file(const std::string& path, const std::string& text);
// A string attribute of an image file's header ("" if absent).
std::string read_image_attribute(const std::string& path, const std::string& name);
// Every string attribute of an image file's header (EXR: without its pixels).
std::map<std::string, std::string> read_image_attributes(const std::string& path);
// 16 hex digits: FNV-1a over the size, channel names and float bits of the
// pixels. Stored in cache entries so that damage to them is detected.
std::string image_checksum(const Image& image);

// Reads any file OpenImageIO can read, all channels as float; with
// `attributes`, also every string attribute of its header. A file that is
// not a regular file, declares more than the limit above or cannot be
// decoded is InputError, one line naming it (the decoders' own messages,
// which libpng prints to stderr, are folded into that line).
Image read_image(const std::string& path, std::map<std::string, std::string>* attributes = nullptr);

}  // namespace penumbra
