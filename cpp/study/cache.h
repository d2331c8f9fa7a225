// The render cache of a study folder: cache/KEY.exr, one file per render,
// addressed by a key that covers everything that can change its pixels.
// Entries carry their key and a checksum of their pixels; an entry that does
// not verify is never used.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "evaluator/evaluator.h"
#include "image/image.h"
#include "renderers/registry.h"

namespace penumbra {

struct Plan;
struct Job;

// What identifies the code that renders with a renderer: its version line
// ("Blender 3.4.1", "penumbra 0.4.0") and the digest of Penumbra's code and
// scripts that produce its pixels (pixel_code_digest).
struct RendererIdentity {
  std::string version = "unavailable";
  std::string code_digest;
};

// 32 hex digits: two 64-bit FNV-1a hashes (different seeds) of the canonical
// scene JSON, the renderer id, its version, the code digest and Penumbra's
// version. A content key, not a cryptographic hash.
std::string render_key(const nlohmann::json& canonical_scene, RendererKind renderer,
                       const RendererIdentity& identity);

class RenderCache {
 public:
  explicit RenderCache(std::string folder);  // "<study>/cache"

  const std::string& folder() const { return folder_; }
  std::string exr_path(const std::string& key) const;
  std::string log_path(const std::string& key) const;
  // The entry's path as report.json gives it, relative to the study folder.
  static std::string relative_exr(const std::string& key);

  bool contains(const std::string& key) const;
  // The entry's image if it reads, carries `key` and matches its checksum and
  // holds only finite values; otherwise nullopt and why in `reason`.
  std::optional<Image> lookup(const std::string& key, std::string* reason) const;
  void remove(const std::string& key) const;
  // Writes the entry (temporary name, then rename) with `metadata` plus the
  // key and the pixels' checksum.
  void store(const std::string& key, const Image& image,
             std::vector<std::pair<std::string, std::string>> metadata) const;

  // A displacement truth's per-pixel sums (evaluator.h, SampleSums), kept
  // so that a check at 4^k times its samples extends them instead of
  // drawing them again (issue 45): cache/sums/SAMPLES-sSPP.sums, SAMPLES the
  // key of the scene without its sample count (samples_key). Little-endian
  // doubles behind a header, checked by size and an FNV-1a digest; one that
  // does not verify is never used. Written under a temporary name, then
  // renamed.
  std::string sums_path(const std::string& samples_key, int spp) const;
  std::optional<SampleSums> lookup_sums(const std::string& samples_key, int spp) const;
  void store_sums(const std::string& samples_key, const SampleSums& sums) const;

 private:
  std::string folder_;
};

// The key of `job`'s scene without /camera/spp: the sample sequence that
// its renders with 4^k times the samples share (RenderCache::store_sums).
std::string samples_key(const Job& job,
                        const std::vector<std::pair<RendererKind, RendererIdentity>>& ids);

// Sets every job's key from its canonical scene and its renderer's identity.
void assign_keys(Plan& plan, const std::vector<std::pair<RendererKind, RendererIdentity>>& ids);
void assign_keys(std::vector<Job>& jobs,
                 const std::vector<std::pair<RendererKind, RendererIdentity>>& ids);

}  // namespace penumbra
