// The Slurm executor's submissions without a cluster: `sbatch` and `squeue`
// are stand-ins on PATH that record what they were asked, and the test runs
// each submitted array task itself (run_slurm_task), as a node would. What
// it checks is the chain of submissions: the ground-truth convergence goes
// to array tasks as chains, a report job either submits something or writes
// the report, never neither, and a chain whose check failed ends in the
// report as that failure. (tests/slurm/ runs the same against a real
// one-node cluster.)
#include <gtest/gtest.h>

#include "study/study_options.h"
#include "temp_dir_test.h"

#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "study/slurm.h"
#include "study/study.h"
#include "study/study_file.h"
#include "study_options.h"

namespace penumbra {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;
const std::string kSource = PENUMBRA_SOURCE_DIR;

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class SlurmChains : public TempDirTest {
 protected:
  void SetUp() override {
    TempDirTest::SetUp();
    fs::create_directories(dir_ / "bin");
    // sbatch prints a new job id per call; squeue knows of no job (every
    // array has ended when the test looks).
    std::ofstream(dir_ / "bin" / "sbatch")
        << "#!/bin/sh\nn=$(cat '" << path("ids") << "' 2>/dev/null || echo 0)\nn=$((n+1))\n"
        << "echo $n > '" << path("ids") << "'\necho \"$@\" >> '" << path("sbatch.log")
        << "'\necho $n\n";
    std::ofstream(dir_ / "bin" / "squeue") << "#!/bin/sh\nexit 0\n";
    fs::permissions(dir_ / "bin" / "sbatch", fs::perms::owner_all);
    fs::permissions(dir_ / "bin" / "squeue", fs::perms::owner_all);
    old_path_ = std::getenv("PATH") ? std::getenv("PATH") : "";
    ::setenv("PATH", (path("bin") + ":" + old_path_).c_str(), 1);
  }
  void TearDown() override {
    ::setenv("PATH", old_path_.c_str(), 1);
    TempDirTest::TearDown();
  }

  // Two variants of the sphere, evaluator and POV-Ray, whose truths take two
  // rounds of checks at this tolerance (edge and samples refined once, then
  // the budget ends).
  ::penumbra::Study study() const {
    const json j = {
        {"version", 1},
        {"name", "chains"},
        {"scenes", {kSource + "/scenes/calibration/sphere.json"}},
        {"set",
         {{"/camera/width", 24},
          {"/camera/height", 24},
          {"/camera/spp", 4},
          {"/displacement/edge_length", 0.04}}},
        {"axes", {{{"pointer", "/height/amplitude"}, {"values", {0.01, 0.02}}}}},
        {"methods", {"none", "chiang2019"}},
        {"renderers", {"evaluator", "povray"}},
        {"ground_truth",
         {{"tolerance", 1e-9}, {"max_edge_refinements", 2}, {"max_spp_refinements", 2}}}};
    std::ofstream(path("chains.json")) << j.dump(2);
    return load_study(path("chains.json"));
  }

  StudyOptions slurm_options(const std::string& folder, const std::string& chain = "") const {
    StudyOptions o = test_study_options(path(folder));
    SlurmOptions s;
    s.continue_argv = {"/bin/true"};
    s.chain = chain;
    o.slurm = s;
    return o;
  }

  // The batch files of `folder`, oldest first.
  std::vector<fs::path> batch_files(const std::string& folder) const {
    std::vector<fs::path> out;
    for (const auto& e : fs::directory_iterator(path(folder + "/slurm")))
      if (e.path().filename().string().rfind("batch-", 0) == 0) out.push_back(e.path());
    std::sort(out.begin(), out.end());
    return out;
  }

  // Runs every task of `batch` but those `skip` names, as the nodes would.
  void run_tasks(const fs::path& batch, const std::vector<int>& skip = {}) const {
    const json b = json::parse(read_text(batch));
    for (int t = 0; t < int(b["tasks"].size()); ++t)
      if (std::find(skip.begin(), skip.end(), t) == skip.end())
        run_slurm_task(batch.string(), t, 2, nullptr);
  }

  std::string old_path_;
};

TEST_F(SlurmChains, OneSubmissionConvergesEveryTruthAndGivesTheLocalReport) {
  const ::penumbra::Study s = study();
  StudyOptions local = test_study_options(path("local"));
  std::vector<std::string> lines;
  local.log = [&](const std::string& line) { lines.push_back(line); };
  ASSERT_TRUE(run_study(s, local).complete());
  const auto rounds = std::count_if(lines.begin(), lines.end(), [](const std::string& l) {
    return l.rfind("ground truth: checking convergence", 0) == 0;
  });
  ASSERT_GE(rounds, 2) << "the study must need more than one round to show anything";

  const StudyRunStats first = run_study(s, slurm_options("slurm"));
  ASSERT_TRUE(first.slurm);
  EXPECT_EQ(first.slurm->chains, 2u) << "one chain per variant";
  EXPECT_GT(first.not_started, 0u);
  EXPECT_FALSE(fs::exists(path("slurm/report.json")));
  ASSERT_EQ(batch_files("slurm").size(), 1u);
  run_tasks(batch_files("slurm")[0]);

  // The report job: everything is in the cache, nothing is submitted.
  const StudyRunStats report = run_study(s, slurm_options("slurm", first.slurm->chain));
  EXPECT_EQ(batch_files("slurm").size(), 1u) << "a second submission";
  EXPECT_TRUE(report.complete());
  EXPECT_EQ(report.not_started, 0u);
  EXPECT_EQ(report_without_provenance(path("slurm/report.json")),
            report_without_provenance(path("local/report.json")));
  EXPECT_EQ(read_text(path("slurm/metrics.csv")), read_text(path("local/metrics.csv")));
}

TEST_F(SlurmChains, AFailedCheckEndsItsChainUnconvergedAndEveryReportJobMovesOn) {
  const ::penumbra::Study s = study();
  const StudyRunStats first = run_study(s, slurm_options("failed"));
  ASSERT_TRUE(first.slurm);
  const fs::path batch = batch_files("failed")[0];
  const json b = json::parse(read_text(batch));
  // The first task is the first variant's chain: it "fails" at its first
  // check, leaving the record an array task leaves.
  ASSERT_TRUE(b["jobs"][0].contains("chain"));
  const std::string key = b["jobs"][0]["key"];
  std::ofstream(path("failed/cache/" + key + ".failed")) << "simulated failure of the check";
  run_tasks(batch, {0});

  // Each report job submits what is missing or writes the report.
  std::size_t submissions = 1;
  for (int round = 0; round < 4 && !fs::exists(path("failed/report.json")); ++round) {
    const StudyRunStats r = run_study(s, slurm_options("failed", first.slurm->chain));
    if (fs::exists(path("failed/report.json"))) break;
    ASSERT_EQ(batch_files("failed").size(), submissions + 1)
        << "a report job that neither submitted nor wrote the report";
    ++submissions;
    run_tasks(batch_files("failed").back());
    EXPECT_EQ(r.slurm->chains, 0u) << "the failed chain is not submitted again";
  }
  ASSERT_TRUE(fs::exists(path("failed/report.json")));
  const json report = json::parse(read_text(path("failed/report.json")));
  // Both end unconverged: one at the budget, one at the failed check.
  const json& variants = report["ground_truth"]["variants"];
  ASSERT_EQ(variants.size(), 2u);
  std::size_t failed = 0;
  for (const json& v : variants) {
    EXPECT_FALSE(v["converged"].get<bool>());
    const std::string why = v["why"];
    failed += why.find("simulated failure of the check") != std::string::npos;
    if (why.find("simulated") == std::string::npos) {
      EXPECT_NE(why.find("budget"), std::string::npos) << why;
    }
  }
  EXPECT_EQ(failed, 1u);
}

// Renders that share a mesh go to one array task unless there are more of
// them than a task takes; every render lands in exactly one task, in order,
// and no task is larger than asked.
TEST(SlurmTasks, RendersOfOneMeshShareATaskUnlessTheyOutnumberIt) {
  const std::vector<std::string> keys = {"", "a", "a", "a", "", "b", "b", "b", "b", "b", "c", "c"};
  using Ranges = std::vector<std::pair<std::size_t, std::size_t>>;
  EXPECT_EQ(slurm_task_ranges(keys, 3), (Ranges{{0, 1}, {1, 3}, {4, 1}, {5, 3}, {8, 2}, {10, 2}}));
  EXPECT_EQ(slurm_task_ranges(std::vector<std::string>(7, ""), 3), (Ranges{{0, 3}, {3, 3}, {6, 1}}))
      << "renders without a mesh fill tasks as before";
  EXPECT_TRUE(slurm_task_ranges({}, 3).empty());
  for (int per = 1; per <= 13; ++per) {
    const Ranges tasks = slurm_task_ranges(keys, per);
    std::size_t next = 0;
    std::vector<std::size_t> task_of(keys.size());
    for (std::size_t t = 0; t < tasks.size(); ++t) {
      EXPECT_EQ(tasks[t].first, next) << "per " << per;
      EXPECT_GE(tasks[t].second, 1u);
      EXPECT_LE(tasks[t].second, std::size_t(per));
      for (std::size_t k = 0; k < tasks[t].second; ++k) task_of[next + k] = t;
      next += tasks[t].second;
    }
    EXPECT_EQ(next, keys.size()) << "per " << per;
    for (const auto& [key, size] : {std::pair{"a", 3}, {"b", 5}, {"c", 2}}) {
      if (size > per) continue;
      std::set<std::size_t> used;
      for (std::size_t i = 0; i < keys.size(); ++i)
        if (keys[i] == key) used.insert(task_of[i]);
      EXPECT_EQ(used.size(), 1u) << key << ", per " << per;
    }
  }
}

}  // namespace
}  // namespace penumbra
