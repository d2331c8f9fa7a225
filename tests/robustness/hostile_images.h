// Image files that lie: PNG and OpenEXR bytes written by hand or patched, so
// that a header can declare any size, channel count or pixel type without
// the pixels behind it. Shared by the hostile-input tests and the fuzzer.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace penumbra {

inline void append_be32(std::string& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out += static_cast<char>((v >> shift) & 0xff);
}

inline std::uint32_t crc32(const std::string& bytes) {
  std::uint32_t c = 0xffffffffu;
  for (unsigned char b : bytes) {
    c ^= b;
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
  }
  return c ^ 0xffffffffu;
}

inline std::string png_chunk(const std::string& type, const std::string& data) {
  std::string out;
  append_be32(out, static_cast<std::uint32_t>(data.size()));
  const std::string body = type + data;
  out += body;
  append_be32(out, crc32(body));
  return out;
}

// A zlib stream of `raw` in one stored (uncompressed) deflate block.
inline std::string zlib_stored(const std::string& raw) {
  std::string out = "\x78\x01";
  out += '\x01';
  const auto n = static_cast<std::uint16_t>(raw.size());
  out += static_cast<char>(n & 0xff), out += static_cast<char>(n >> 8);
  out += static_cast<char>(~n & 0xff), out += static_cast<char>((~n >> 8) & 0xff);
  out += raw;
  std::uint32_t a = 1, b = 0;
  for (unsigned char c : raw) a = (a + c) % 65521, b = (b + a) % 65521;
  append_be32(out, (b << 16) | a);
  return out;
}

// A PNG whose IHDR declares width x height at `bit_depth` and `colour_type`,
// followed by `rows` of filtered scanline bytes (none: a lying header).
inline std::string png_bytes(std::uint32_t width, std::uint32_t height, int bit_depth,
                             int colour_type, const std::string& rows = std::string(2, '\0')) {
  std::string ihdr;
  append_be32(ihdr, width);
  append_be32(ihdr, height);
  ihdr += static_cast<char>(bit_depth), ihdr += static_cast<char>(colour_type);
  ihdr += std::string(3, '\0');  // compression, filter, interlace
  std::string out = "\x89PNG\r\n\x1a\n";
  out += png_chunk("IHDR", ihdr);
  if (colour_type == 3) out += png_chunk("PLTE", std::string(3, '\x7f'));
  out += png_chunk("IDAT", zlib_stored(rows));
  out += png_chunk("IEND", "");
  return out;
}

inline std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

// Where the value of an OpenEXR header attribute starts ("NAME\0TYPE\0" +
// 4-byte size), or npos.
inline std::size_t exr_attribute(const std::string& bytes, const std::string& name,
                                 const std::string& type) {
  const std::string key = name + std::string(1, '\0') + type + std::string(1, '\0');
  const std::size_t at = bytes.find(key);
  return at == std::string::npos ? at : at + key.size() + 4;
}

inline void put_le32(std::string& bytes, std::size_t at, std::int32_t v) {
  for (int k = 0; k < 4; ++k)
    bytes[at + k] = static_cast<char>((std::uint32_t(v) >> (8 * k)) & 0xff);
}

// An OpenEXR file's bytes with its data window set to [x0, x1] x [y0, y1].
inline std::string exr_with_window(std::string bytes, std::int32_t x0, std::int32_t y0,
                                   std::int32_t x1, std::int32_t y1) {
  const std::size_t at = exr_attribute(bytes, "dataWindow", "box2i");
  if (at == std::string::npos || at + 16 > bytes.size()) return bytes;
  put_le32(bytes, at, x0), put_le32(bytes, at + 4, y0);
  put_le32(bytes, at + 8, x1), put_le32(bytes, at + 12, y1);
  return bytes;
}

// An OpenEXR file's bytes with an empty channel list (OpenEXR will not
// write one). Only the header is consistent afterwards.
inline std::string exr_without_channels(const std::string& bytes) {
  const std::size_t at = exr_attribute(bytes, "channels", "chlist");
  if (at == std::string::npos) return bytes;
  std::uint32_t size = 0;
  for (int k = 0; k < 4; ++k)
    size |= std::uint32_t(static_cast<unsigned char>(bytes[at - 4 + k])) << (8 * k);
  if (at + size > bytes.size()) return bytes;
  return bytes.substr(0, at - 4) + std::string("\x01\x00\x00\x00", 4) + std::string(1, '\0') +
         bytes.substr(at + size);
}

// What the process writes to file descriptor 2 while this lives (libpng
// writes there, not to the stream a command is given).
class Fd2Capture {
 public:
  Fd2Capture() {
    std::fflush(stderr);
    file_ = std::tmpfile();
    saved_ = ::dup(2);
    ::dup2(::fileno(file_), 2);
  }
  ~Fd2Capture() { text(); }
  Fd2Capture(const Fd2Capture&) = delete;
  Fd2Capture& operator=(const Fd2Capture&) = delete;
  std::string text() {
    if (saved_ >= 0) {
      std::fflush(stderr);
      ::dup2(saved_, 2);
      ::close(saved_);
      saved_ = -1;
      std::rewind(file_);
      char buffer[4096];
      std::size_t n = 0;
      while ((n = std::fread(buffer, 1, sizeof buffer, file_)) > 0) text_.append(buffer, n);
      std::fclose(file_);
    }
    return text_;
  }

 private:
  std::FILE* file_ = nullptr;
  int saved_ = -1;
  std::string text_;
};

}  // namespace penumbra
