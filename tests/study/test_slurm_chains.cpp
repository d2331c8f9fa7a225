// The Slurm executor's submissions without a cluster: `sbatch` and `squeue`
// are stand-ins on PATH that record what they were asked, and the test runs
// each submitted array task itself (run_slurm_task), as a node would. What
// it checks is the chain of submissions: the ground-truth convergence goes
// to array tasks as chains, a report job either submits something or writes
// the report, never neither, and a chain whose check failed ends in the
// report as that failure. (tests/slurm/ runs the same against a real
// one-node cluster.)
#include <gtest/gtest.h>

#include "cli_test.h"
#include "study/study_options.h"
#include "temp_dir_test.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>
#include <string>
#include <thread>
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

// sbatch that accepts the array but not what follows: whatever was submitted
// is either cancelled or recorded, never shown as a phantom "array job ?",
// and a rerun never submits a render that is still queued.
class SlurmHalfSubmission : public TempDirTest {
 protected:
  void SetUp() override {
    TempDirTest::SetUp();
    fs::create_directories(dir_ / "bin");
    old_path_ = std::getenv("PATH") ? std::getenv("PATH") : "";
    ::setenv("PATH", (path("bin") + ":" + old_path_).c_str(), 1);
  }
  void TearDown() override {
    ::setenv("PATH", old_path_.c_str(), 1);
    TempDirTest::TearDown();
  }
  // A stand-in for a Slurm client: logs its arguments to NAME.log, then runs `body`.
  void tool(const std::string& name, const std::string& body) const {
    const fs::path file = dir_ / "bin" / name;
    std::ofstream(file) << "#!/bin/sh\necho \"$@\" >> '" << path(name + ".log") << "'\n"
                        << body << "\n";
    fs::permissions(file, fs::perms::owner_all);
  }
  // sbatch's answer to its Nth call (1-based): `first` to the array, `then` after.
  void sbatch(const std::string& first, const std::string& then) const {
    tool("sbatch", "n=$(wc -l < '" + path("sbatch.log") + "')\nif [ \"$n\" -le 1 ]; then " + first +
                       "; else " + then + "; fi");
  }
  ::penumbra::Study study(int size = 16, int spp = 1,
                          const std::vector<std::string>& methods = {"none", "chiang2019"}) const {
    const json j = {
        {"version", 1},
        {"name", "half"},
        {"scenes", {kSource + "/scenes/calibration/sphere.json"}},
        {"set", {{"/camera/width", size}, {"/camera/height", size}, {"/camera/spp", spp}}},
        {"axes", {{{"pointer", "/height/amplitude"}, {"values", {0.01, 0.02}}}}},
        {"methods", methods},
        {"renderers", {"evaluator"}}};
    std::ofstream(path("half.json")) << j.dump(2);
    return load_study(path("half.json"));
  }
  StudyOptions options() const {
    StudyOptions o = test_study_options(path("out"));
    SlurmOptions s;
    s.continue_argv = {"/bin/true"};
    o.slurm = s;
    return o;
  }
  std::size_t lines(const std::string& log) const {
    std::istringstream in(read_text(path(log)));
    std::size_t n = 0;
    for (std::string line; std::getline(in, line);) ++n;
    return n;
  }
  std::string old_path_;
};

TEST_F(SlurmHalfSubmission, ARefusedReportJobCancelsTheArrayAndLeavesNoPhantom) {
  sbatch("echo 4242", "echo 'sbatch: error: QOSMaxSubmitJobPerUserLimit' >&2; exit 1");
  tool("scancel", "exit 0");
  tool("squeue", "exit 0");
  const ::penumbra::Study s = study();
  try {
    run_study(s, options());
    FAIL() << "a refused report job must fail the run";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("4242"), std::string::npos) << e.what();
  }
  EXPECT_EQ(read_text(path("scancel.log")), "4242\n") << "the array must be cancelled";
  EXPECT_TRUE(slurm_status(path("out")).batches.empty()) << "nothing stays submitted";
}

TEST_F(SlurmHalfSubmission, AnArrayThatCannotBeCancelledIsRecordedAndNotSubmittedAgain) {
  sbatch("echo 4242", "exit 1");
  tool("scancel", "exit 1");
  tool("squeue", "echo 4242");  // the array still runs
  const ::penumbra::Study s = study();
  EXPECT_THROW(run_study(s, options()), std::exception);
  const SlurmStatus status = slurm_status(path("out"));
  ASSERT_EQ(status.batches.size(), 1u);
  EXPECT_EQ(status.batches[0].array_job, "4242");
  const std::size_t calls = lines("sbatch.log");

  const StudyRunStats rerun = run_study(s, options());
  ASSERT_TRUE(rerun.slurm);
  EXPECT_EQ(rerun.slurm->submitted, 0u) << "renders of the queued array submitted again";
  EXPECT_GT(rerun.slurm->still_queued, 0u);
  EXPECT_EQ(lines("sbatch.log"), calls);
}

TEST_F(SlurmHalfSubmission, AFailedArraySubmissionLeavesNoPhantom) {
  tool("scancel", "exit 0");
  tool("squeue", "exit 0");
  const ::penumbra::Study s = study();
  for (const std::string answer : {"exit 1", "echo 'no job id here'", "missing"}) {
    SCOPED_TRACE(answer);
    if (answer == "missing")
      fs::remove(dir_ / "bin" / "sbatch");
    else
      sbatch(answer, answer);
    EXPECT_THROW(run_study(s, options()), std::exception);
    EXPECT_TRUE(slurm_status(path("out")).batches.empty());
  }
  // Once sbatch works, the renders are submitted exactly once.
  fs::remove(path("sbatch.log"));
  tool("sbatch", "echo 77");
  const StudyRunStats ok = run_study(s, options());
  ASSERT_TRUE(ok.slurm);
  EXPECT_GT(ok.slurm->submitted, 0u);
  ASSERT_EQ(slurm_status(path("out")).batches.size(), 1u);
  EXPECT_EQ(slurm_status(path("out")).batches[0].array_job, "77");
  EXPECT_EQ(slurm_status(path("out")).batches[0].report_job, "77");
}

// run-batch takes nothing from its batch file on trust: a key is the digest
// of its scene (recomputed before anything is cached), never a path.
class RunBatch : public SlurmHalfSubmission {
 protected:
  // A batch file from a submission, `edit` applied to its first render.
  std::string batch(const std::function<void(json&)>& edit) {
    tool("sbatch", "echo 77");
    tool("squeue", "exit 0");
    const StudyRunStats stats = run_study(study(), options());
    EXPECT_TRUE(stats.slurm && stats.slurm->submitted > 0);
    const std::string file = slurm_status(path("out")).batches.at(0).file;
    json b = json::parse(read_text(file));
    edit(b["jobs"][0]);
    std::ofstream(file) << b.dump(1);
    return file;
  }
  std::size_t cached() const {
    std::size_t n = 0;
    for (const auto& e : fs::recursive_directory_iterator(dir_))
      n += e.path().extension() == ".exr" ? 1 : 0;
    return n;
  }
};

TEST_F(RunBatch, AnUntouchedBatchFileRenders) {
  const std::string file = batch([](json&) {});
  const CliResult r = run_penumbra({"run-batch", file, "--task", "0"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_GT(cached(), 0u);
}

TEST_F(RunBatch, AKeyThatIsNotADigestIsBadInputAndWritesNothing) {
  for (const std::string key : {"../../PWNED", "zz", "0123456789abcdef0123456789ABCDEF"}) {
    SCOPED_TRACE(key);
    fs::remove_all(path("out"));
    const std::string file = batch([&](json& job) { job["key"] = key; });
    const CliResult r = run_penumbra({"run-batch", file, "--task", "0"});
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find(file + ": /jobs/0/key"), std::string::npos) << r.err;
    EXPECT_EQ(cached(), 0u);
    EXPECT_FALSE(fs::exists(path("PWNED.exr")));
    EXPECT_FALSE(fs::exists(path("PWNED.failed")));
  }
}

TEST_F(RunBatch, AnEditedSceneIsNotCachedUnderThePlannedKey) {
  std::string planned;
  const std::string file = batch([&](json& job) {
    planned = job["key"];
    job["scene"]["camera"]["spp"] = 3;
  });
  const CliResult r = run_penumbra({"run-batch", file, "--task", "0"});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find(file + ": /jobs/0/key"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(planned), std::string::npos) << r.err;
  EXPECT_EQ(cached(), 0u);
}

// SIGTERM (scancel, a node's shutdown) stops a task as it stops `render`:
// soon, with 128 + 15, and with nothing cached from the render it cut short.
TEST_F(RunBatch, SigtermStopsTheRenderAndCachesNothing) {
  tool("sbatch", "echo 77");
  tool("squeue", "exit 0");
  run_study(study(1024, 256, {"none"}), options());
  const std::string file = slurm_status(path("out")).batches.at(0).file;
  const pid_t child = ::fork();
  if (child == 0) {
    const int out = ::open(path("task.log").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(out, 1);
    ::dup2(out, 2);
    ::execl(PENUMBRA_BINARY, PENUMBRA_BINARY, "run-batch", file.c_str(), "--task", "0",
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  // Well into its render: a second of CPU time (its signal handlers are set
  // before it parses the batch file).
  const auto cpu_ticks = [&] {
    std::istringstream stat(read_text("/proc/" + std::to_string(child) + "/stat"));
    std::string field;
    long ticks = 0;
    for (int i = 1; i <= 15 && stat >> field; ++i)
      if (i >= 14) ticks += std::atol(field.c_str());
    return ticks;
  };
  const auto limit = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (cpu_ticks() < ::sysconf(_SC_CLK_TCK) && std::chrono::steady_clock::now() < limit)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ASSERT_EQ(cached(), 0u) << "the render must still be running when the signal comes";
  ::kill(child, SIGTERM);
  const auto sent = std::chrono::steady_clock::now();
  int status = 0;
  while (::waitpid(child, &status, WNOHANG) == 0 &&
         std::chrono::steady_clock::now() - sent < std::chrono::seconds(10))
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  if (::waitpid(child, &status, WNOHANG) == 0) {
    ::kill(child, SIGKILL);
    ::waitpid(child, &status, 0);
    FAIL() << "still running 10 s after SIGTERM: " << read_text(path("task.log"));
  }
  ASSERT_TRUE(WIFEXITED(status)) << read_text(path("task.log"));
  EXPECT_EQ(WEXITSTATUS(status), 143) << read_text(path("task.log"));
  EXPECT_EQ(cached(), 0u);
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
