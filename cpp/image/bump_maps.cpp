#include "image/bump_maps.h"

#include <fmt/format.h>

#include <ImfThreading.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <thread>

#include "image/image_io.h"
#include "util/files.h"
#include "util/strict_json.h"
#include "util/version.h"

namespace fs = std::filesystem;

namespace penumbra {

namespace {

std::string channel_list(const Image& image) {
  std::string list;
  for (const std::string& name : image.channels) list += (list.empty() ? "" : ", ") + name;
  return list;
}

int pick_channel(const Image& image, const std::string& path, const std::string& channel) {
  if (channel.empty()) {
    if (image.channels.size() == 1) return 0;
    throw InputError(path, "",
                     fmt::format("has {} channels ({}); name the height channel",
                                 image.channels.size(), channel_list(image)));
  }
  const int index = image.channel_index(channel);
  if (index < 0)
    throw InputError(
        path, "", fmt::format("has no channel \"{}\" (it has {})", channel, channel_list(image)));
  return index;
}

Image read_map_image(const std::string& path) {
  Image image;
  try {
    image = read_image(path);  // InputError naming the file
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(path, "", fmt::format("cannot read it as an image: {}", e.what()));
  }
  if (image.width <= 0 || image.height <= 0)
    throw InputError(path, "", fmt::format("is empty ({}x{})", image.width, image.height));
  return image;
}

// The three channels of a normal map: R, G, B, or the file's only three.
std::array<int, 3> normal_channels(const Image& image, const std::string& path) {
  const std::array<int, 3> rgb{image.channel_index("R"), image.channel_index("G"),
                               image.channel_index("B")};
  if (rgb[0] >= 0 && rgb[1] >= 0 && rgb[2] >= 0) return rgb;
  if (image.channels.size() == 3) return {0, 1, 2};
  throw InputError(path, "",
                   fmt::format("has channels {}; a normal map needs R, G and B (or exactly three "
                               "channels)",
                               channel_list(image)));
}

SurfaceMap read_surface_map(const std::string& path, MapKind kind, const std::string& channel) {
  SurfaceMap map;
  map.kind = kind;
  if (kind == MapKind::kHeight) {
    HeightMap h = read_height_map(path, channel);
    map.width = h.width, map.height = h.height;
    map.texels = std::move(h.heights);
  } else {
    const Image image = read_map_image(path);
    const std::array<int, 3> c = normal_channels(image, path);
    map.width = image.width, map.height = image.height;
    map.texels.resize(std::size_t(image.width) * image.height * 3);
    for (int y = 0; y < image.height; ++y)
      for (int x = 0; x < image.width; ++x)
        for (int k = 0; k < 3; ++k) {
          const float value = image.at(x, y, c[k]);
          if (!std::isfinite(value))
            throw InputError(path, "",
                             fmt::format("channel {} holds {} at texel ({}, {}) (column, row from "
                                         "the top); normals must be finite",
                                         image.channels[c[k]], value, x, y));
          map.texels[(std::size_t(y) * image.width + x) * 3 + k] = value;
        }
  }
  map.digest = map_digest(map);
  return map;
}

}  // namespace

std::shared_ptr<const SurfaceMap> load_surface_map(const std::string& path, MapKind kind,
                                                   const std::string& channel) {
  // A study reads each of its scenes once per render job; the map behind
  // them is read once.
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const SurfaceMap>> loaded;
  std::error_code error;
  const auto size = fs::file_size(path, error);
  const auto time = fs::last_write_time(path, error);
  const std::string key =
      fmt::format("{}\n{}\n{}\n{}\n{}", path, static_cast<int>(kind), channel, error ? 0 : size,
                  error ? 0 : time.time_since_epoch().count());
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (const auto it = loaded.find(key); it != loaded.end()) return it->second;
  }
  auto map = std::make_shared<const SurfaceMap>(read_surface_map(path, kind, channel));
  std::lock_guard<std::mutex> lock(mutex);
  if (loaded.size() > 64) loaded.clear();
  loaded[key] = map;
  return map;
}

Image bake_surface_map(const Shape& shape, const HeightFunction& f, double amplitude, int width,
                       int height, MapKind kind) {
  if (width < 1 || height < 1) throw std::invalid_argument("baking needs a size of at least 1x1");
  Image image;
  image.width = width, image.height = height;
  image.channels = kind == MapKind::kHeight ? std::vector<std::string>{"Y"}
                                            : std::vector<std::string>{"R", "G", "B"};
  image.pixels.resize(std::size_t(width) * height * image.channels.size());
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const double u = (x + 0.5) / width, v = 1.0 - (y + 0.5) / height;
      const SurfaceGeometry g = surface_at_parameters(shape, u, v);
      const HeightSample h = evaluate_height(f, g.p);
      if (kind == MapKind::kHeight) {
        image.at(x, y, 0) = float(amplitude * h.h);
        continue;
      }
      const SurfaceParameters q = surface_parameters(shape, g.p);
      const Vec3 n = displaced_normal(g, amplitude, h);
      const Vec3 tangent = normalize(q.dp_du), bitangent = normalize(q.dp_dv);
      const Vec3 local{dot(n, tangent), dot(n, bitangent), dot(n, g.n)};
      for (int k = 0; k < 3; ++k) image.at(x, y, k) = float(0.5 * local[k] + 0.5);
    }
  return image;
}

HeightMap read_height_map(const std::string& path, const std::string& channel) {
  const Image image = read_map_image(path);
  const int index = pick_channel(image, path, channel);
  HeightMap map{image.width, image.height, {}, image.channels[index]};
  map.heights.resize(std::size_t(image.width) * image.height);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const float h = image.at(x, y, index);
      if (!std::isfinite(h))
        throw InputError(path, "",
                         fmt::format("channel {} holds {} at texel ({}, {}) (column, row from "
                                     "the top); heights must be finite",
                                     map.channel, h, x, y));
      map.heights[std::size_t(y) * image.width + x] = h;
    }
  return map;
}

void check_map_slopes(const HeightMap& map, const std::string& path, double texel_size,
                      double height_scale) {
  // Neighbours across the edge count too: conservative for a clamped edge.
  double steepest = 0.0;
  const auto at = [&](int x, int y) { return double(map.heights[std::size_t(y) * map.width + x]); };
  for (int y = 0; y < map.height; ++y)
    for (int x = 0; x < map.width; ++x) {
      const double h = at(x, y);
      steepest = std::max({steepest, std::abs(at((x + 1) % map.width, y) - h),
                           std::abs(at(x, (y + 1) % map.height) - h)});
    }
  const double slope = steepest * std::abs(height_scale) / texel_size;
  if (!(slope <= kMaxMapSlope))
    throw InputError(path, "",
                     fmt::format("heights x --height-scale {:.6g} / --texel-size {:.6g} give "
                                 "slopes up to {:.3g}; expected at most {:.0e}, so that the "
                                 "pyramid's squared slopes stay finite",
                                 height_scale, texel_size, slope, kMaxMapSlope));
}

Image bake_height_map(const HeightFunction& f, double amplitude, int size, double extent) {
  if (size < 1 || !(extent > 0.0) || !std::isfinite(extent))
    throw std::invalid_argument("baking needs size >= 1 and a finite extent > 0");
  Image image;
  image.width = image.height = size;
  image.channels = {"Y"};
  image.pixels.resize(std::size_t(size) * size);
  const double t = extent / size;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x)
      image.at(x, y, 0) =
          float(amplitude * evaluate_height(f, Vec3((x + 0.5) * t, (size - y - 0.5) * t, 0.0)).h);
  return image;
}

Image pyramid_level_image(const PyramidLevel& level) {
  Image image;
  image.width = level.width;
  image.height = level.height;
  image.channels = {"bump.f_u",     "bump.f_v",          "roughness.d1", "roughness.d2",
                    "roughness.d3", "roughness.lambda1", "normal.length"};
  image.pixels.resize(std::size_t(level.width) * level.height * image.channels.size());
  for (int y = 0; y < level.height; ++y)
    for (int x = 0; x < level.width; ++x) {
      const Covariance2 k = level.covariance(x, y);
      const RoughnessFactor d = roughness_factor(k);
      const std::size_t i = level.index(x, y);
      const float values[] = {level.f_u[i],
                              level.f_v[i],
                              float(d.d1),
                              float(d.d2),
                              float(d.d3),
                              float(isotropic_roughness(k)),
                              float(length(level.mean_normal(x, y)))};
      for (int c = 0; c < 7; ++c) image.at(x, y, c) = values[c];
    }
  return image;
}

namespace {

nlohmann::json manifest(const std::vector<PyramidLevel>& levels, const PyramidSource& source) {
  nlohmann::json list = nlohmann::json::array();
  for (std::size_t l = 0; l < levels.size(); ++l)
    list.push_back({{"level", l},
                    {"file", fmt::format("level_{:02}.exr", l)},
                    {"width", levels[l].width},
                    {"height", levels[l].height},
                    {"finest_texels_per_texel", 1L << (2 * l)}});
  return {
      {"format", "penumbra-bump-pyramid"},
      {"version", 1},
      {"penumbra", kPenumbraVersion},
      {"source", {{"file", source.path}, {"channel", source.channel}}},
      {"texel_size", source.texel_size},
      {"height_scale", source.height_scale},
      {"edge", name_of<MapEdge>(kMapEdgeNames, source.edge)},
      {"conventions",
       "offsets f_u = dh/du, f_v = dh/dv by central differences (one-sided at a clamped edge), "
       "u along columns, v up (against rows); h = height_scale x file value; offsets are "
       "slopes (scene units per scene unit) with texel_size in scene units. Level l texel "
       "(x, y) covers finest texels [x 2^l, (x+1) 2^l) x [y 2^l, (y+1) 2^l). roughness: "
       "D = [[d1, d2], [0, d3]], D D^T = K, the covariance of the covered finest offsets "
       "(Schilling's recursion); lambda1 = sqrt of K's largest eigenvalue. normal.length: length "
       "of the mean of the covered unit normals (f_u, f_v, 1)/|.|, which Toksvig's filter "
       "reads."},
      {"levels", list}};
}

// OpenEXR compresses line blocks on a thread pool while this is alive; the
// finest level of a 4096^2 map is 450 MB of floats, which one thread
// compresses at ~30 MB/s.
class ExrThreads {
 public:
  ExrThreads() : previous_(Imf::globalThreadCount()) {
    Imf::setGlobalThreadCount(int(std::max(1u, std::thread::hardware_concurrency())));
  }
  ~ExrThreads() { Imf::setGlobalThreadCount(previous_); }
  ExrThreads(const ExrThreads&) = delete;
  ExrThreads& operator=(const ExrThreads&) = delete;

 private:
  int previous_;
};

void replace_folder(const std::string& built, const std::string& folder) {
  std::error_code ec;
  if (fs::exists(folder)) {
    const bool pyramid = fs::exists(fs::path(folder) / "pyramid.json");
    if (!pyramid && !fs::is_empty(folder, ec))
      throw OutputError(fmt::format(
          "{}: exists and is not a pyramid folder (no pyramid.json); not overwriting it", folder));
    fs::remove_all(folder, ec);
  }
  fs::rename(built, folder, ec);
  if (ec)
    throw OutputError(
        fmt::format("{}: cannot move the pyramid into place: {}", folder, ec.message()));
}

}  // namespace

void write_pyramid(const std::vector<PyramidLevel>& levels, const PyramidSource& source,
                   const std::string& folder) {
  fs::path target = fs::absolute(folder).lexically_normal();
  if (!target.has_filename()) target = target.parent_path();  // "dir/"
  const fs::path parent = target.parent_path();
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (fs::exists(target) && !fs::is_directory(target))
    throw OutputError(fmt::format("{}: exists and is not a folder", folder));
  const std::string built = temporary_name((parent / target.filename()).string());
  fs::create_directory(built, ec);
  if (ec)
    throw OutputError(
        fmt::format("{}: cannot create a folder beside it: {}", folder, ec.message()));
  try {
    const ExrThreads threads;
    for (std::size_t l = 0; l < levels.size(); ++l)
      write_exr(pyramid_level_image(levels[l]),
                (fs::path(built) / fmt::format("level_{:02}.exr", l)).string(),
                {{"penumbra:pyramid_level", std::to_string(l)}});
    write_text_file((fs::path(built) / "pyramid.json").string(),
                    manifest(levels, source).dump(2) + "\n");
    replace_folder(built, target.string());
  } catch (...) {
    fs::remove_all(built, ec);
    throw;
  }
}

}  // namespace penumbra
