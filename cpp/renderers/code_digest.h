// Digests of the source files that produce a render's pixels, computed at
// build time (cpp/renderers/code_digest.cmake regenerates them whenever one
// of those files changes; CMakeLists.txt lists the files). They are part of
// every cache key, so editing a method or an exporter re-renders exactly
// the entries it can change:
//   evaluator  core math, scene reader, images, evaluator (`_pixel_common`):
//              every renderer's entry holds the evaluator's analysis
//              channels, so all depend on it;
//   each external renderer, by id: its exporter and driver (`_pixel_<id>`,
//              its entries only; Blender's script itself is hashed when it
//              is used, see its entry);
//   filtering  the bump-filtering experiment and the math it reads (the
//              filtering section of a study, study/filtering_study.h);
//   comparison the metrics of one comparison of two images (kept between a
//              study's runs, study/comparison_store.h);
//   previews   the drawing of a study's preview, difference and FLIP PNGs (kept
//              between a study's runs, study/previews.h).
#pragma once

#include <string_view>

namespace penumbra {

struct CodeDigests {
  const char* evaluator;
  const char* filtering;
  const char* comparison;
  const char* previews;
};

const CodeDigests& build_code_digests();

// The digest of external renderer `id`'s own code; std::logic_error for an
// id without a `_pixel_<id>` list in CMakeLists.txt.
const char* external_code_digest(std::string_view id);

}  // namespace penumbra
