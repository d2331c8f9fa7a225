#include "study/compare.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <optional>

#include "image/image_io.h"
#include "study/names.h"
#include "util/parallel.h"

namespace penumbra {

namespace {

const char* truth_name(SectionKind kind) {
  return kind == SectionKind::kBump ? "displacement" : "analytic";
}

// `flip`: job i's FLIP map against its renderer's truth where a comparison
// has just computed it (else empty).
RenderRow render_row(const Plan& plan, const RenderedImages& r,
                     const std::vector<std::uint64_t>& digests, std::size_t i,
                     PreviewFolder& pictures, const FlipImage& flip_map) {
  const Job& job = plan.jobs[i];
  const double scale = radiance_scale(job.scene());
  RenderRow row;
  row.job = i;
  const std::string stem = file_safe(job.label);
  row.image = "images/" + stem + ".png";
  pictures.preview(r.images[i], digests[i], row.image);
  const long truth = plan.truth(job.variant, job.renderer);
  if (!job.truth && truth >= 0 && r.done[truth]) {
    row.difference = "images/" + stem + "-diff.png";
    pictures.difference(r.images[i], digests[i], r.images[truth], digests[truth], scale,
                        row.difference);
    // A folder of their own: "-flip.png" is also how the preview of method
    // mitsuba3-flip ends.
    const std::string flip = "images/flip/" + stem + ".png";
    if (pictures.flip(r.images[i], digests[i], r.images[truth], digests[truth], flip, flip_map))
      row.flip_map = flip;
  }
  row.profile = terminator_profile(r.images[i], scale, ProfileOptions{});
  return row;
}

// Each done job's pixel digest, the comparisons' keys in the store.
std::vector<std::uint64_t> pixel_digests(const RenderedImages& r, int jobs) {
  std::vector<std::uint64_t> digests(r.images.size());
  run_parallel(jobs, digests.size(), [&](std::size_t i) {
    if (r.done[i]) digests[i] = pixel_digest(r.images[i]);
  });
  return digests;
}

// Where the images of the rows come from, and where their metrics are kept.
struct Measurer {
  const RenderedImages& renders;
  const std::vector<std::uint64_t>& digests;
  ComparisonStore* store;

  // `flip_map`: measure_comparison's, filled only where the metrics are
  // computed rather than found in the store.
  Measurement operator()(std::size_t test, std::size_t reference, double scale,
                         ComparisonExtent extent, FlipImage* flip_map = nullptr) const {
    if (!store)
      return measure_comparison(renders.images[test], renders.images[reference], scale, extent,
                                flip_map);
    const std::uint64_t key = comparison_key(digests[test], digests[reference], scale, extent);
    if (std::optional<Measurement> kept = store->find(key)) return *kept;
    Measurement m = measure_comparison(renders.images[test], renders.images[reference], scale,
                                       extent, flip_map);
    store->insert(key, m);
    return m;
  }
};

// The test job against the same renderer's truth, and the evaluator's;
// the FLIP map against the former into *own_flip (the preview draws it).
void add_comparisons(const Plan& plan, const Measurer& measure, std::size_t i, Comparisons& c,
                     FlipImage* own_flip) {
  const Job& job = plan.jobs[i];
  const SectionKind kind = plan.variants[job.variant].section;
  std::vector<std::pair<RendererKind, long>> refs{
      {job.renderer, plan.truth(job.variant, job.renderer)}};
  if (job.renderer != RendererKind::kEvaluator)
    refs.push_back({RendererKind::kEvaluator, plan.truth(job.variant, RendererKind::kEvaluator)});
  const double scale = radiance_scale(job.scene());
  const ComparisonExtent extent =
      kind == SectionKind::kLowPoly ? ComparisonExtent::kFullShadows : ComparisonExtent::kFull;
  for (const auto& [ref_renderer, ref] : refs) {
    if (ref < 0 || !measure.renders.done[ref]) continue;
    Measurement m = measure(i, static_cast<std::size_t>(ref), scale, extent,
                            ref_renderer == job.renderer ? own_flip : nullptr);
    ComparisonRow row;
    row.variant = job.variant, row.job = i, row.reference_job = static_cast<std::size_t>(ref);
    row.renderer = job.renderer, row.reference_renderer = ref_renderer;
    row.method = job.method;
    row.reference = std::string(to_string(ref_renderer)) + ":" + truth_name(kind);
    row.profile = m.profile;
    row.image = m.image;
    row.view = m.view;
    row.intervals = m.intervals;
    row.shadow = m.shadow;
    c.nonfinite += row.image.nonfinite;
    c.rows.push_back(std::move(row));
  }
}

// An external renderer's render against the evaluator's same render.
void add_agreement(const Plan& plan, const Measurer& measure, std::size_t i, Comparisons& c) {
  const Job& job = plan.jobs[i];
  if (job.renderer == RendererKind::kEvaluator ||
      plan.variants[job.variant].section != SectionKind::kBump)
    return;
  long ref = -1;  // the evaluator's job with the same role and method
  for (std::size_t k : plan.variants[job.variant].jobs)
    if (plan.jobs[k].renderer == RendererKind::kEvaluator && plan.jobs[k].truth == job.truth &&
        plan.jobs[k].method == job.method)
      ref = static_cast<long>(k);
  if (ref < 0 || !measure.renders.done[ref]) return;
  const Measurement m = measure(i, static_cast<std::size_t>(ref), radiance_scale(job.scene()),
                                ComparisonExtent::kProfileOnly);
  AgreementRow row;
  row.variant = job.variant, row.job = i, row.reference_job = static_cast<std::size_t>(ref);
  row.renderer = job.renderer;
  row.what = job.truth ? "ground truth" : job.method;
  row.profile = m.profile;
  row.intervals = m.intervals;
  c.agreement.push_back(std::move(row));
}

// Mean of `metric` (and `second`) per method (and `group` of its variant,
// appended to the label) over the evaluator's rows against the evaluator's
// truth that `metric` and `second` define, sorted by the mean, then the
// label; `with_intervals`: each mean's interval and the paired comparison
// with the first (RankEntry), pairing rows by `pair_key` (else by variant).
std::vector<RankEntry> rank_rows(const Plan& plan, const std::vector<ComparisonRow>& rows,
                                 SectionKind kind, const std::string& scene,
                                 const std::function<double(const ComparisonRow&)>& metric,
                                 const std::function<double(const ComparisonRow&)>& second,
                                 const std::function<std::string(const Variant&)>& group = {},
                                 const std::function<std::string(const Variant&)>& pair_key = {},
                                 bool with_intervals = false) {
  std::map<std::string, RankEntry> sums;
  // label -> the row's pairing key (pair_key, else its variant) -> metric
  std::map<std::string, std::map<std::string, double>> values;
  for (const ComparisonRow& row : rows) {
    const Variant& v = plan.variants[row.variant];
    if (v.section != kind || row.renderer != RendererKind::kEvaluator ||
        row.reference_renderer != RendererKind::kEvaluator)
      continue;
    if (!scene.empty() && v.scene != scene) continue;
    const double m = metric(row), s = second(row);
    if (!std::isfinite(m) || !std::isfinite(s)) continue;
    const std::string label = group ? row.method + group(v) : row.method;
    RankEntry& e = sums[label];
    e.method = label;
    e.mean += m, e.second += s, ++e.count;
    values[label][pair_key ? pair_key(v) : v.id] = m;
  }
  std::vector<RankEntry> order;
  for (auto& [method, e] : sums) {
    e.mean /= e.count, e.second /= e.count;
    order.push_back(e);
  }
  std::sort(order.begin(), order.end(), [](const RankEntry& a, const RankEntry& b) {
    return a.mean != b.mean ? a.mean < b.mean : a.method < b.method;
  });
  if (!with_intervals || order.empty()) return order;
  const std::map<std::string, double>& best = values[order.front().method];
  for (std::size_t k = 0; k < order.size(); ++k) {
    RankEntry& e = order[k];
    std::vector<double> own, mine, theirs;
    for (const auto& [variant, m] : values[e.method]) {
      own.push_back(m);
      if (const auto b = best.find(variant); b != best.end()) {
        mine.push_back(m);
        theirs.push_back(b->second);
      }
    }
    e.interval = bootstrap_mean_interval(own);
    if (k > 0 && !mine.empty()) e.versus_best = compare_paired(mine, theirs);
  }
  return order;
}

}  // namespace

Comparisons compare_study(const Plan& plan, const RenderedImages& renders, PreviewFolder& pictures,
                          int jobs, ComparisonStore* store) {
  // Each job's rows in its own slot, joined in job order afterwards: the
  // report is the same for any number of threads (every bootstrap has its
  // own fixed seed).
  struct JobRows {
    std::optional<RenderRow> render;
    Comparisons rows;
  };
  std::vector<std::size_t> order;
  for (const Variant& v : plan.variants)
    for (std::size_t i : v.jobs)
      if (renders.done[i]) order.push_back(i);
  std::vector<JobRows> slots(order.size());
  const std::vector<std::uint64_t> digests = pixel_digests(renders, jobs);
  const Measurer measure{renders, digests, store};
  run_parallel(jobs, order.size(), [&](std::size_t k) {
    const std::size_t i = order[k];
    // The comparisons first: a FLIP map they compute is the one the
    // preview draws, not computed twice.
    FlipImage flip;
    if (!plan.jobs[i].truth) add_comparisons(plan, measure, i, slots[k].rows, &flip);
    add_agreement(plan, measure, i, slots[k].rows);
    slots[k].render = render_row(plan, renders, digests, i, pictures, flip);
  });
  Comparisons c;
  c.renders.resize(plan.variants.size());
  for (std::size_t k = 0; k < order.size(); ++k) {
    JobRows& s = slots[k];
    c.renders[plan.jobs[order[k]].variant].push_back(std::move(*s.render));
    for (ComparisonRow& row : s.rows.rows) c.rows.push_back(std::move(row));
    for (AgreementRow& row : s.rows.agreement) c.agreement.push_back(std::move(row));
    c.nonfinite += s.rows.nonfinite;
  }
  return c;
}

std::vector<RankEntry> rank_bump(const Plan& plan, const std::vector<ComparisonRow>& rows,
                                 const std::string& scene) {
  return rank_rows(
      plan, rows, SectionKind::kBump, scene,
      [](const ComparisonRow& r) { return r.profile.rmse_terminator; },
      [](const ComparisonRow&) { return 0.0; });
}

std::vector<RankEntry> rank_lowpoly(const Plan& plan, const Section& section,
                                    const std::vector<ComparisonRow>& rows,
                                    const std::string& scene) {
  // The tessellation level is averaged over; any other axis (Phong
  // refinement, normal interpolation) is a different mesh, ranked apart.
  auto group = [&section](const Variant& v) {
    std::string suffix;
    for (std::size_t i = 0; i < section.axes.size() && i < v.axis_values.size(); ++i) {
      if (int(i) == section.convergence_axis) continue;
      const StudyAxis& axis = section.axes[i];
      suffix += suffix.empty() ? " (" : ", ";
      suffix += axis.label + ": " + axis_value_text(axis.pointer, v.axis_values[i]);
    }
    return suffix.empty() ? suffix : suffix + ")";
  };
  // Entries pair up on the same scene at the same tessellation level, so
  // that values of the other axes (ranked apart) compare pairwise too.
  auto pair_key = [&section](const Variant& v) {
    const int c = section.convergence_axis;
    if (c < 0 || std::size_t(c) >= v.axis_values.size()) return v.scene;
    return v.scene + " " + v.axis_values[std::size_t(c)].dump();
  };
  return rank_rows(
      plan, rows, SectionKind::kLowPoly, scene,
      [](const ComparisonRow& r) { return r.shadow->darkened_fraction; },
      [](const ComparisonRow& r) { return r.profile.rmse_terminator; }, group, pair_key, true);
}

}  // namespace penumbra
