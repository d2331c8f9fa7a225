// The interface of penumbra_oiio, a module that Penumbra loads with dlopen
// the first time it reads or writes a format other than OpenEXR (PNG
// previews, a user's PNG or TIFF in `compare`). Loading it on demand keeps
// OpenImageIO's ~260 shared libraries out of every process that only
// renders and caches EXR. Both sides are built together from this tree, so
// the interface may pass C++ types; `abi` guards against a stale module.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "image/image.h"

namespace penumbra {

inline constexpr int kOiioModuleAbi = 3;  // 2: encode_rgb8 to memory; 3: read_header

struct OiioModule {
  int abi = kOiioModuleAbi;
  // Each returns "" on success, else OpenImageIO's reason; neither throws.
  // An 8-bit RGB image, row-major from the top, encoded in memory in the
  // format of the file name's extension (Penumbra writes the bytes itself,
  // checking each write: util/files.h).
  std::string (*encode_rgb8)(const std::string& path, int width, int height,
                             const unsigned char* rgb, std::vector<unsigned char>* bytes) = nullptr;
  // The size and channel names the header declares, without pixels: the
  // caller checks them before `read` allocates.
  std::string (*read_header)(const std::string& path, Image* image) = nullptr;
  // Every channel as float; with `attributes`, also the string attributes.
  std::string (*read)(const std::string& path, Image* image,
                      std::map<std::string, std::string>* attributes) = nullptr;
};

}  // namespace penumbra

// The module's one exported symbol.
extern "C" const penumbra::OiioModule* penumbra_oiio_module();
