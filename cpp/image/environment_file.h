// Environment maps from files: a latitude-longitude radiance image read
// through OpenImageIO into the core's EnvironmentMap (core/environment.h).
#pragma once

#include <memory>
#include <string>

#include "core/environment.h"

namespace penumbra {

struct LoadedEnvironment {
  std::shared_ptr<const EnvironmentMap> map;
  std::string digest;        // content digest of the texels read and the size
  std::size_t negative = 0;  // texels below 0 (lossy compression), read as 0
};

// One radiance channel per texel: the Rec. 709 luminance 0.2126 R +
// 0.7152 G + 0.0722 B of a file with R, G and B, else its only channel.
// InputError naming the file for a file OpenImageIO cannot read, one that
// does not store floating-point texels (half, float, double: an 8-bit image
// holds display values, not radiance), one smaller than 2 x 2, and a NaN or
// infinite texel (with its position). Maps already read in this process
// are shared while the file's size and modification time stay the same.
LoadedEnvironment load_environment_map(const std::string& path, double rotation_rad);

}  // namespace penumbra
