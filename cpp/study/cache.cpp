#include "study/cache.h"

#include <algorithm>
#include <filesystem>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "core/mesh_surface.h"
#include "image/image_io.h"
#include "scene/factor_table_file.h"
#include "study/plan.h"
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

void assign_keys(Plan& plan, const std::vector<std::pair<RendererKind, RendererIdentity>>& ids) {
  assign_keys(plan.jobs, ids);
}

void assign_keys(std::vector<Job>& jobs,
                 const std::vector<std::pair<RendererKind, RendererIdentity>>& ids) {
  // Each key is made from its job's scene alone: in parallel, the same keys.
  tbb::parallel_for(std::size_t{0}, jobs.size(), [&](std::size_t i) {
    Job& job = jobs[i];
    const auto it = std::find_if(ids.begin(), ids.end(),
                                 [&](const auto& entry) { return entry.first == job.renderer; });
    const RendererIdentity identity = it != ids.end() ? it->second : RendererIdentity{};
    const Scene scene = job.scene();
    const auto& table = scene.terminator.method.table;
    nlohmann::json keyed = job.scene_json();
    // An image map, a mesh, a fitted table or a user method enters the key by its content, not by
    // where it lies: a file edited in place re-renders, a moved one does not.
    if (scene.height.map) keyed["height"]["file"] = "content:" + scene.height.map->digest;
    if (scene.light.environment) keyed["light"]["map"] = "content:" + scene.light.map_digest;
    if (scene.shape.mesh) keyed["shape"]["file"] = "content:" + scene.shape.mesh->digest;
    if (table)
      keyed["terminator"]["parameters"]["table"] = "content:" + factor_table_digest(*table);
    // A user method by its definition: editing the function renders again.
    if (const auto& user = scene.terminator.method.user)
      keyed["terminator"]["definition"] = "content:" + user->digest;
    job.key = render_key(keyed, job.renderer, identity);
  });
}

}  // namespace penumbra
