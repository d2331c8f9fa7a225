// `penumbra fit`: what any terminator factor of given inputs could achieve
// on a finished study's variants (analysis/achievable.h), how much of it
// each shipped method captures, and a table fitted without the scene family
// it is measured on.
//
// Reads the study folder's report.json and the cached renders it names:
// each variant's raw-bump render (evaluator, bump, `none`) and its ground
// truth (evaluator, displacement). Raw bump is re-traced with the tally
// (render_tallied), which must give the cached image's bits; a variant
// whose re-traced image differs is left out and counted.
//
// Errors are the terminator-profile RMSE (analysis/metrics.h, fraction of
// albedo*E/pi), pooled over variants as a root mean square, the quantity
// the floor minimises: E = sqrt(mean over variants of RMSE^2). The image
// RMSE's floors (ImageFloors) are per variant: the image is not binned by
// an input, so a G fitted to one variant is not exact by construction.
#pragma once

#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "analysis/achievable.h"
#include "analysis/statistics.h"
#include "core/factor_table.h"
#include "study/fit_probes.h"

namespace penumbra {

// The grid `fit` uses for the inputs light and deviation: light [20, 120)
// degrees in 2-degree cells, deviation [0, 60) in 4-degree cells, G at the
// cells' centres and multilinear between them, in [0, 2]. It covers where
// the shipped factors of these inputs differ from 1 on the default study:
// tabulated on it, estevez2019 and deshmukh2020 reproduce their rendered
// errors to under 0.1 percentage point (fit.json, on_grid). Light outside
// the grid keeps G = 1; fit.json reports what share of the tallied light
// that is.
FactorGrid default_fit_grid();

// The input sets `penumbra fit --inputs` offers, each on its own grid:
//   light,deviation               default_fit_grid()
//   light,deviation,shading       light [20, 120) in 4-degree cells, deviation
//                                 [0, 60) in 6, shading [0, 180) in 12
//   light,deviation,shading,view  light in 5-degree cells, deviation in 10,
//                                 shading in 15 and view [0, 90) in 45
// The added axes are coarser so that the cells some variant can light stay
// near the default grid's count (a point's shading angle lies within its
// deviation of its light angle, so a third of the shading cells can be lit
// at each light and deviation): with many more free cells than the
// profiles have bins, any floor reaches zero and says nothing. Shading
// spans every angle, so no point leaves the grid through it.
inline constexpr const char* kFitInputSets[] = {"light,deviation", "light,deviation,shading",
                                                "light,deviation,shading,view"};
// The grid of one of kFitInputSets; std::invalid_argument for another set.
FactorGrid fit_grid(const std::string& inputs);
// `grid` with some axes' cells resized: each of `steps` is "AXIS=DEGREES"
// (`fit --step shading=6`), AXIS one of the grid's inputs, DEGREES dividing
// its range. std::invalid_argument naming what was expected otherwise.
// At most kMaxFitCells cells in all.
FactorGrid with_steps(FactorGrid grid, const std::vector<std::string>& steps);
inline constexpr int kMaxFitCells = 100000;
// The inputs of a grid, comma-separated in axis order ("light,deviation").
std::string grid_inputs(const FactorGrid& grid);

struct FitOptions {
  std::string folder;  // a finished study's output folder
  FactorGrid grid = default_fit_grid();
  // Candidate weights of the smoothness prior (FloorOptions::smoothness) for
  // the held-out tables, each chosen by leave-one-family-out within the
  // families it is fitted on.
  std::vector<double> smoothness = {0.1, 1.0, 10.0};
  int resamples = 2000;  // bootstrap over variants
  std::uint64_t seed = 1;
  // Floor solves at once (0: the cores). The result does not depend on it.
  int jobs = 0;
  std::function<void(const std::string&)> progress;  // one line per step
};

// A pooled error E over a set of variants and its 95 % percentile-bootstrap
// interval over those variants.
struct PooledError {
  double value = 0.0;
  Interval interval;
};

// A pooled error minus another over the same variants, paired: both are
// recomputed on each resample. A tie when its interval holds 0.
struct PairedError {
  PooledError difference;
  bool tie = true;
};

struct FitVariant {
  std::string id, family;  // family: the variant's scene
  TallyVariant data;
  // Per probed constant (FitResult::probed), per value tried: the
  // terminator RMSE of the method with that value (study/fit_probes.h).
  std::vector<std::vector<double>> probe_rmse;
  // The image RMSE (ImageMetrics::rmse / albedo*E/pi) through the tally's
  // pixel rows (analysis/achievable.h, PixelRows): raw bump's (G = 1) and
  // the variant's own floor (solve_image_floor on the fit's grid), and per
  // shipped method whose factor is a function of the grid's inputs, its
  // table's (never below the floor: it is one of the G the floor ranges over).
  double image_none = std::nan(""), image_floor = std::nan("");
  double image_kkt_residual = 0.0;  // of the variant's floor solve
  std::map<std::string, double> image_on_grid;
  double radiance_scale = 0.0;  // albedo*E/pi of the variant, W m^-2 sr^-1
};

struct FloorFit {
  std::string scope;  // "study" or a family
  std::size_t variants = 0;
  PooledError floor, none;
  FloorSolution solution;
};

// The study floor of a factor of fewer inputs on the same grid: the fit's
// tallies with the other axes summed out (marginal_tally), so that every G
// it ranges over is one the fit's floor ranges over too. The fit's floor
// minus this one, paired over variants, is what the other inputs buy at the
// grid's resolution (never above 0 but for the solver's tolerance).
struct NestedFloor {
  std::string inputs;  // "light,deviation"
  FloorFit floor;
  PairedError gain;  // the fit's study floor minus this floor
};

struct HeldOutFit {
  std::string family;
  std::size_t variants = 0;
  double smoothness = 0.0;  // chosen without this family
  PooledError held_out;     // the table fitted without the family, on it
  double in_sample = 0.0;   // the study floor (fitted with it) on it
  PooledError none;
  std::string best_method;  // the shipped method with the lowest E on the family
  PooledError best;
  PairedError held_out_minus_best;  // held_out - best, paired over the family's variants
};

struct MethodShare {
  std::string method;
  PooledError error;
  // (E_none - E_method) / (E_none - E_floor) against the study floor.
  PooledError share;
  // Methods whose factor is a function of the grid's inputs: E of their
  // table at the cells' centres through the tally (cannot beat the floor),
  // and how far that is from their rendered E (the grid's resolution error).
  bool on_grid_inputs = false;
  double grid_error = 0.0, resolution_error = 0.0;
  // Tie groups by share: the highest share not yet grouped leads group 1,
  // 2, ...; each group holds every later method whose share minus the
  // leader's, paired over the same resamples, holds 0 (the leader: 0, a tie).
  int group = 0;
  std::string leader;
  PairedError versus_leader;
};

// One constant of a method, refitted. A method with several constants (deshmukh2020's d0
// and d1) has an entry for each, fitted together: the errors are those of the set, the
// interval each constant's own over the same resamples.
struct FittedConstant {
  std::string method, constant;         // constant: its symbol first, then where it enters
  std::string reference = "published";  // what `published` is
  double published = 0.0, fitted = 0.0;
  Interval interval;         // bootstrap over variants, refitted per resample
  PooledError in_sample;     // E at the fitted value, all variants
  PooledError at_published;  // E at the published value, all variants
  // E with the value fitted without each family, pooled, and its paired difference from
  // at_published; defined only where the variants span two or more families (a single
  // family has nothing to fit on once it is held out).
  bool held_out_defined = false;
  PooledError held_out;
  PairedError held_out_minus_published;  // paired over all variants
  // Which edge of the search's range the fit on every variant reached
  // ("d at deviation 60 degrees = 1"), "" where none: E would fall further
  // outside the range, and the interval holds within it.
  std::string at_bound;
  // Constants fitted through the re-trace's probes: the largest difference,
  // over the variants, of E at `published` from the error of the study's own
  // render of the method with it (rounding; NaN where the study has none).
  double probe_minus_rendered = std::nan("");
};

// A low-poly offset's parameter (`epsilon`'s distance, Cycles' cutoff,
// phong2008's alpha, OSPRay's ulp) refitted among the values the study's
// low-poly section rendered: the parameter moves the shadow ray's origin,
// so raw bump's re-trace cannot probe it and each value is a render. The
// error is the image RMSE (ImageMetrics::rmse / albedo*E/pi) of the
// evaluator's mesh render against the analytic surface, recomputed from
// the cache, pooled over the low-poly variants that rendered every value:
// it counts both what a small offset leaves (the shadow line) and what a
// large one loses (cast shadows). `fit`'s method is the offset's id, its
// constant the parameter's name and unit; families are the low-poly scenes.
struct FittedOffsetParameter {
  FittedConstant fit;
  std::vector<double> values;       // rendered, ascending
  std::vector<PooledError> errors;  // E at each value over every variant
  std::size_t variants = 0;
  // The largest difference of a recomputed image RMSE from the study
  // report's (W m^-2 sr^-1; rounding).
  double report_difference = 0.0;
};

// The image metric's per-variant floors (FitVariant::image_floor), pooled as
// the profile's are: E = sqrt(mean over variants of RMSE^2).
struct ImageFloors {
  PooledError floor, none;  // none: raw bump through the tally
  // The largest difference, over the variants, of raw bump's image RMSE
  // through the tally from the study report's (its float rounding).
  double none_minus_report = std::nan("");
  double kkt_residual = 0.0;  // the largest of the variants' floor solves
  // Each method's image RMSE, from the study's report, and its share of
  // the floors' gain on raw bump; by error, lowest first. A share above 1
  // only for a method that is not a factor of the grid's inputs.
  std::vector<MethodShare> methods;
};

struct FitResult {
  std::string folder, study;
  FactorGrid grid;
  std::vector<FitVariant> variants;
  std::size_t retraced = 0, retraced_different = 0, skipped = 0;
  // Variants left out because their ground truth did not converge
  // (report.json's /ground_truth/variants), by id; not counted in skipped.
  std::vector<std::string> unconverged;
  double outside_share = 0.0;  // of the terminator bins' tallied light, outside the grid
  FloorFit study_floor;
  std::vector<NestedFloor> nested;  // each shorter set of kFitInputSets, shortest first
  std::vector<FloorFit> family_floors;
  std::vector<HeldOutFit> held_out;
  PooledError held_out_pooled;  // every family's held-out errors pooled
  // The shipped method (not raw bump, not a fitted table) with the lowest E
  // over every variant, and the held-out table against it, paired.
  std::string best_method;
  PairedError held_out_minus_best;
  std::vector<MethodShare> shares;
  std::vector<FittedConstant> constants;
  // The constants fitted through the re-trace's probes (light,deviation
  // fits only), in FitVariant::probe_rmse's order.
  std::vector<ProbedConstant> probed;
  ImageFloors image;
  // Every low-poly offset rendered at two or more values of its parameter.
  std::vector<FittedOffsetParameter> offset_parameters;
  FactorTable table;  // fitted on every variant, smoothness chosen by leave-one-family-out
  double table_smoothness = 0.0;
  std::vector<double> smoothness_candidates;  // FitOptions::smoothness
  double seconds = 0.0;
};

// InputError naming report.json for a folder that is not a finished study
// or holds no variant to fit.
FitResult fit_study(const FitOptions& options);

// estevez2019's factor with alpha^2 = k tan^2(delta) (the published k is
// 1/8) on a light,deviation grid, at the cells' centres.
std::vector<double> estevez2019_table(const FactorGrid& grid, double k);
// The k minimising the mean squared terminator RMSE of estevez2019_table
// over `variants` (golden section on log k in [1e-3, 10]).
double fit_estevez2019_k(const std::vector<TallyVariant>& variants, const FactorGrid& grid);

// deshmukh2020's two constants: its smoothstep of <Ng,wi>/d darkens light
// from <Ng,wi> = d down to the terminator, with d = d0 + (d1 - d0) <Ns,Ng>
// (dimensionless cosines; published d0 = 0.14922, d1 = 0.01999).
struct Deshmukh2020Constants {
  double d0 = 0.0, d1 = 0.0;
};
inline constexpr Deshmukh2020Constants kDeshmukh2020Published{0.14922, 0.01999};
// deshmukh2020's factor with constants `c` on a light,deviation grid, at the
// cells' centres (at the published constants, core/terminator's
// deshmukh2020 to the bit).
std::vector<double> deshmukh2020_table(const FactorGrid& grid, const Deshmukh2020Constants& c);
// The (d0, d1) minimising the mean squared terminator RMSE of
// deshmukh2020_table over `variants`, with d in (0, 1] over the grid's
// deviations (d0, at 90 degrees, is not bounded): a coarse grid in the
// angles asin(d) at the deviation axis' two ends, at half the light axis'
// step, then Nelder-Mead from the best of it and the published pair (so E
// at the fit is never above E at the published constants).
Deshmukh2020Constants fit_deshmukh2020(const std::vector<TallyVariant>& variants,
                                       const FactorGrid& grid);

// fit.json (everything), fit.csv (one row per number) and table.json (the
// fitted table) in `out`.
void write_fit(const FitResult& result, const std::filesystem::path& out);

// What a fit of the study folder `study` is made from: report.json less its
// provenance (it names every render by its content key), the evaluator's
// code digest (the fit re-traces raw bump), Penumbra's version and the
// version of fit.json's contents.
std::string fit_inputs_digest(const std::filesystem::path& study);
// Whether `fit_dir` holds fit.json, fit.csv and table.json of a fit from
// `digest` (its .inputs stamp), and writing that stamp after a fit.
bool fit_is_current(const std::filesystem::path& fit_dir, const std::string& digest);
void write_fit_stamp(const std::filesystem::path& fit_dir, const std::string& digest);

}  // namespace penumbra
