// The study's sections beside its two sweeps (bump and low-poly, which
// plan.h expands into variants): the filtering section
// (study/filtering_study.h) and the interplay section (study/interplay.h).
// Each runs as steps of the one study run (study/study.h), with what every
// step of the run uses: the study folder, the render cache, the probed
// renderers, the run's parallelism and its progress log. A section that
// renders adds its jobs to the run's one render phase (after the truths
// converged, beside the sweeps' jobs, through the same executor) and is
// handed their images afterwards.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "image/image.h"
#include "study/cache.h"
#include "study/rendering.h"
#include "util/parallel.h"

namespace penumbra {

struct StepContext {
  std::string out_dir;  // the study folder
  const RenderCache& cache;
  const Renderers& renderers;
  Parallelism parallelism;
  std::function<void(const std::string&)> log;  // progress lines; may be empty
};

// What the render phase gave a section's jobs, in the order the section
// listed them.
struct SectionRenders {
  std::vector<Image> images;        // empty where not done
  std::vector<char> done, cached;   // cached: taken from the cache, not rendered now
  std::vector<std::string> errors;  // "" where done
};

}  // namespace penumbra
