#include "image/exr_file.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStandardAttributes.h>
#include <ImfStdIO.h>
#include <ImfStringAttribute.h>
#include <ImfXdr.h>
#include <fmt/format.h>

#include "image/image_io.h"
#include "util/strict_json.h"

namespace penumbra {
namespace {

// OpenImageIO's order: the colour and alpha channels first, so that code
// and tools that take "the first three channels" see R, G, B.
int channel_rank(const std::string& name) {
  static const std::array<const char*, 4> first{"R", "G", "B", "A"};
  for (std::size_t i = 0; i < first.size(); ++i)
    if (name == first[i]) return static_cast<int>(i);
  return static_cast<int>(first.size());
}

// Interleaved float slices of `image`, shifted so that pixel (x0, y0) of the
// file's data window lands on the first pixel.
Imf::FrameBuffer frame_buffer(Image& image, int x0, int y0) {
  const std::size_t nc = image.channels.size();
  const std::size_t x_stride = nc * sizeof(float);
  const std::size_t y_stride = x_stride * std::size_t(image.width);
  Imf::FrameBuffer buffer;
  for (std::size_t c = 0; c < nc; ++c) {
    char* base = reinterpret_cast<char*>(image.pixels.data() + c) -
                 std::ptrdiff_t(x0) * std::ptrdiff_t(x_stride) -
                 std::ptrdiff_t(y0) * std::ptrdiff_t(y_stride);
    buffer.insert(image.channels[c], Imf::Slice(Imf::FLOAT, base, x_stride, y_stride));
  }
  return buffer;
}

void string_attributes(const Imf::Header& header, std::map<std::string, std::string>* out) {
  for (auto it = header.begin(); it != header.end(); ++it)
    if (const auto* s = dynamic_cast<const Imf::StringAttribute*>(&it.attribute()))
      (*out)[it.name()] = s->value();
}

// Most tiles a file may declare: InputFile allocates a table of 8 bytes
// per tile before the first pixel, and 1x1 tiles make it as long as the image.
constexpr long long kMaxExrTiles = 1LL << 22;

// The first header alone, checked before InputFile builds its offset tables
// from it (their size follows the declared data window and tiles).
void check_exr_header(const std::string& path) {
  Imf::StdIFStream in(path.c_str());
  int magic = 0, version = 0;
  Imf::Xdr::read<Imf::StreamIO>(in, magic);
  Imf::Xdr::read<Imf::StreamIO>(in, version);
  Imf::Header header;
  header.readFrom(in, version);
  const Imath::Box2i window = header.dataWindow();
  const long long width = 1LL + window.max.x - window.min.x;
  const long long height = 1LL + window.max.y - window.min.y;
  std::size_t channels = 0;
  for (auto it = header.channels().begin(); it != header.channels().end(); ++it) ++channels;
  check_declared_image(path, width, height, channels);
  if (!header.hasTileDescription()) return;
  const Imf::TileDescription& tiles = header.tileDescription();
  const long long count = ((width + tiles.xSize - 1) / std::max(1u, tiles.xSize)) *
                          ((height + tiles.ySize - 1) / std::max(1u, tiles.ySize));
  if (tiles.xSize == 0 || tiles.ySize == 0 || count > kMaxExrTiles)
    throw InputError(path, "",
                     fmt::format("declares {}x{} tiles of {}x{} pixels; expected at most {} tiles",
                                 width, height, tiles.xSize, tiles.ySize, kMaxExrTiles));
}

// OpenEXR's output stream over a CheckedFile: OpenEXR writes the offset
// table in OutputFile's destructor and swallows what that throws, so the
// file keeps the failure for CheckedFile::finish() to throw.
class CheckedStream : public Imf::OStream {
 public:
  explicit CheckedStream(CheckedFile& file) : Imf::OStream("penumbra output"), file_(file) {}
  void write(const char c[], int n) override { file_.write(c, std::size_t(n)); }
  uint64_t tellp() override { return file_.tell(); }
  void seekp(uint64_t position) override { file_.seek(position); }

 private:
  CheckedFile& file_;
};

}  // namespace

bool is_exr_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char magic[4] = {};
  if (!in.read(reinterpret_cast<char*>(magic), sizeof magic)) return false;
  return magic[0] == 0x76 && magic[1] == 0x2f && magic[2] == 0x31 && magic[3] == 0x01;
}

void write_exr_file(const Image& image, CheckedFile& out,
                    const std::vector<std::pair<std::string, std::string>>& attributes) {
  try {
    Imf::Header header(image.width, image.height);
    header.compression() = Imf::ZIP_COMPRESSION;
    header.zipCompressionLevel() = 1;
    for (const std::string& name : image.channels)
      header.channels().insert(name, Imf::Channel(Imf::FLOAT));
    for (const auto& [key, value] : attributes) header.insert(key, Imf::StringAttribute(value));
    // The frame buffer only reads from the image; OpenEXR's Slice takes char*.
    Image& pixels = const_cast<Image&>(image);
    CheckedStream stream(out);
    Imf::OutputFile file(stream, header);
    file.setFrameBuffer(frame_buffer(pixels, 0, 0));
    file.writePixels(image.height);
  } catch (const std::exception& e) {
    throw std::runtime_error(e.what());
  }
}

Image read_exr_file(const std::string& path, std::map<std::string, std::string>* attributes) {
  try {
    check_exr_header(path);
    Imf::InputFile file(path.c_str());
    const Imf::Header& header = file.header();
    const Imath::Box2i window = header.dataWindow();
    Image image;
    // In 64 bits: a hostile data window overflows int.
    const long long width = 1LL + window.max.x - window.min.x;
    const long long height = 1LL + window.max.y - window.min.y;
    for (auto it = header.channels().begin(); it != header.channels().end(); ++it) {
      if (it.channel().xSampling != 1 || it.channel().ySampling != 1)
        throw std::runtime_error(
            fmt::format("channel \"{}\" is subsampled, which Penumbra does not read", it.name()));
      image.channels.emplace_back(it.name());
    }
    std::stable_sort(image.channels.begin(), image.channels.end(),
                     [](const std::string& a, const std::string& b) {
                       return channel_rank(a) < channel_rank(b);
                     });
    check_declared_image(path, width, height, image.channels.size());
    image.width = int(width), image.height = int(height);
    image.pixels.assign(std::size_t(image.width) * image.height * image.channels.size(), 0.0f);
    file.setFrameBuffer(frame_buffer(image, window.min.x, window.min.y));
    file.readPixels(window.min.y, window.max.y);
    if (attributes) string_attributes(header, attributes);
    return image;
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(path, "", fmt::format("cannot read it as OpenEXR: {}", e.what()));
  }
}

std::map<std::string, std::string> read_exr_attributes(const std::string& path) {
  try {
    check_exr_header(path);
    Imf::InputFile file(path.c_str());
    std::map<std::string, std::string> attributes;
    string_attributes(file.header(), &attributes);
    return attributes;
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(path, "", fmt::format("cannot read it as OpenEXR: {}", e.what()));
  }
}

void write_exr_file(const Image& image, const std::string& path,
                    const std::vector<std::pair<std::string, std::string>>& attributes) {
  write_atomically(path, [&](CheckedFile& file) { write_exr_file(image, file, attributes); });
}

}  // namespace penumbra
