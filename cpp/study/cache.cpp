#include "study/cache.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "core/mesh_surface.h"
#include "image/image_io.h"
#include "scene/factor_table_file.h"
#include "study/plan.h"
#include "util/files.h"
#include "util/hash.h"
#include "util/strict_json.h"

namespace penumbra {
namespace fs = std::filesystem;

std::string render_key(const nlohmann::json& canonical_scene, RendererKind renderer,
                       const RendererIdentity& identity) {
  const std::string text = canonical_scene.dump() + "\n" + to_string(renderer) + "\n" +
                           identity.version + "\n" + identity.code_digest + "\n" + kPenumbraVersion;
  return fmt::format("{:016x}{:016x}", fnv1a(text, kFnvOffset), fnv1a(text, 0x84222325cbf29ce4ull));
}

RenderCache::RenderCache(std::string folder) : folder_(std::move(folder)) {}

std::string RenderCache::exr_path(const std::string& key) const {
  return (fs::path(folder_) / (key + ".exr")).string();
}

std::string RenderCache::log_path(const std::string& key) const {
  return (fs::path(folder_) / (key + ".log")).string();
}

std::string RenderCache::relative_exr(const std::string& key) {
  return "cache/" + key + ".exr";
}

bool RenderCache::contains(const std::string& key) const {
  std::error_code ec;
  return fs::exists(exr_path(key), ec);
}

std::optional<Image> RenderCache::lookup(const std::string& key, std::string* reason) const {
  std::map<std::string, std::string> attributes;
  Image image;
  try {
    image = read_image(exr_path(key), &attributes);
  } catch (const std::exception& e) {
    *reason = fmt::format("unreadable ({})", printable(e.what(), 200));
    return std::nullopt;
  }
  if (attributes["penumbra:key"] != key) {
    *reason = fmt::format("it carries key \"{}\", not its own",
                          printable(attributes["penumbra:key"], 40));
    return std::nullopt;
  }
  if (attributes["penumbra:checksum"] != image_checksum(image)) {
    *reason = "its pixels do not match their checksum";
    return std::nullopt;
  }
  if (count_nonfinite(image) > 0) {
    *reason = "it holds NaN or Inf values";
    return std::nullopt;
  }
  return image;
}

void RenderCache::remove(const std::string& key) const {
  std::error_code ignored;
  fs::remove(exr_path(key), ignored);
}

void RenderCache::store(const std::string& key, const Image& image,
                        std::vector<std::pair<std::string, std::string>> metadata) const {
  metadata.push_back({"penumbra:key", key});
  metadata.push_back({"penumbra:checksum", image_checksum(image)});
  write_exr(image, exr_path(key), metadata);
}

namespace {

constexpr char kSumsMagic[8] = {'p', 'e', 'n', 's', 'u', 'm', 's', '1'};

struct SumsHeader {
  char magic[8];
  std::int32_t spp, width, height, channels;
};

}  // namespace

std::string RenderCache::sums_path(const std::string& samples_key, int spp) const {
  return (fs::path(folder_) / "sums" / fmt::format("{}-s{}.sums", samples_key, spp)).string();
}

std::optional<SampleSums> RenderCache::lookup_sums(const std::string& samples_key, int spp) const {
  static_assert(std::endian::native == std::endian::little, "sums files are little-endian");
  std::ifstream in(sums_path(samples_key, spp), std::ios::binary);
  SumsHeader header{};
  if (!in.read(reinterpret_cast<char*>(&header), sizeof header) ||
      std::memcmp(header.magic, kSumsMagic, sizeof kSumsMagic) != 0 || header.spp != spp ||
      header.width <= 0 || header.height <= 0 ||
      header.channels != static_cast<std::int32_t>(kSampleSumChannels))
    return std::nullopt;
  SampleSums sums{header.spp, header.width, header.height, {}};
  sums.values.resize(std::size_t(header.width) * std::size_t(header.height) * kSampleSumChannels);
  std::uint64_t digest = 0;
  const auto bytes = static_cast<std::streamsize>(sums.values.size() * sizeof(double));
  if (!in.read(reinterpret_cast<char*>(sums.values.data()), bytes) ||
      !in.read(reinterpret_cast<char*>(&digest), sizeof digest) || in.peek() != EOF)
    return std::nullopt;
  const std::uint64_t expected =
      fnv1a(sums.values.data(), std::size_t(bytes), fnv1a(&header, sizeof header));
  if (digest != expected) return std::nullopt;
  return sums;
}

void RenderCache::store_sums(const std::string& samples_key, const SampleSums& sums) const {
  SumsHeader header{};
  std::memcpy(header.magic, kSumsMagic, sizeof kSumsMagic);
  header.spp = sums.spp, header.width = sums.width, header.height = sums.height;
  header.channels = static_cast<std::int32_t>(kSampleSumChannels);
  const std::size_t bytes = sums.values.size() * sizeof(double);
  const std::uint64_t digest = fnv1a(sums.values.data(), bytes, fnv1a(&header, sizeof header));
  const std::string path = sums_path(samples_key, sums.spp);
  fs::create_directories(fs::path(path).parent_path());
  write_atomically(path, [&](CheckedFile& file) {
    file.write(&header, sizeof header);
    file.write(sums.values.data(), bytes);
    file.write(&digest, sizeof digest);
  });
}

namespace {

// The scene a key is made from: an image map, a mesh, a fitted table or a
// user method by its content, not by where it lies (a file edited in place
// re-renders, a moved one does not).
nlohmann::json keyed_scene(const Job& job) {
  const Scene scene = job.scene();
  const auto& table = scene.terminator.method.table;
  nlohmann::json keyed = job.scene_json();
  if (scene.height.map) keyed["height"]["file"] = "content:" + scene.height.map->digest;
  if (scene.light.environment) keyed["light"]["map"] = "content:" + scene.light.map_digest;
  for (std::size_t i = 0; i < scene.light.members.size(); ++i)
    if (scene.light.members[i].environment)
      keyed["light"]["lights"][i]["map"] = "content:" + scene.light.members[i].map_digest;
  if (scene.shape.mesh) keyed["shape"]["file"] = "content:" + scene.shape.mesh->digest;
  if (table) keyed["terminator"]["parameters"]["table"] = "content:" + factor_table_digest(*table);
  // A user method by its definition: editing the function renders again.
  if (const auto& user = scene.terminator.method.user)
    keyed["terminator"]["definition"] = "content:" + user->digest;
  return keyed;
}

RendererIdentity identity_of(RendererKind renderer,
                             const std::vector<std::pair<RendererKind, RendererIdentity>>& ids) {
  const auto it = std::find_if(ids.begin(), ids.end(),
                               [&](const auto& entry) { return entry.first == renderer; });
  return it != ids.end() ? it->second : RendererIdentity{};
}

}  // namespace

std::string samples_key(const Job& job,
                        const std::vector<std::pair<RendererKind, RendererIdentity>>& ids) {
  nlohmann::json keyed = keyed_scene(job);
  keyed["camera"].erase("spp");
  return render_key(keyed, job.renderer, identity_of(job.renderer, ids));
}

void assign_keys(Plan& plan, const std::vector<std::pair<RendererKind, RendererIdentity>>& ids) {
  assign_keys(plan.jobs, ids);
}

void assign_keys(std::vector<Job>& jobs,
                 const std::vector<std::pair<RendererKind, RendererIdentity>>& ids) {
  // Each key is made from its job's scene alone: in parallel, the same keys.
  tbb::parallel_for(std::size_t{0}, jobs.size(), [&](std::size_t i) {
    Job& job = jobs[i];
    job.key = render_key(keyed_scene(job), job.renderer, identity_of(job.renderer, ids));
  });
}

}  // namespace penumbra
