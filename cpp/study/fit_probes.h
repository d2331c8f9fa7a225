// The constants `penumbra fit` refits without a grid: factor methods whose
// factor reads more than the grid's inputs (the height field's visibility)
// or depends on them through a constant a table would blur. The re-trace
// of raw bump tries each at a list of values on every sample
// (evaluator/evaluator.h, FactorProbe), so the terminator RMSE at each
// value is that of a render of the method with that value, to rounding,
// and no render is added.
#pragma once

#include <set>
#include <string>
#include <vector>

#include "analysis/metrics.h"
#include "core/terminator.h"
#include "evaluator/evaluator.h"
#include "image/image.h"
#include "scene/scene.h"

namespace penumbra {

struct ProbedConstant {
  TerminatorMethod method = TerminatorMethod::kNone;
  // The study's method label under which its render at `published` has an
  // error ("" where the study has none).
  std::string label;
  std::string constant;   // its symbol first, then where it enters (no comma)
  std::string reference;  // what `published` is ("published", "the study's value")
  double published = 0.0;
  std::vector<double> values;  // tried, ascending, `published` among them
};

// The constants refitted on a study whose evaluator methods have the labels
// `labels` (its report's comparisons):
//   shading-offset   s in [0, 1] in steps of 0.025, against the study's own
//                    s (its first "shading-offset(s=...)"), else 0, Cycles'
//                    default (raw bump)
//   microshadow-chan2018    p in saturate(cos / sqrt(1 - V))^p, published 2
//   microshadow-brinck2016  q in saturate(cos + 2 V^q - 1), published 2
// the exponents at 2^(k/4) for k in [0, 20]: 1 to 32 in quarter octaves (a
// large exponent cuts the light where the cosine falls below the
// visibility's threshold; the default study wants them above 2). Every
// fourth value is the square of one before it (core/terminator.h's list
// forms), so a quarter-octave list costs five pows per sample, and half
// octaves lost 0.8 points of Brinck's held-out E.
std::vector<ProbedConstant> probed_constants(const std::set<std::string>& labels);

// The probes of `constants` on `scene`: each factor on the lobes its method
// scales there (core/terminator.h, FactorLobes), tried only on the pixels
// that `raw_bump` (the scene's raw-bump render) places in the terminator's
// profile bins, with a degree's margin: the others do not enter the
// terminator RMSE, and the probes would triple the re-trace's time.
TallyProbes probes_for(const std::vector<ProbedConstant>& constants, const Scene& scene,
                       const Image& raw_bump);

// Per probe, per value: the terminator RMSE (fraction of albedo*E/pi) of the
// probe's radiance against `truth`, profiled as the study profiles
// `traced`, the raw-bump image the probes were tallied with (its analysis
// channels place each pixel). Only the terminator's bins are right: the
// pixels outside them were not probed.
std::vector<std::vector<double>> probe_errors(const TallyProbes& probes, const Image& traced,
                                              double radiance_scale, const Profile& truth);

}  // namespace penumbra
