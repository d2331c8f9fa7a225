// The executors behind study/executor.h: which one the options choose, and
// what the local one records of a round (the Slurm one's rounds are
// tests/study/test_slurm_chains.cpp and tests/slurm/).
#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "study/executor.h"
#include "study/study_file.h"
#include "study_options.h"
#include "temp_dir_test.h"
#include "util/files.h"

namespace penumbra {
namespace {

using nlohmann::json;
const std::string kSource = PENUMBRA_SOURCE_DIR;

class Executors : public TempDirTest {};

TEST_F(Executors, TheOptionsChooseOneAndOnlySlurmSubmitsAndSharesItsVersionProbes) {
  const StudyOptions local = test_study_options(path("out"));
  EXPECT_FALSE(make_executor(local)->submits());
  EXPECT_EQ(make_executor(local)->probe_cache(path("out")), "");
  StudyOptions slurm = local;
  slurm.slurm = SlurmOptions{};
  EXPECT_TRUE(make_executor(slurm)->submits());
  EXPECT_EQ(make_executor(slurm)->probe_cache("/s"), "/s/slurm/versions." + host_tag() + ".json");
}

// A round of two evaluator renders, one of them failing: the other is
// rendered into the cache and counted, the failure recorded with its error.
TEST_F(Executors, TheLocalOneRendersARoundIntoTheCacheAndRecordsEachOutcome) {
  const json j = {{"version", 1},
                  {"scenes", {kSource + "/scenes/calibration/sphere.json"}},
                  {"set", {{"/camera/width", 8}, {"/camera/height", 8}, {"/camera/spp", 1}}},
                  {"methods", {"none"}},
                  {"renderers", {"evaluator"}}};
  std::ofstream(path("s.json")) << j.dump();
  const Study study = load_study(path("s.json"));
  Plan plan = plan_study(study, kDefaultMaxMemoryBytes);
  Renderers renderers = probe_renderers({RendererKind::kEvaluator}, 60.0);
  renderers.unavailable[RendererKind::kPovray] = "not installed here";
  assign_keys(plan, renderers.identities);
  std::vector<Job> jobs{plan.jobs.at(0), plan.jobs.at(0)};
  jobs[1].key = std::string(32, '0');
  jobs[1].renderer = RendererKind::kPovray;
  const RenderCache cache(path("cache"));
  std::filesystem::create_directories(path("cache"));
  const std::vector<std::size_t> todo{0, 1}, groups;
  Renders r(jobs.size());
  StudyRunStats stats;
  const StudyOptions options = test_study_options(path("out"));
  make_executor(options)->render({jobs, todo, groups, 0, cache, renderers}, r, stats);
  EXPECT_TRUE(r.images.done[0]);
  EXPECT_TRUE(cache.contains(jobs[0].key));
  EXPECT_EQ(r.images.images[0].width, 8);
  EXPECT_FALSE(r.images.done[1]);
  EXPECT_TRUE(r.attempted[1]);
  EXPECT_EQ(r.errors[1], "not installed here");
  EXPECT_EQ(stats.rendered, 1u);
  EXPECT_EQ(stats.failed, 1u);
  ASSERT_EQ(stats.failures.size(), 1u);
  EXPECT_EQ(stats.failures[0], jobs[1].label + ": not installed here");
}

}  // namespace
}  // namespace penumbra
