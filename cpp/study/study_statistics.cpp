// The study-level statistics: the overall ranking, one per scene and one per
// level of every axis, the interaction tests, and the report's lead.
#include <algorithm>
#include <cmath>
#include <map>
#include <thread>

#include "study/ranking.h"
#include "study/ranking_text.h"
#include "util/parallel.h"

namespace penumbra {
namespace {

// The level of axis `a` each bump variant has (-1: another section, or a
// value the axis does not list).
std::vector<int> variant_levels(const Plan& plan, const StudyAxis& axis, std::size_t a) {
  std::vector<int> level(plan.variants.size(), -1);
  for (std::size_t v = 0; v < plan.variants.size(); ++v) {
    const Variant& var = plan.variants[v];
    if (var.section != SectionKind::kBump || a >= var.axis_values.size()) continue;
    const auto it = std::find(axis.values.begin(), axis.values.end(), var.axis_values[a]);
    if (it != axis.values.end()) level[v] = static_cast<int>(it - axis.values.begin());
  }
  return level;
}

// Matched variants for axis `a`: those with the same scene and the same
// values on every other axis share a block.
std::vector<int> variant_blocks(const Plan& plan, std::size_t a) {
  std::map<std::string, int> ids;
  std::vector<int> block(plan.variants.size(), -1);
  for (std::size_t v = 0; v < plan.variants.size(); ++v) {
    const Variant& var = plan.variants[v];
    if (var.section != SectionKind::kBump) continue;
    std::string key = var.scene;
    for (std::size_t k = 0; k < var.axis_values.size(); ++k)
      if (k != a) key += "\n" + var.axis_values[k].dump();
    block[v] = ids.emplace(key, static_cast<int>(ids.size())).first->second;
  }
  return block;
}

// C(method, v) per bump variant of the plan, from the evaluator rows.
std::vector<double> combined_per_variant(const Plan& plan, const std::vector<ComparisonRow>& rows,
                                         const std::string& method) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> sum(plan.variants.size(), nan), none(plan.variants.size(), nan);
  for (const ComparisonRow& row : rows) {
    if (row.renderer != RendererKind::kEvaluator ||
        row.reference_renderer != RendererKind::kEvaluator ||
        plan.variants[row.variant].section != SectionKind::kBump)
      continue;
    const double e = row.profile.rmse_terminator + row.view.rmse_grazing;
    if (row.method == method) sum[row.variant] = e;
    if (row.method == "none") none[row.variant] = e;
  }
  std::vector<double> c(plan.variants.size(), nan);
  for (std::size_t v = 0; v < c.size(); ++v)
    if (std::isfinite(sum[v]) && std::isfinite(none[v]) && none[v] > 0.0) c[v] = sum[v] / none[v];
  return c;
}

// Every method's interaction test on every axis, then Holm over all of them.
void interaction_tests(const Plan& plan, const std::vector<ComparisonRow>& rows,
                       const std::vector<StudyAxis>& axes, const std::vector<std::string>& methods,
                       std::vector<AxisStatistics>& by_axis) {
  std::vector<std::pair<std::size_t, std::size_t>> tests;  // (axis, method)
  for (std::size_t a = 0; a < axes.size(); ++a)
    for (std::size_t m = 0; m < methods.size(); ++m)
      if (methods[m] != "none") tests.push_back({a, m});
  std::vector<LevelTest> results(tests.size());
  std::vector<std::vector<double>> combined;
  for (const std::string& m : methods) combined.push_back(combined_per_variant(plan, rows, m));
  run_parallel(static_cast<int>(std::thread::hardware_concurrency()), tests.size(),
               [&](std::size_t k) {
                 const auto [a, m] = tests[k];
                 const std::vector<int> level = variant_levels(plan, axes[a], a);
                 const std::vector<int> block = variant_blocks(plan, a);
                 std::vector<double> y;
                 std::vector<int> l, b;
                 for (std::size_t v = 0; v < plan.variants.size(); ++v)
                   if (level[v] >= 0)
                     y.push_back(combined[m][v]), l.push_back(level[v]), b.push_back(block[v]);
                 results[k] = level_permutation_test(y, l, b, kInteractionPermutations);
               });
  std::vector<double> p;
  for (const LevelTest& t : results) p.push_back(t.p);
  const std::vector<double> adjusted = holm_adjust(p);
  for (std::size_t k = 0; k < tests.size(); ++k) {
    Interaction i;
    i.method = methods[tests[k].second];
    i.test = results[k];
    i.p_holm = adjusted[k];
    i.depends = results[k].blocks >= 2 && adjusted[k] < kSignificance;
    by_axis[tests[k].first].interactions.push_back(std::move(i));
  }
}

bool numeric_axis(const StudyAxis& a) {
  return a.sets.empty() && std::all_of(a.values.begin(), a.values.end(),
                                       [](const nlohmann::json& v) { return v.is_number(); });
}

// Whether an axis sets the kind of light: each of its levels lights all
// its variants with one kind (distant, sphere, quad, environment), and not
// every level the same kind. An axis crossed with it (the amplitude) mixes
// kinds within a level and is not one.
bool sets_light_type(const Plan& plan, const std::vector<int>& level, std::size_t levels) {
  std::vector<std::string> type(levels);
  for (std::size_t v = 0; v < plan.variants.size(); ++v) {
    if (level[v] < 0 || plan.variants[v].jobs.empty()) continue;
    const nlohmann::json scene = plan.jobs[plan.variants[v].jobs.front()].scene_json();
    const std::string t = scene.at("light").value("type", std::string("distant"));
    std::string& kind = type[static_cast<std::size_t>(level[v])];
    if (!kind.empty() && kind != t) return false;
    kind = t;
  }
  return std::any_of(type.begin(), type.end(),
                     [&](const std::string& t) { return !t.empty() && t != type.front(); });
}

// The rankings to compute: overall, per scene, per axis level.
struct RankingTask {
  std::vector<char> selected;
  bool all_pairs = false;
  RankingStatistics* out = nullptr;
  std::string scene;
};

std::vector<RankingTask> ranking_tasks(const Plan& plan, const std::vector<StudyAxis>& axes,
                                       StudyStatistics& s) {
  const std::size_t n = plan.variants.size();
  std::vector<RankingTask> tasks;
  tasks.push_back({std::vector<char>(n, 1), true, &s.overall, ""});
  std::vector<std::string> scenes;
  for (const Variant& v : plan.variants)
    if (v.section == SectionKind::kBump &&
        std::find(scenes.begin(), scenes.end(), v.scene) == scenes.end()) {
      scenes.push_back(v.scene);
      s.mesh_scenes |=
          !v.jobs.empty() && plan.jobs[v.jobs.front()].scene().shape.type == ShapeType::kMesh;
    }
  s.per_scene.resize(scenes.size());
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    std::vector<char> sel(n, 0);
    for (std::size_t v = 0; v < n; ++v) sel[v] = plan.variants[v].scene == scenes[i];
    tasks.push_back({std::move(sel), false, &s.per_scene[i], scenes[i]});
  }
  s.by_axis.resize(axes.size());
  for (std::size_t a = 0; a < axes.size(); ++a) {
    AxisStatistics& axis = s.by_axis[a];
    axis.pointer = axes[a].pointer;
    axis.label = axes[a].label;
    axis.numeric = numeric_axis(axes[a]);
    axis.levels.resize(axes[a].values.size());
    const std::vector<std::string> ids = axis_value_ids(axes[a]);
    const std::vector<int> level = variant_levels(plan, axes[a], a);
    axis.lighting = sets_light_type(plan, level, axes[a].values.size());
    for (std::size_t l = 0; l < axes[a].values.size(); ++l) {
      LevelRanking& lr = axis.levels[l];
      lr.value = axes[a].values[l];
      lr.value_label = axis_value_text(axes[a].pointer, lr.value);
      lr.value_id = ids[l];
      std::vector<char> sel(n, 0);
      for (std::size_t v = 0; v < n; ++v) sel[v] = level[v] == static_cast<int>(l);
      tasks.push_back({std::move(sel), false, &lr.ranking, ""});
    }
  }
  return tasks;
}

}  // namespace

StudyStatistics study_statistics(const Plan& plan, const std::vector<ComparisonRow>& rows,
                                 const std::vector<StudyAxis>& axes) {
  StudyStatistics s;
  std::vector<RankingTask> tasks = ranking_tasks(plan, axes, s);
  // Each ranking draws from its own fixed seeds: the threads change no bit.
  run_parallel(
      static_cast<int>(std::thread::hardware_concurrency()), tasks.size(), [&](std::size_t k) {
        *tasks[k].out = ranking_statistics(plan, rows, tasks[k].selected, tasks[k].all_pairs);
        tasks[k].out->scene = tasks[k].scene;
      });
  if (s.overall.methods.empty()) return s;
  std::vector<std::string> methods;
  for (const MethodStatistics& m : s.overall.methods) methods.push_back(m.method);
  interaction_tests(plan, rows, axes, methods, s.by_axis);
  s.headline = lead_sentences(s);
  s.notes = quantity_notes(s, plan, rows);
  return s;
}

}  // namespace penumbra
