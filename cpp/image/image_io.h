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
// `attributes`, also every string attribute of its header.
Image read_image(const std::string& path, std::map<std::string, std::string>* attributes = nullptr);

}  // namespace penumbra
