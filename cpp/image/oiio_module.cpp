// Built as the loadable module penumbra_oiio (see oiio_module.h); the only
// file in Penumbra that includes OpenImageIO.
#include "image/oiio_module.h"

#include <algorithm>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>

namespace penumbra {
namespace {

std::string encode_rgb8(const std::string& path, int width, int height, const unsigned char* rgb,
                        std::vector<unsigned char>* bytes) {
  auto output = OIIO::ImageOutput::create(path);
  if (!output) return OIIO::geterror();
  if (!output->supports("ioproxy"))
    return "OpenImageIO cannot write " + std::string(output->format_name()) + " to memory";
  OIIO::Filesystem::IOVecOutput memory(*bytes);
  OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
  OIIO::Filesystem::IOProxy* proxy = &memory;
  spec.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
  if (!output->open(path, spec) || !output->write_image(OIIO::TypeDesc::UINT8, rgb) ||
      !output->close()) {
    const std::string why = output->geterror();
    return why.empty() ? "OpenImageIO gave no reason" : why;
  }
  return {};
}

// One name per channel the file holds: some readers name fewer.
void take_spec(const OIIO::ImageSpec& spec, Image* image) {
  image->width = spec.width;
  image->height = spec.height;
  image->channels = spec.channelnames;
  const std::size_t count = std::size_t(std::max(spec.nchannels, 0));
  image->channels.resize(count);
  for (std::size_t c = 0; c < count; ++c)
    if (image->channels[c].empty()) image->channels[c] = "channel" + std::to_string(c);
}

std::string read_header(const std::string& path, Image* image) {
  auto input = OIIO::ImageInput::open(path);
  if (!input) return OIIO::geterror();
  take_spec(input->spec(), image);
  return {};
}

std::string read(const std::string& path, Image* image,
                 std::map<std::string, std::string>* attributes) {
  // ImageInput rather than ImageBuf: ImageBuf reads through OpenImageIO's
  // shared ImageCache, which serves a file's old pixels after it was replaced.
  auto input = OIIO::ImageInput::open(path);
  if (!input) return OIIO::geterror();
  const OIIO::ImageSpec spec = input->spec();
  take_spec(spec, image);
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0) return "an empty image";
  image->pixels.resize(std::size_t(spec.width) * spec.height * spec.nchannels);
  if (!input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image->pixels.data()))
    return input->geterror();
  if (attributes) {
    for (const OIIO::ParamValue& p : spec.extra_attribs)
      if (p.type() == OIIO::TypeDesc::STRING) (*attributes)[p.name().string()] = p.get_string();
    // How the file stores its texels ("half", "float", "uint8", ...):
    // environment maps refuse display values (image/environment_file.h).
    (*attributes)["penumbra:format"] = spec.format.c_str();
  }
  return {};
}

}  // namespace
}  // namespace penumbra

extern "C" __attribute__((visibility("default"))) const penumbra::OiioModule*
penumbra_oiio_module() {
  static const penumbra::OiioModule module{penumbra::kOiioModuleAbi, penumbra::encode_rgb8,
                                           penumbra::read_header, penumbra::read};
  return &module;
}
