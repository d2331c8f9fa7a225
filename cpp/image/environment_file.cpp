#include "image/environment_file.h"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <mutex>

#include "image/exr_file.h"
#include "image/image_io.h"
#include "util/hash.h"
#include "util/strict_json.h"

namespace fs = std::filesystem;

namespace penumbra {

namespace {

// The texels' radiance, row-major from the top row.
std::vector<float> radiance_channel(const Image& image, const std::string& path,
                                    std::size_t* negative) {
  const int r = image.channel_index("R"), g = image.channel_index("G"),
            b = image.channel_index("B");
  const bool rgb = r >= 0 && g >= 0 && b >= 0;
  if (!rgb && image.channels.size() != 1)
    throw InputError(path, "",
                     fmt::format("has {} channels and no R, G, B; an environment map needs R, "
                                 "G and B, or one channel",
                                 image.channels.size()));
  std::vector<float> out(std::size_t(image.width) * image.height);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const double value =
          rgb ? 0.2126 * image.at(x, y, r) + 0.7152 * image.at(x, y, g) + 0.0722 * image.at(x, y, b)
              : double(image.at(x, y, 0));
      if (!std::isfinite(value))
        throw InputError(path, "",
                         fmt::format("holds {} at texel ({}, {}) (column, row from the top); "
                                     "radiance must be finite",
                                     value, x, y));
      if (value < 0.0) ++*negative;
      out[std::size_t(y) * image.width + x] = value < 0.0 ? 0.0f : float(value);
    }
  return out;
}

LoadedEnvironment read_environment(const std::string& path, double rotation_rad) {
  std::map<std::string, std::string> attributes;
  Image image;
  try {
    image = read_image(path, &attributes);
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(path, "", fmt::format("cannot read it as an image: {}", e.what()));
  }
  // OpenEXR stores half or float texels (Penumbra reads it itself); other
  // files say how through OpenImageIO.
  const std::string format = is_exr_file(path) ? "float" : attributes["penumbra:format"];
  if (format != "half" && format != "float" && format != "double")
    throw InputError(path, "",
                     fmt::format("stores {} texels; an environment map needs floating-point "
                                 "radiance (OpenEXR or Radiance HDR), not display values",
                                 format.empty() ? "unknown" : format));
  if (image.width < 2 || image.height < 2)
    throw InputError(path, "",
                     fmt::format("is {}x{}; an environment map needs at least 2x2 texels",
                                 image.width, image.height));
  LoadedEnvironment loaded;
  std::vector<float> radiance = radiance_channel(image, path, &loaded.negative);
  ContentDigest digest;
  const int size[2] = {image.width, image.height};
  digest.add(size, sizeof size);
  digest.add(radiance.data(), radiance.size() * sizeof(float));
  loaded.digest = digest.hex();
  loaded.map = std::make_shared<const EnvironmentMap>(std::move(radiance), image.width,
                                                      image.height, rotation_rad);
  return loaded;
}

}  // namespace

LoadedEnvironment load_environment_map(const std::string& path, double rotation_rad) {
  static std::mutex mutex;
  static std::map<std::string, LoadedEnvironment> loaded;
  std::error_code error;
  const auto size = fs::file_size(path, error);
  const auto time = fs::last_write_time(path, error);
  const std::string key = fmt::format("{}\n{:a}\n{}\n{}", path, rotation_rad, error ? 0 : size,
                                      error ? 0 : time.time_since_epoch().count());
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (const auto it = loaded.find(key); it != loaded.end()) return it->second;
  }
  LoadedEnvironment map = read_environment(path, rotation_rad);
  std::lock_guard<std::mutex> lock(mutex);
  if (loaded.size() > 16) loaded.clear();
  loaded[key] = map;
  return map;
}

}  // namespace penumbra
