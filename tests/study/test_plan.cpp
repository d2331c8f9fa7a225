// A plan keeps each job's scene as where it comes from (the scene file's
// document, override lists, a parsed part shared by the jobs of a variant and
// renderer, and the method's parts) rather than as a document and a reading
// of its own (issue 41, item 17). These tests check that what a job gives
// back is its own scene read in full, and that planning stays under a
// kibibyte per render.
#include <gtest/gtest.h>

#include "temp_dir_test.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "study/cache.h"
#include "study/convergence.h"
#include "study/plan.h"
#include "study/ranking.h"
#include "study/study_file.h"
#include "util/resource_usage.h"

namespace penumbra {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
const std::string kSource = PENUMBRA_SOURCE_DIR;

std::string vec_text(const Vec3& v) {
  return fmt::format("({:.17g} {:.17g} {:.17g})", v.x, v.y, v.z);
}

// Every value of a scene that a render reads, as text (a map or a table by
// its address: the same object, shared, or not).
std::string scene_text(const Scene& s) {
  const Camera& c = s.camera;
  std::string t = "name " + s.name + "\n";
  t += fmt::format("camera {} {} {} {} {} {}x{} {} {} {}\n", int(c.projection),
                   vec_text(c.position), vec_text(c.direction), vec_text(c.right), vec_text(c.up),
                   c.width, c.height, c.spp, c.seed, c.jitter);
  t += fmt::format("light {} {} {:.17g} {} {:.17g}\n", int(s.light.type),
                   vec_text(s.light.direction), s.light.irradiance, vec_text(s.light.position),
                   s.light.intensity);
  const Shape& sh = s.shape;
  t += fmt::format("shape {} {} {} {:.17g} {:.17g} {:.17g} {}\n", int(sh.type), vec_text(sh.center),
                   vec_text(sh.axis), sh.radius, sh.height, sh.width, sh.caps);
  if (s.tessellation)
    t += fmt::format("tessellation {} {} {} {} {}\n", int(s.tessellation->scheme),
                     s.tessellation->segments, s.tessellation->rings, s.tessellation->frequency,
                     int(s.tessellation->shading));
  t += fmt::format("offset {} {:.17g} {:.17g}\n", int(s.offset.method), s.offset.epsilon,
                   s.offset.cutoff);
  t += fmt::format("props {}\n", s.props.size());
  t += fmt::format("material {:.17g} {:.17g} {:.17g}\n", s.material.albedo,
                   s.material.specular_weight, s.material.specular_roughness);
  t += fmt::format("height {} {:.17g} {} {} {}\n", int(s.height.family), s.height.amplitude,
                   s.height.function.terms.size(), fmt::ptr(s.height.map.get()),
                   fmt::ptr(s.height.filtered.get()));
  const TerminatorSettings& m = s.terminator;
  t += fmt::format("terminator {} {:.17g} {} {} {} {} {}\n", int(s.representation),
                   m.method.shading_offset, int(m.method.method), fmt::ptr(m.method.table.get()),
                   int(m.normal_adjustment), int(m.reference_normal), int(m.lobes));
  t += fmt::format("displacement {:.17g}\n", s.displacement.edge_length);
  return t;
}

// Every shipped study: each job's scene, as the plan keeps it, is the scene
// its own document reads as (maps and tables are read once per study file
// and shared, so their addresses are compared after reading the document with
// the job's own: only values are compared for those).
TEST(Plan, EveryJobsSceneIsItsOwnDocumentReadInFull) {
  for (const fs::directory_entry& e : fs::directory_iterator(kSource + "/scenes/studies")) {
    if (e.path().extension() != ".json") continue;
    const Plan plan = plan_study(load_study(e.path().string()), 8.0 * (1ull << 30));
    for (const Job& job : plan.jobs) {
      Scene kept = job.scene();
      Scene read = scene_from_json(job.document(), job.origin());
      // The reader reads a map or a table anew each time: compare them by
      // content digest, then let the addresses agree.
      ASSERT_EQ(bool(kept.height.map), bool(read.height.map)) << job.label;
      if (kept.height.map) {
        EXPECT_EQ(kept.height.map->digest, read.height.map->digest);
      }
      read.height.map = kept.height.map;
      read.height.filtered = kept.height.filtered;
      ASSERT_EQ(bool(kept.terminator.method.table), bool(read.terminator.method.table));
      read.terminator.method.table = kept.terminator.method.table;
      EXPECT_EQ(scene_text(kept), scene_text(read)) << e.path().filename() << " " << job.label;
      EXPECT_EQ(job.representation, read.representation) << job.label;
    }
  }
}

// The ground truth's convergence sets its edge length and samples on every
// evaluator job of a variant, which share one reading again afterwards.
TEST(Plan, ARefinedJobReadsAsItsRefinedDocument) {
  Plan plan = plan_study(load_study(kSource + "/scenes/studies/quick.json"), 8.0 * (1ull << 30));
  VariantConvergence reached;
  reached.variant = 0;
  reached.edge_length = 0.003;
  reached.spp = 64;
  for (std::size_t j : plan.variants[0].jobs) {
    Job& job = plan.jobs[j];
    apply_convergence(job, reached);
    const Scene kept = job.scene();
    Scene read = scene_from_json(job.document(), job.origin());
    EXPECT_EQ(scene_text(kept), scene_text(read)) << job.label;
    const bool evaluator = job.renderer == RendererKind::kEvaluator;
    EXPECT_EQ(kept.camera.spp == 64, evaluator) << job.label;
    EXPECT_EQ(kept.displacement.edge_length == 0.003, evaluator) << job.label;
  }
}

// The shipped lighting study plans (its maps are Blender's own data files)
// into 4 scenes x 2 amplitudes x 8 lightings, and its lighting axis, and
// only that one, is told apart as lighting the scene with different kinds
// of light, so that the headline says whether the sun's winner wins under
// the rest (study/ranking_text.cpp).
TEST(Plan, TheLightingStudyMixesKindsOfLightOnItsLightingAxisOnly) {
  const Study study = load_study(kSource + "/scenes/studies/lighting.json");
  const Plan plan = plan_study(study, 8.0 * (1ull << 30));
  ASSERT_EQ(plan.variants.size(), 64u);
  const StudyStatistics s = study_statistics(plan, {}, study.bump.axes);
  ASSERT_EQ(s.by_axis.size(), 2u);
  EXPECT_FALSE(s.by_axis[0].lighting) << s.by_axis[0].pointer;
  EXPECT_TRUE(s.by_axis[1].lighting) << s.by_axis[1].pointer;
  const Study quick = load_study(kSource + "/scenes/studies/quick.json");
  const StudyStatistics q =
      study_statistics(plan_study(quick, 8.0 * (1ull << 30)), {}, quick.bump.axes);
  for (const AxisStatistics& a : q.by_axis) EXPECT_FALSE(a.lighting) << a.pointer;
}

// Consistent normal interpolation is evaluator-only: a study that puts it on
// an axis leaves exactly those variants out of POV-Ray and Blender, each with
// the renderer's reason, and renders the smooth ones everywhere.
TEST(Plan, ConsistentNormalVariantsAreLeftOutOfTheExternalRenderers) {
  Study study = load_study(kSource + "/scenes/studies/consistent.json");
  ASSERT_TRUE(study.lowpoly);
  study.lowpoly->renderers = {RendererKind::kEvaluator, RendererKind::kPovray,
                              RendererKind::kBlender};
  const Plan plan = plan_study(study, 8.0 * (1ull << 30));
  std::size_t consistent = 0;
  for (const Variant& v : plan.variants) {
    const bool is_consistent = v.axis_values.at(1) == "consistent";
    consistent += is_consistent;
    for (RendererKind r : {RendererKind::kPovray, RendererKind::kBlender}) {
      // ball-on-sphere has a prop, which neither renders at all.
      if (std::any_of(plan.skipped.begin(), plan.skipped.end(), [&](const SkippedRenderer& s) {
            return s.scene == v.scene && s.renderer == r && s.variant.empty();
          }))
        continue;
      const bool skipped =
          std::any_of(plan.skipped.begin(), plan.skipped.end(), [&](const SkippedRenderer& s) {
            return s.variant == v.id && s.renderer == r &&
                   s.why == renderer_info(r).consistent_normals_why_not;
          });
      EXPECT_EQ(skipped, is_consistent) << v.id << " " << to_string(r);
      const bool has_jobs = std::any_of(v.jobs.begin(), v.jobs.end(),
                                        [&](std::size_t j) { return plan.jobs[j].renderer == r; });
      EXPECT_EQ(has_jobs, !is_consistent) << v.id << " " << to_string(r);
    }
  }
  EXPECT_EQ(consistent, plan.variants.size() / 2);
}

// POV-Ray's bump on a mesh shape is not the evaluator's (the renderer
// table's mesh_bump_why_not), Cycles' is: a study with both plans POV-Ray's
// truth of each mesh variant and none of its methods, and says so once,
// not as failed renders; Cycles gets the truth and `none`, but not
// chiang2019, whose reference normal in Cycles is Ni where the scene's is
// Ng (mesh_method_why_not), which it also says once.
class PlanMesh : public TempDirTest {};
TEST_F(PlanMesh, PovrayRendersAMeshTruthAndNoBumpCyclesItsOwnMethods) {
  std::ofstream(path("study.json")) << json{
      {"version", 1},
      {"name", "mesh"},
      {"scenes", {kSource + "/scenes/meshes/wuson.json"}},
      {"axes", {{{"pointer", "/height/amplitude"}, {"label", "A"}, {"values", {0.005, 0.01}}}}},
      {"methods", {"none", "chiang2019"}},
      {"renderers", {"evaluator", "povray", "blender"}}};
  const Plan plan = plan_study(load_study(path("study.json")), 8.0 * (1ull << 30));
  ASSERT_EQ(plan.variants.size(), 2u);
  for (const Variant& v : plan.variants)
    for (const auto& [r, methods_expected] :
         {std::pair{RendererKind::kPovray, 0u}, std::pair{RendererKind::kBlender, 1u}}) {
      std::size_t truths = 0, methods = 0;
      for (std::size_t j : v.jobs)
        if (plan.jobs[j].renderer == r) (plan.jobs[j].truth ? truths : methods) += 1;
      EXPECT_EQ(truths, 1u) << v.id << " " << to_string(r);
      EXPECT_EQ(methods, methods_expected) << v.id << " " << to_string(r);
    }
  ASSERT_EQ(plan.skipped.size(), 2u);
  EXPECT_EQ(plan.skipped[0].renderer, RendererKind::kPovray);
  EXPECT_NE(plan.skipped[0].why.find("mesh shape"), std::string::npos) << plan.skipped[0].why;
  EXPECT_EQ(plan.skipped[1].renderer, RendererKind::kBlender);
  EXPECT_NE(plan.skipped[1].why.find("`chiang2019`"), std::string::npos) << plan.skipped[1].why;
  for (const SkippedRenderer& s : plan.skipped) EXPECT_TRUE(s.variant.empty());
}

class PlanMemory : public TempDirTest {};

// 100,002 renders (4,762 amplitudes x the 20 methods and the truth of the
// shipped studies, evaluator only) plan and get their cache keys in under
// 1 KiB per render of peak memory. Before the plan kept recipes it held a
// document and a reading per job: about 10 KiB per render here.
TEST_F(PlanMemory, AHundredThousandRendersPlanInUnderAKibibyteEach) {
  json amplitudes = json::array();
  for (int i = 0; i < 4762; ++i) amplitudes.push_back(0.001 + 0.0001 * i);
  json methods =
      json::array({"none", "chiang2019", "chiang2019-sine", "estevez2019", "estevez2019-reciprocal",
                   "deshmukh2020", "cycles34", "cycles45", "cycles50", "mitsuba3", "mitsuba3-flip",
                   "iray2017", "unity-hdrp", "falcor", "schuessler2017", "schuessler2017-shadowing",
                   "schuessler2017-walk", "microshadow-chan2018", "microshadow-brinck2016"});
  methods.push_back({{"id", "shading-offset"}, {"parameters", {{"s", 0.3}}}});
  const json study = {
      {"version", 1},
      {"name", "large"},
      {"scenes", {kSource + "/scenes/cylinder-grating.json"}},
      {"axes", {{{"pointer", "/height/amplitude"}, {"label", "A"}, {"values", amplitudes}}}},
      {"methods", methods},
      {"renderers", {"evaluator"}}};
  std::ofstream(path("large.json")) << study.dump();
  const Study loaded = load_study(path("large.json"));
  const double before_mib = peak_rss_mib();
  Plan plan = plan_study(loaded, 8.0 * (1ull << 30));
  assign_keys(plan, {});
  const double grown_kib = (peak_rss_mib() - before_mib) * 1024.0;
  ASSERT_EQ(plan.jobs.size(), 100002u);
  RecordProperty("kib_per_render", fmt::format("{:.3f}", grown_kib / double(plan.jobs.size())));
  EXPECT_LT(grown_kib / double(plan.jobs.size()), 1.0)
      << grown_kib / 1024.0 << " MiB for " << plan.jobs.size() << " renders";
}

}  // namespace
}  // namespace penumbra
