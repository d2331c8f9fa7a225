#include "study/comparison_store.h"

#include <algorithm>
#include <cstring>
#include <type_traits>
#include <vector>

#include <fmt/format.h>

#include "image/image_io.h"
#include "renderers/code_digest.h"
#include "util/files.h"
#include "util/hash.h"

namespace penumbra {
namespace {

// Records are the metric structs' bytes, so each must be plain data with no
// padding (whose bytes would differ from run to run).
template <typename T>
constexpr bool kPlain = std::is_trivially_copyable_v<T>;
static_assert(kPlain<ProfileMetrics> && sizeof(ProfileMetrics) == 12 * sizeof(double));
static_assert(kPlain<ImageMetrics> &&
              sizeof(ImageMetrics) == 8 * sizeof(double) + 2 * sizeof(std::size_t));
static_assert(kPlain<ViewMetrics> && sizeof(ViewMetrics) == 2 * sizeof(double) + 8);
static_assert(kPlain<ShadowMetrics> &&
              sizeof(ShadowMetrics) == 4 * sizeof(double) + 4 * sizeof(std::size_t));
static_assert(kPlain<ComparisonIntervals> &&
              sizeof(ComparisonIntervals) == 17 * sizeof(double) + 2 * sizeof(int));

// key, has-shadow flag, then the metrics.
constexpr std::size_t kRecordBytes = 2 * sizeof(std::uint64_t) + sizeof(ProfileMetrics) +
                                     sizeof(ImageMetrics) + sizeof(ViewMetrics) +
                                     sizeof(ShadowMetrics) + sizeof(ComparisonIntervals);

// The comparison code's digest and the record size: a store written by other
// code, or with another layout, is not read.
std::string header() {
  return fmt::format("penumbra comparisons\ncode {}\nrecord {}\n", build_code_digests().comparison,
                     kRecordBytes);
}

template <typename T>
void put(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

template <typename T>
T get(const char*& in) {
  T value;
  std::memcpy(&value, in, sizeof(T));
  in += sizeof(T);
  return value;
}

void append_record(std::string& out, std::uint64_t key, const Measurement& m) {
  put(out, key);
  put(out, std::uint64_t{m.shadow.has_value()});
  put(out, m.profile);
  put(out, m.image);
  put(out, m.view);
  put(out, m.shadow.value_or(ShadowMetrics{}));
  put(out, m.intervals);
}

Measurement read_record(const char* in, std::uint64_t* key) {
  Measurement m;
  *key = get<std::uint64_t>(in);
  const bool has_shadow = get<std::uint64_t>(in) != 0;
  m.profile = get<ProfileMetrics>(in);
  m.image = get<ImageMetrics>(in);
  m.view = get<ViewMetrics>(in);
  const ShadowMetrics shadow = get<ShadowMetrics>(in);
  if (has_shadow) m.shadow = shadow;
  m.intervals = get<ComparisonIntervals>(in);
  return m;
}

}  // namespace

Measurement measure_comparison(const Image& test, const Image& reference, double scale,
                               ComparisonExtent extent, FlipImage* flip_map) {
  MeasureOptions options;
  options.scale = scale;
  options.image = options.view = extent != ComparisonExtent::kProfileOnly;
  options.shadows = extent == ComparisonExtent::kFullShadows;
  options.flip = options.image;
  return measure(test, reference, options, flip_map);
}

std::uint64_t pixel_digest(const Image& image) {
  // One hash per channel, folded in name order. The channels' hashes are
  // independent chains, advanced side by side in one pass over the pixels.
  const std::size_t nc = image.channels.size();
  const std::size_t pixels = std::size_t(image.width) * image.height;
  std::vector<std::uint64_t> hashes(nc, kFnvOffset);
  const float* p = image.pixels.data();
  for (std::size_t i = 0; i < pixels; ++i, p += nc)
    for (std::size_t c = 0; c < nc; ++c) {
      std::uint32_t bits;
      std::memcpy(&bits, p + c, sizeof bits);
      hashes[c] = (hashes[c] ^ bits) * kFnvPrime;
    }
  std::vector<std::pair<std::string, std::uint64_t>> channels;
  for (std::size_t c = 0; c < nc; ++c) channels.emplace_back(image.channels[c], hashes[c]);
  std::sort(channels.begin(), channels.end());
  std::uint64_t h = fnv1a(fmt::format("{}x{}", image.width, image.height));
  for (const auto& [name, channel_hash] : channels) {
    h = fnv1a(name + "\n", h);
    h = fnv1a(&channel_hash, sizeof channel_hash, h);
  }
  return h;
}

std::uint64_t comparison_key(std::uint64_t test_digest, std::uint64_t reference_digest,
                             double scale, ComparisonExtent extent) {
  std::uint64_t h = fnv1a(&test_digest, sizeof test_digest);
  h = fnv1a(&reference_digest, sizeof reference_digest, h);
  h = fnv1a(&scale, sizeof scale, h);
  return fnv1a(&extent, sizeof extent, h);
}

ComparisonStore::ComparisonStore(std::string path, std::string* warning) : path_(std::move(path)) {
  const std::string bytes = read_file(path_);
  const std::string head = header();
  if (bytes.empty() || bytes.compare(0, head.size(), head) != 0) {
    // Missing, or written by other comparison code: nothing to reuse. Only
    // a file that is not a store at all is worth a warning.
    if (!bytes.empty() && bytes.rfind("penumbra comparisons\n", 0) != 0)
      *warning = fmt::format("{}: not a comparison store; measuring every comparison", path_);
    return;
  }
  const std::size_t body = bytes.size() - head.size();
  if (body % kRecordBytes != 0) {
    *warning = fmt::format(
        "{}: truncated ({} bytes after the header, not a whole number of "
        "{}-byte records); measuring every comparison",
        path_, body, kRecordBytes);
    return;
  }
  for (std::size_t at = head.size(); at < bytes.size(); at += kRecordBytes) {
    std::uint64_t key = 0;
    const Measurement m = read_record(bytes.data() + at, &key);
    loaded_.emplace(key, m);
  }
}

std::optional<Measurement> ComparisonStore::find(std::uint64_t key) {
  const std::lock_guard<std::mutex> lock(mutex_);
  const auto it = loaded_.find(key);
  if (it == loaded_.end()) return std::nullopt;
  used_.insert(*it);
  ++found_;
  return it->second;
}

void ComparisonStore::insert(std::uint64_t key, const Measurement& metrics) {
  const std::lock_guard<std::mutex> lock(mutex_);
  used_.insert_or_assign(key, metrics);
  ++inserted_;
}

void ComparisonStore::save() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  std::vector<std::uint64_t> keys;
  keys.reserve(used_.size());
  for (const auto& entry : used_) keys.push_back(entry.first);
  std::sort(keys.begin(), keys.end());  // the same bytes for the same entries
  std::string out = header();
  out.reserve(out.size() + keys.size() * kRecordBytes);
  for (std::uint64_t key : keys) append_record(out, key, used_.at(key));
  write_binary_file(path_, out.data(), out.size());
}

}  // namespace penumbra
