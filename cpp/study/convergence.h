// Ground-truth convergence, checked not assumed (bump section). Each
// variant's evaluator ground truth (the displaced mesh) is rendered again
// with the edge length halved and, separately, with four times the samples
// per pixel; each change is
//   max(terminator-region profile RMSE, grazing-view RMSE) of one truth
//   against the other (fractions of albedo*E/pi, analysis/metrics.h),
// which bounds how far either metric of any method can move when the truth
// is replaced by the refined one (triangle inequality of the RMS). A setting
// whose change is at or above the tolerance is refined and checked again
// (an edge change that stays above it once the mesh budget is spent is
// checked again with more samples: at few samples it carries their noise),
// until both changes are below it or the budget ends: check renders go down
// to edge_length / 2^max_edge_refinements and up to spp * 4^max_spp_refinements,
// and never above the study's memory limit. The variant's evaluator renders
// (its truth and every method) then use the settings reached, so that method
// and truth are sampled alike; the external renderers keep theirs.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "image/image.h"
#include "study/plan.h"

namespace penumbra {

// One check: the truth at (edge_length, spp) against its two refinements.
struct ConvergenceStep {
  double edge_length = 0.0;  // scene units
  int spp = 0;
  double edge_change = 0.0;  // against edge_length / 2; NaN when not rendered
  double spp_change = 0.0;   // against 4 spp; NaN when not rendered
};

struct VariantConvergence {
  std::size_t variant = 0;
  double edge_length = 0.0;  // the settings reached, used for the variant
  int spp = 0;
  double reached = 0.0;  // max(edge_change, spp_change) at those settings
  bool converged = false;
  std::string why;  // when not converged: the budget, a failed render
  std::vector<ConvergenceStep> steps;
};

// What the next check does, from the last one's changes.
struct ConvergenceDecision {
  bool done = false;       // converged, or the budget is spent
  bool converged = false;  // both changes below the tolerance
  bool refine_edge = false, refine_spp = false;
};

// `edge_steps`/`spp_steps`: refinements already made. A change that is NaN
// (its render failed) cannot converge.
ConvergenceDecision decide_refinement(double edge_change, double spp_change, int edge_steps,
                                      int spp_steps, const GroundTruthSettings& settings);

// The change between two truths of the same variant (see above).
double truth_change(const Image& truth, const Image& refined, double radiance_scale);

// One variant's chain of checks as a round finds it: its truth (the plan's
// job, at the plan's settings), the refinements made so far, and which of
// the round's jobs are its checks (jobs[first, first + count)). A Slurm run
// hands the rest of a chain to one array task (continue_chain) rather than
// submitting every round.
struct ChainState {
  const Job* truth = nullptr;
  int edge_steps = 0, spp_steps = 0;
  std::size_t first = 0, count = 0;
};

// Renders jobs (through the study's cache); an entry is nullopt when its
// render failed, with the error in `errors`. `chains` says whose checks they are.
using RenderBatch = std::function<std::vector<std::optional<Image>>(
    const std::vector<Job>& jobs, const std::vector<ChainState>& chains,
    std::vector<std::string>* errors)>;

// Runs the checks for every bump variant with an evaluator truth, in rounds
// (one batch of renders per round, all variants together), then sets the
// settings reached on the variant's evaluator jobs. Keys must be assigned
// again afterwards.
std::vector<VariantConvergence> converge_truths(Plan& plan, const GroundTruthSettings& settings,
                                                double max_memory_bytes, const RenderBatch& render);

// The rest of one variant's chain, from `edge_steps` and `spp_steps`
// refinements of `truth` (the plan's job) to its end, one round at a time:
// the same checks and decisions as converge_truths makes for that variant,
// so that the renders it leaves in the cache let converge_truths finish the
// variant without rendering. `steps` then holds this call's checks only.
VariantConvergence continue_chain(const Job& truth, int edge_steps, int spp_steps,
                                  const GroundTruthSettings& settings, double max_memory_bytes,
                                  const RenderBatch& render);

// `job` at the settings reached, when it is an evaluator job (the others
// keep theirs). Its key must be assigned again.
void apply_convergence(Job& job, const VariantConvergence& r);

// "ground truth v003 (...): converged at edge length 0.006, 16 spp (change ...)".
std::string convergence_log_line(const Plan& plan, const VariantConvergence& r);

}  // namespace penumbra
