// The metrics of a study's comparisons, kept between runs. A comparison's
// paired bootstrap and SSIM cost far more than reading its two images (in
// the default study, 14 of a warm run's 26 s on 2 cores), and they depend
// only on the two images, the radiance scale and the comparison code. So a
// run looks each comparison up by those, computes only what it lacks, and
// keeps the entries it used in STUDY_DIR/cache/comparisons.bin.
#pragma once

#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>

#include "analysis/measure.h"

namespace penumbra {

// Which metrics a comparison computes (the store keeps them as
// measure() gives them, analysis/measure.h). Agreement rows (an external
// renderer against the evaluator) fill `profile` and `intervals` only.
enum class ComparisonExtent : std::uint8_t {
  kFull,         // profile, image, view and intervals
  kFullShadows,  // and the shadow metrics (low-poly rows)
  kProfileOnly,  // profile and intervals (agreement rows)
};

// The metrics of `test` against `reference` (radiance scale in W m^-2 sr^-1):
// measure() asked for what `extent` names.
// `flip_map`: as measure's (analysis/measure.h).
Measurement measure_comparison(const Image& test, const Image& reference, double scale,
                               ComparisonExtent extent, FlipImage* flip_map = nullptr);

// A digest of an image's size, channel names and pixel bits, independent of
// the channels' order (a render and its cache entry read back differ in it).
// Word by word: a cache entry's checksum (image_checksum) goes byte by byte
// and would take longer than the comparisons it saves.
std::uint64_t pixel_digest(const Image& image);

// The key of a comparison: both images' pixel digests, the scale and the
// extent. The comparison code's digest is the file's, not the key's: a
// store written by other code is not read.
std::uint64_t comparison_key(std::uint64_t test_digest, std::uint64_t reference_digest,
                             double scale, ComparisonExtent extent);

// Thread-safe. Entries found or inserted since loading are the ones saved.
class ComparisonStore {
 public:
  // Reads `path`. A missing file, or one written by other comparison code,
  // gives an empty store; a damaged one too, with *warning saying so.
  ComparisonStore(std::string path, std::string* warning);

  std::optional<Measurement> find(std::uint64_t key);
  void insert(std::uint64_t key, const Measurement& metrics);
  // Replaces the file atomically (OutputError when it cannot be written).
  void save() const;

  std::size_t found() const { return found_; }
  std::size_t inserted() const { return inserted_; }

 private:
  std::string path_;
  std::unordered_map<std::uint64_t, Measurement> loaded_, used_;
  std::size_t found_ = 0, inserted_ = 0;
  mutable std::mutex mutex_;
};

}  // namespace penumbra
