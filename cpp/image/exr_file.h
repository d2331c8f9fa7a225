// OpenEXR files through the OpenEXR library itself rather than OpenImageIO:
// every render, cache entry and comparison reads and writes EXR, and a
// process linked against OpenImageIO maps about 260 shared libraries at
// start-up (0.3 s and 130 MiB before the first pixel). OpenImageIO stays,
// loaded on demand, for every other format (image_io.cpp).
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "image/image.h"
#include "util/files.h"

namespace penumbra {

// True when the file starts with the OpenEXR magic number (false for a
// missing or unreadable file: the reader then says why).
bool is_exr_file(const std::string& path);

// Writes `image` as 32-bit float channels, ZIP compressed, with string
// attributes, into `file` (write_atomically gives it and finishes it).
// Throws std::runtime_error with OpenEXR's reason or the write's.
void write_exr_file(const Image& image, CheckedFile& file,
                    const std::vector<std::pair<std::string, std::string>>& attributes);
// The same into `path` (write_atomically), without write_exr's finiteness
// check: for tests and tools that write non-finite values on purpose.
void write_exr_file(const Image& image, const std::string& path,
                    const std::vector<std::pair<std::string, std::string>>& attributes);

// Reads the first part's data window, every channel as float, channels
// ordered R, G, B, A first, then as stored (sorted by name), which is the
// order OpenImageIO gave. With `attributes`, also the header's string
// attributes. Throws std::runtime_error naming the file.
Image read_exr_file(const std::string& path, std::map<std::string, std::string>* attributes);

// The header's string attributes, without reading pixels.
std::map<std::string, std::string> read_exr_attributes(const std::string& path);

}  // namespace penumbra
