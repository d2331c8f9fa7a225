#include "study/convergence.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "analysis/measure.h"
#include "scene/scene_json.h"

namespace penumbra {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// One variant's state between rounds.
struct Track {
  std::size_t variant = 0;
  const Job* truth = nullptr;  // the plan's evaluator truth, at the plan's settings
  double edge_length0 = 0.0;
  int spp0 = 0;
  int edge_steps = 0, spp_steps = 0;
  bool done = false;
  VariantConvergence result;
  double edge_length() const { return edge_length0 / double(1 << edge_steps); }
  int spp() const { return spp0 << (2 * spp_steps); }
};

// The overrides that set the ground truth's edge length and samples.
OverrideList sampling(double edge_length, int spp) {
  return std::make_shared<const std::vector<Override>>(
      std::vector<Override>{{"/displacement/edge_length", edge_length}, {"/camera/spp", spp}});
}

// The plan's truth job with other settings; nullopt (and why) when the scene
// would need more memory than allowed or more triangles than a truth may
// have (the reader's limit, kMaxDisplacementTriangles): the budget ends
// there for that variant instead of the study.
std::optional<Job> truth_at(const Job& truth, double edge_length, int spp, double max_memory_bytes,
                            std::string* why) {
  Job job = truth;
  try {
    job.refine(sampling(edge_length, spp), nullptr);  // renders once: kept as its recipe
  } catch (const InputError& e) {
    *why = fmt::format("a check at edge length {:g} cannot be rendered: {}", edge_length, e.what());
    return std::nullopt;
  }
  job.label = fmt::format("{}-e{:g}-s{}", truth.label, edge_length, spp);
  if (job.resources.memory_bytes > max_memory_bytes) {
    *why = fmt::format("a check at edge length {:g} needs {:.1f} GiB, above the limit of {:.1f}",
                       edge_length, job.resources.memory_bytes / kGiB, max_memory_bytes / kGiB);
    return std::nullopt;
  }
  return job;
}

Track track_of(const Job& truth, int edge_steps, int spp_steps) {
  Track track;
  track.truth = &truth;
  const Scene scene = truth.scene();
  track.edge_length0 = scene.displacement.edge_length;
  track.spp0 = scene.camera.spp;
  track.edge_steps = edge_steps, track.spp_steps = spp_steps;
  return track;
}

std::vector<Track> tracks_of(const Plan& plan) {
  std::vector<Track> tracks;
  for (std::size_t v = 0; v < plan.variants.size(); ++v) {
    if (plan.variants[v].section != SectionKind::kBump) continue;
    const long t = plan.truth(v, RendererKind::kEvaluator);
    if (t < 0) continue;
    tracks.push_back(track_of(plan.jobs[t], 0, 0));
    tracks.back().variant = tracks.back().result.variant = v;
  }
  return tracks;
}

// The three renders one check needs: the truth, edge halved, spp x 4.
struct CheckJobs {
  std::optional<Job> current, edge, spp;
  std::string why;
};

CheckJobs check_jobs(const Track& t, double max_memory_bytes) {
  const Job& truth = *t.truth;
  CheckJobs c;
  c.current = truth_at(truth, t.edge_length(), t.spp(), max_memory_bytes, &c.why);
  c.edge = truth_at(truth, t.edge_length() / 2.0, t.spp(), max_memory_bytes, &c.why);
  c.spp = truth_at(truth, t.edge_length(), 4 * t.spp(), max_memory_bytes, &c.why);
  return c;
}

// The mean of the samples a check at 4x the samples adds to the truth it
// checks, where its pattern nests the truth's (a jittered camera,
// core/sample_pattern.h): its first quarter of samples are the truth's, so
// the change to it would hide that share of their noise (expected square
// 3/4 of the truth's own error, against 5/4 for two independent renders).
// The samples added, (4 I_4s - I_s) / 3 in radiance and coverage, are
// independent of the truth (expected square 4/3): the check stays at least
// as strict as with independent renders. Angles: the refined image's.
Image added_samples(const Image& truth, const Image& refined) {
  Image out = refined;
  for (const std::string& name : rgba_channels()) {
    const int r = refined.channel_index(name), t = truth.channel_index(name);
    if (r < 0 || t < 0) continue;
    for (int y = 0; y < out.height; ++y)
      for (int x = 0; x < out.width; ++x)
        out.at(x, y, r) = (4.0f * refined.at(x, y, r) - truth.at(x, y, t)) / 3.0f;
  }
  return out;
}

// Whether the sample check of `t` nests its truth (added_samples).
bool nests_truth(const Track& t) {
  return t.truth->scene().camera.jitter && nests(t.spp(), 4 * t.spp());
}

// Records a check's changes and moves the track on.
void advance(Track& t, double edge_change, double spp_change, const GroundTruthSettings& s,
             const std::string& why) {
  t.result.steps.push_back({t.edge_length(), t.spp(), edge_change, spp_change});
  const ConvergenceDecision d =
      decide_refinement(edge_change, spp_change, t.edge_steps, t.spp_steps, s);
  if (!d.done) {
    t.edge_steps += d.refine_edge;
    t.spp_steps += d.refine_spp;
    return;
  }
  t.done = true;
  t.result.edge_length = t.edge_length(), t.result.spp = t.spp();
  t.result.reached = std::max(edge_change, spp_change);
  if (std::isnan(edge_change) || std::isnan(spp_change)) t.result.reached = kNaN;
  t.result.converged = d.converged;
  if (!d.converged)
    t.result.why = !why.empty() ? why
                                : fmt::format(
                                      "the budget ({} edge, {} sample refinements) ended "
                                      "above the tolerance {:g}",
                                      s.max_edge_refinements, s.max_spp_refinements, s.tolerance);
}

// One round: every unfinished track's check, rendered as one batch; with
// `reversed`, the tracks in the reverse order (each track's renders still
// in order: a sample check extends the truth before it), so that the
// displaced meshes the last round built last, which the process's mesh
// cache still holds, are the first this one asks for.
void run_round(std::vector<Track>& tracks, const GroundTruthSettings& s, double max_memory_bytes,
               const RenderBatch& render, bool reversed = false) {
  std::vector<Job> batch;
  std::vector<ChainState> chains;
  std::vector<std::pair<std::size_t, CheckJobs>> checks;
  for (std::size_t n = 0; n < tracks.size(); ++n) {
    const std::size_t k = reversed ? tracks.size() - 1 - n : n;
    if (tracks[k].done) continue;
    CheckJobs c = check_jobs(tracks[k], max_memory_bytes);
    ChainState chain{tracks[k].truth, tracks[k].edge_steps, tracks[k].spp_steps, batch.size(), 0};
    for (const std::optional<Job>* j : {&c.current, &c.edge, &c.spp})
      if (*j) batch.push_back(**j);
    chain.count = batch.size() - chain.first;
    chains.push_back(chain);
    checks.push_back({k, std::move(c)});
  }
  std::vector<std::string> errors;
  const std::vector<std::optional<Image>> images = render(batch, chains, &errors);
  std::size_t next = 0;
  for (auto& [k, c] : checks) {
    Track& t = tracks[k];
    const std::size_t first = next;
    const std::optional<Image>* current = c.current ? &images[next++] : nullptr;
    const std::optional<Image>* edge = c.edge ? &images[next++] : nullptr;
    const std::optional<Image>* spp = c.spp ? &images[next++] : nullptr;
    const double scale = radiance_scale(t.truth->scene());
    auto change = [&](const std::optional<Image>* refined, bool nested) {
      if (!(current && *current && refined && *refined)) return kNaN;
      return truth_change(**current, nested ? added_samples(**current, **refined) : **refined,
                          scale);
    };
    std::string why = c.why;
    for (std::size_t e = first; e < next; ++e)
      if (!errors[e].empty() && why.empty()) why = "a check render failed: " + errors[e];
    advance(t, change(edge, false), change(spp, nests_truth(t)), s, why);
  }
}

// The variant's evaluator jobs at the settings reached.
void apply(Plan& plan, const VariantConvergence& r) {
  const auto settings = sampling(r.edge_length, r.spp);
  std::shared_ptr<const Scene> shared;  // one for the variant's evaluator jobs
  for (std::size_t j : plan.variants[r.variant].jobs)
    if (plan.jobs[j].renderer == RendererKind::kEvaluator) plan.jobs[j].refine(settings, &shared);
}

}  // namespace

void apply_convergence(Job& job, const VariantConvergence& r) {
  if (job.renderer != RendererKind::kEvaluator) return;
  std::shared_ptr<const Scene> shared;
  job.refine(sampling(r.edge_length, r.spp), &shared);
}

VariantConvergence continue_chain(const Job& truth, int edge_steps, int spp_steps,
                                  const GroundTruthSettings& settings, double max_memory_bytes,
                                  const RenderBatch& render) {
  std::vector<Track> tracks{track_of(truth, edge_steps, spp_steps)};
  tracks[0].variant = tracks[0].result.variant = truth.variant;
  while (!tracks[0].done) run_round(tracks, settings, max_memory_bytes, render);
  return tracks[0].result;
}

std::string convergence_log_line(const Plan& plan, const VariantConvergence& r) {
  const Variant& v = plan.variants[r.variant];
  // A check that could not be rendered leaves the change unmeasured.
  const std::string change = std::isnan(r.reached) ? std::string("change not measured")
                                                   : fmt::format("change {:.2g}", r.reached);
  return fmt::format("ground truth {} ({}): {} at edge length {:g}, {} spp ({}{})", v.id, v.label,
                     r.converged ? "converged" : "NOT CONVERGED", r.edge_length, r.spp, change,
                     r.converged ? "" : "; " + r.why);
}

ConvergenceDecision decide_refinement(double edge_change, double spp_change, int edge_steps,
                                      int spp_steps, const GroundTruthSettings& s) {
  ConvergenceDecision d;
  const bool edge_ok = edge_change < s.tolerance, spp_ok = spp_change < s.tolerance;
  if (edge_ok && spp_ok) {
    d.done = d.converged = true;
    return d;
  }
  if (std::isnan(edge_change) || std::isnan(spp_change)) {
    d.done = true;  // a check that did not render cannot be trusted either way
    return d;
  }
  // A refinement is affordable when its own check stays within the budget.
  d.refine_edge = !edge_ok && edge_steps + 1 < s.max_edge_refinements;
  // The edge change is measured at the current samples and carries their
  // noise along hard shadow edges: when the mesh cannot be refined further,
  // more samples tell a geometric error from that noise.
  const bool spp_left = spp_steps + 1 < s.max_spp_refinements;
  d.refine_spp = spp_left && (!spp_ok || (!edge_ok && !d.refine_edge));
  // A setting that cannot be refined any further will never converge.
  d.done = (!edge_ok && !d.refine_edge && !d.refine_spp) || (!spp_ok && !d.refine_spp);
  if (d.done) d.refine_edge = d.refine_spp = false;
  return d;
}

double truth_change(const Image& truth, const Image& refined, double radiance_scale) {
  MeasureOptions options;
  options.scale = radiance_scale;
  options.intervals = options.image = false;
  const Measurement m = measure(refined, truth, options);
  const double profile = m.profile.rmse_terminator;
  const double view = m.view.rmse_grazing;
  // A truth without grazing views (or without a terminator) constrains only
  // the other; one without either has no profile to converge.
  if (std::isnan(profile)) return view;
  return std::isnan(view) ? profile : std::max(profile, view);
}

std::vector<VariantConvergence> converge_truths(Plan& plan, const GroundTruthSettings& settings,
                                                double max_memory_bytes,
                                                const RenderBatch& render) {
  std::vector<Track> tracks = tracks_of(plan);
  if (settings.max_edge_refinements == 0 || settings.max_spp_refinements == 0) {
    for (Track& t : tracks)
      advance(t, kNaN, kNaN, settings, "a refinement budget is 0: nothing was checked");
  }
  for (int round = 0;
       std::any_of(tracks.begin(), tracks.end(), [](const Track& t) { return !t.done; }); ++round)
    run_round(tracks, settings, max_memory_bytes, render, round % 2 == 1);
  std::vector<VariantConvergence> out;
  for (const Track& t : tracks) {
    apply(plan, t.result);
    out.push_back(t.result);
  }
  return out;
}

}  // namespace penumbra
