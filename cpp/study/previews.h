// The PNG pictures of a study's renders in its images/ folder: each render's
// preview (NAME.png), its difference from its ground truth (NAME-diff.png)
// and its HDR-FLIP map against that truth (flip/NAME.png). Encoding some
// 3,700 PNGs was a third of a warm run of the default study, so a stamp
// (images/.inputs) records what each picture was drawn from, and a picture
// drawn from the same pixels by the same drawing code is kept rather than
// drawn again.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <mutex>
#include <string>

#include "analysis/flip.h"
#include "image/image.h"

namespace penumbra {

// Signed difference test - reference in units of `scale` (albedo*E/pi), on
// a diverging map saturating at +-0.25: red brighter, blue darker, white
// equal; grey where either image has no object (alpha below 0.5).
void write_difference_png(const Image& test, const Image& reference, double scale,
                          const std::string& path);

// One study folder's pictures. Thread-safe. A picture's key is a hash of the
// pixel digests it is drawn from (study/comparison_store.h), the scale of a
// difference, and the digest of the drawing code (renderers/code_digest.h),
// so that editing the drawing redraws every picture.
class PreviewFolder {
 public:
  // Reads `study_folder`/images/.inputs and removes it: a run stopped while
  // drawing leaves no stamp, so the next run draws everything again. A
  // missing or unreadable stamp keeps nothing.
  explicit PreviewFolder(const std::filesystem::path& study_folder);

  // Draws `image`'s preview into `relative` (from the study folder) unless
  // the file is there, drawn from pixels of the same `digest`.
  void preview(const Image& image, std::uint64_t digest, const std::string& relative);
  // The same for the difference of `test` from `reference`.
  void difference(const Image& test, std::uint64_t test_digest, const Image& reference,
                  std::uint64_t reference_digest, double scale, const std::string& relative);

  // The HDR-FLIP map of `test` against `reference` (analysis/flip.h, the
  // study's viewer) in magma colours, as the FLIP papers show them. False,
  // and nothing written, where FLIP refuses the images (no R, G and B).
  // `map`: that map where the caller has it already (measure_comparison's),
  // else empty.
  bool flip(const Image& test, std::uint64_t test_digest, const Image& reference,
            std::uint64_t reference_digest, const std::string& relative, const FlipImage& map = {});

  // Writes the stamp: every picture drawn or kept since construction.
  void save() const;

  std::size_t drawn() const;
  std::size_t kept() const;

 private:
  // Whether `relative` needs drawing for `key`; records the key either way.
  bool needs_drawing(const std::string& relative, std::uint64_t key);

  std::filesystem::path folder_;
  std::map<std::string, std::uint64_t> last_;  // from the stamp
  mutable std::mutex mutex_;
  std::map<std::string, std::uint64_t> now_;
  std::size_t drawn_ = 0, kept_ = 0;
};

}  // namespace penumbra
