// Comparing a study's renders: every test render against its section's
// ground truth, the same renderer's and the evaluator's, as typed rows; the
// rankings are computed from those rows.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "analysis/intervals.h"
#include "analysis/metrics.h"
#include "analysis/statistics.h"
#include "image/image.h"
#include "study/comparison_store.h"
#include "study/plan.h"
#include "study/previews.h"

namespace penumbra {

// The images of a study's jobs after the render phase (done[i]: images[i] is valid).
struct RenderedImages {
  std::vector<char> done;
  std::vector<Image> images;
};

// A render as the report lists it.
struct RenderRow {
  std::size_t job = 0;
  std::string image;       // preview PNG, relative to the study folder
  std::string difference;  // difference PNG against the truth, "" if none
  std::string flip_map;    // HDR-FLIP map PNG against the truth, "" if none
  Profile profile;
};

// One test render against one ground truth.
struct ComparisonRow {
  std::size_t variant = 0, job = 0, reference_job = 0;
  RendererKind renderer = RendererKind::kEvaluator;            // of the test
  RendererKind reference_renderer = RendererKind::kEvaluator;  // of the truth
  std::string method;                                          // label of the method or offset
  std::string reference;  // "evaluator:displacement", "blender:analytic"
  ProfileMetrics profile;
  ImageMetrics image;
  ViewMetrics view;                     // the viewer's side (analysis/metrics.h)
  std::optional<ShadowMetrics> shadow;  // low-poly rows
  ComparisonIntervals intervals;        // 95 % intervals (analysis/intervals.h)
};

// An external renderer's render against the evaluator's render of the same
// scene: the ground truth (method "none", displacement), or a method both
// implement. Bump section only.
struct AgreementRow {
  std::size_t variant = 0, job = 0, reference_job = 0;
  RendererKind renderer = RendererKind::kPovray;
  std::string what;  // "ground truth" or the method label
  ProfileMetrics profile;
  ComparisonIntervals intervals;
};

struct Comparisons {
  std::vector<std::vector<RenderRow>> renders;  // per variant, done jobs only
  std::vector<ComparisonRow> rows;              // in job order, then reference order
  std::vector<AgreementRow> agreement;          // in job order
  std::size_t nonfinite = 0;                    // NaN or Inf values seen (a failure)
};

// Compares every done test job with its truths and draws the preview and
// difference PNGs through `pictures` (those unchanged since the last run are
// kept), `jobs` jobs at a time (the result does not depend on it). With a store, a comparison of
// two images it holds is taken from it, and every new one is added.
Comparisons compare_study(const Plan& plan, const RenderedImages& renders, PreviewFolder& pictures,
                          int jobs, ComparisonStore* store = nullptr);

// One method's mean over the rows a ranking selects.
struct RankEntry {
  std::string method;
  double mean = 0.0;    // the ranking metric
  double second = 0.0;  // low-poly: the mean terminator RMSE beside it
  int count = 0;
  // Low-poly: the mean's 95 % percentile-bootstrap interval over the rows
  // counted, and the paired comparison with the first entry over the scenes
  // and tessellation levels both have (none for the first, or without any
  // pair): a tie when its interval of the mean difference holds 0.
  Interval interval;
  std::optional<PairedComparison> versus_best;
};

// Bump methods: the evaluator against the evaluator's displacement, by the
// mean terminator-region profile RMSE, over `scene` ("" for all).
std::vector<RankEntry> rank_bump(const Plan& plan, const std::vector<ComparisonRow>& rows,
                                 const std::string& scene);
// Offsets: the evaluator against its analytic render, by the mean fraction of
// lit pixels each darkens over the tessellation levels; where the section has
// other axes, one entry per offset and value ("none (normal interpolation:
// consistent)").
std::vector<RankEntry> rank_lowpoly(const Plan& plan, const Section& section,
                                    const std::vector<ComparisonRow>& rows,
                                    const std::string& scene);

}  // namespace penumbra
