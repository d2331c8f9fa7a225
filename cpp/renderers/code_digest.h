// Digests of the source files that produce a render's pixels, computed at
// build time (cpp/renderers/code_digest.cmake regenerates them whenever one
// of those files changes). They are part of every cache key, so editing a
// method or an exporter re-renders exactly the entries it can change:
//   evaluator  core math, scene reader, images, evaluator: every renderer's
//              entry holds the evaluator's analysis channels, so all depend on it;
//   povray     the POV-Ray exporter (POV-Ray entries only);
//   blender    the Blender exporter (Blender entries only; the script itself
//              is hashed when it is used, see pixel_code_digest);
//   filtering  the bump-filtering experiment and the math it reads (the
//              filtering section of a study, study/filtering_study.h);
//   comparison the metrics of one comparison of two images (kept between a
//              study's runs, study/comparison_store.h);
//   previews   the drawing of a study's preview and difference PNGs (kept
//              between a study's runs, study/previews.h).
#pragma once

namespace penumbra {

struct CodeDigests {
  const char* evaluator;
  const char* povray;
  const char* blender;
  const char* filtering;
  const char* comparison;
  const char* previews;
};

const CodeDigests& build_code_digests();

}  // namespace penumbra
