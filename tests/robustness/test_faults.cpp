// Broken renderers and a damaged cache, through a real study: each fault must
// end as a reported failed render (never cached, never a number in the
// report), leave no process running, and a resume must redo exactly what is
// missing. Fake renderers are shell scripts named by PENUMBRA_BLENDER.
#include <gtest/gtest.h>

#include "cli_test.h"
#include "fake_blender.h"
#include "study/study_options.h"
#include "temp_dir_test.h"

#include <signal.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "image/exr_file.h"
#include "image/image_io.h"
#include "study/cache.h"
#include "study/study.h"
#include "util/files.h"
#include "util/strict_json.h"

namespace penumbra {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kSource = PENUMBRA_SOURCE_DIR;

std::string read_text(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Processes (not zombies) whose command line mentions `needle`.
std::vector<int> processes_mentioning(const std::string& needle) {
  std::vector<int> found;
  for (const auto& e : fs::directory_iterator("/proc")) {
    const std::string name = e.path().filename().string();
    if (name.empty() || !std::all_of(name.begin(), name.end(), ::isdigit)) continue;
    const int pid = std::stoi(name);
    if (pid == ::getpid()) continue;
    std::string cmdline = read_text(e.path().string() + "/cmdline");
    std::replace(cmdline.begin(), cmdline.end(), '\0', ' ');
    const std::string stat = read_text(e.path().string() + "/stat");
    const auto close = stat.rfind(')');
    const bool zombie =
        close != std::string::npos && close + 2 < stat.size() && stat[close + 2] == 'Z';
    if (!zombie && cmdline.find(needle) != std::string::npos) found.push_back(pid);
  }
  return found;
}

bool alive(int pid) {
  const std::string stat = read_text("/proc/" + std::to_string(pid) + "/stat");
  if (stat.empty()) return false;
  const auto close = stat.rfind(')');
  return !(close != std::string::npos && close + 2 < stat.size() && stat[close + 2] == 'Z');
}

// Polls for up to `seconds` (processes take a moment to die); no timing is asserted.
template <typename F>
bool eventually(F condition, double seconds = 10.0) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < end) {
    if (condition()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return condition();
}

class Faults : public TempDirTest {
 protected:
  void TearDown() override {
    ::unsetenv("PENUMBRA_BLENDER");
    TempDirTest::TearDown();
  }
  // A fake Blender: answers --version, else runs `body` per render in its
  // work folder (Penumbra expects render.exr there).
  std::string fake_blender(const std::string& body, const std::string& version_body = "") {
    const std::string p = path("fake-blender");
    std::ofstream(p) << fake_blender_text(body, version_body);
    ::chmod(p.c_str(), 0755);
    ::setenv("PENUMBRA_BLENDER", p.c_str(), 1);
    return p;
  }
  // An R G B A image of the study's size, filled with `value`.
  std::string rgba_exr(const std::string& name, float value) const {
    Image image;
    image.width = image.height = 16;
    image.channels = {"R", "G", "B", "A"};
    image.pixels.assign(16 * 16 * 4, value);
    for (std::size_t i = 3; i < image.pixels.size(); i += 4) image.pixels[i] = 1.0f;
    write_exr_file(image, path(name), {});  // write_exr refuses the NaN case
    return path(name);
  }
  // 1 variant: evaluator displacement + bump, Blender displacement + bump.
  ::penumbra::Study study() const {
    const json doc = {{"version", 1},
                      {"name", "faults"},
                      {"scenes", {kSource + "/scenes/calibration/sphere.json"}},
                      {"set",
                       {{"/camera/width", 16},
                        {"/camera/height", 16},
                        {"/camera/spp", 2},
                        {"/displacement/edge_length", 0.05}}},
                      {"methods", {"none"}},
                      {"renderers", {"evaluator", "blender"}},
                      // No convergence check renders: these tests count renders.
                      {"ground_truth", {{"max_edge_refinements", 0}}}};
    std::ofstream(path("study.json")) << doc.dump(2);
    return load_study(path("study.json"));
  }
  StudyOptions options(const std::string& out) const {
    StudyOptions o;
    o.output_dir = path(out);
    o.parallelism = resolve_parallelism(1);
    o.figures = false;
    o.timeout_s = 2.0;
    return o;
  }
  std::size_t cached_images(const std::string& out) const {
    std::size_t n = 0;
    for (const auto& e : fs::directory_iterator(path(out) + "/cache"))
      n += e.path().extension() == ".exr" ? 1 : 0;
    return n;
  }
  // The fault's outcome: both Blender renders failed with `expected` in the
  // message, neither was cached, the report lists them, nothing runs on.
  void expect_blender_failed(const StudyRunStats& stats, const std::string& out,
                             const std::string& expected) {
    EXPECT_EQ(stats.failed, 2u);
    EXPECT_EQ(stats.rendered, 2u);  // the evaluator's
    ASSERT_EQ(stats.failures.size(), 2u);
    for (const std::string& f : stats.failures) EXPECT_NE(f.find(expected), std::string::npos) << f;
    EXPECT_EQ(cached_images(out), 2u);
    const json report = read_json_file(path(out) + "/report.json");
    EXPECT_EQ(report.at("failures").size(), 2u);
    for (const json& c : report.at("comparisons")) EXPECT_NE(c.at("renderer"), "blender");
    EXPECT_TRUE(eventually([&] { return processes_mentioning(dir_.string()).empty(); }))
        << "processes left running";
  }
};

TEST_F(Faults, ExitOneIsAFailedRenderNotCached) {
  fake_blender("echo 'boom' >&2; exit 1");
  expect_blender_failed(run_study(study(), options("out")), "out", "exited with status 1");
}

TEST_F(Faults, SegfaultIsAFailedRender) {
  fake_blender("kill -SEGV $$");
  expect_blender_failed(run_study(study(), options("out")), "out", "killed by signal 11");
}

TEST_F(Faults, GarbageImageIsAFailedRender) {
  fake_blender("printf 'this is no OpenEXR file' > render.exr");
  expect_blender_failed(run_study(study(), options("out")), "out", "cannot be read");
}

TEST_F(Faults, NanImageIsNeverCachedAndARerunRendersItAgain) {
  const std::string nan = rgba_exr("nan.exr", std::numeric_limits<float>::quiet_NaN());
  fake_blender(fake_blender_answer(nan));
  expect_blender_failed(run_study(study(), options("out")), "out", "NaN or Inf");
  // The renderer is fixed: exactly the two failed renders are done again.
  fake_blender(fake_blender_answer(rgba_exr("good.exr", 0.25f)));
  const StudyRunStats again = run_study(study(), options("out"));
  EXPECT_TRUE(again.complete());
  EXPECT_EQ(again.cached, 2u);
  EXPECT_EQ(again.rendered, 2u);
}

TEST_F(Faults, HangingRendererAndItsChildAreKilledAtTheTimeout) {
  fake_blender("echo $$ > '" + path("fake.pid") + "'; sleep 300 & echo $! > '" + path("child.pid") +
               "'; sleep 300");
  expect_blender_failed(run_study(study(), options("out")), "out", "timed out");
  const int fake = std::stoi(read_text(path("fake.pid")));
  const int child = std::stoi(read_text(path("child.pid")));
  EXPECT_TRUE(eventually([&] { return !alive(fake) && !alive(child); }));
}

TEST_F(Faults, HangingVersionProbeObeysTheTimeout) {
  fake_blender("exit 1", "echo $$ > '" + path("probe.pid") + "'; sleep 300");
  const StudyRunStats stats = run_study(study(), options("out"));
  EXPECT_EQ(stats.failed, 2u);
  for (const std::string& f : stats.failures)
    EXPECT_NE(f.find("--version` timed out after 2 s"), std::string::npos) << f;
  EXPECT_TRUE(eventually([&] { return !alive(std::stoi(read_text(path("probe.pid")))); }));
  EXPECT_TRUE(eventually([&] { return processes_mentioning(dir_.string()).empty(); }));
}

TEST_F(Faults, DamagedOrSwappedCacheEntriesAreRenderedAgainWithAWarning) {
  ::penumbra::Study s = study();
  s.bump.renderers = {RendererKind::kEvaluator};
  s.bump.methods.push_back({"chiang2019", json(), "chiang2019"});
  s.bump.methods.push_back({"estevez2019", json(), "estevez2019"});
  const StudyRunStats clean = run_study(s, options("out"));
  ASSERT_TRUE(clean.complete());
  ASSERT_EQ(clean.rendered, 4u);
  const std::string report = report_without_provenance(path("out/report.json"));
  std::vector<fs::path> entries;
  for (const auto& e : fs::directory_iterator(path("out/cache")))
    if (e.path().extension() == ".exr") entries.push_back(e.path());
  std::sort(entries.begin(), entries.end());
  ASSERT_EQ(entries.size(), 4u);
  // Truncated, emptied, and two valid entries swapped.
  std::string bytes = read_text(entries[0].string());
  std::ofstream(entries[0], std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  std::ofstream(entries[1], std::ios::binary | std::ios::trunc);
  fs::rename(entries[2], path("swap.tmp"));
  fs::rename(entries[3], entries[2]);
  fs::rename(path("swap.tmp"), entries[3]);
  const StudyRunStats repaired = run_study(s, options("out"));
  EXPECT_TRUE(repaired.complete());
  EXPECT_EQ(repaired.rendered, 4u);
  EXPECT_EQ(repaired.cached, 0u);
  EXPECT_EQ(repaired.warnings.size(), 4u);
  EXPECT_EQ(report_without_provenance(path("out/report.json")), report)
      << "the repaired report differs";
  // A flipped bit in the pixel data of a valid entry. Not every bit of a
  // deflate stream changes what it decodes to (a match's distance within a
  // run of zeros copies the same zeros), so take the last one before the
  // final 40 bytes that does: the pixels read back differ, or do not read.
  const std::string valid = read_text(entries[1].string());
  const std::vector<float> valid_pixels = read_image(entries[1].string()).pixels;
  bool damaged = false;
  for (std::size_t back = 40; back < valid.size() / 2 && !damaged; ++back) {
    bytes = valid;
    bytes[bytes.size() - back] = static_cast<char>(bytes[bytes.size() - back] ^ 0x10);
    std::ofstream(entries[1], std::ios::binary | std::ios::trunc) << bytes;
    try {
      damaged = read_image(entries[1].string()).pixels != valid_pixels;
    } catch (const std::exception&) {
      damaged = true;
    }
  }
  ASSERT_TRUE(damaged);
  const StudyRunStats flipped = run_study(s, options("out"));
  EXPECT_EQ(flipped.rendered, 1u);
  EXPECT_EQ(flipped.warnings.size(), 1u);
  EXPECT_EQ(report_without_provenance(path("out/report.json")), report);
}

// Starts `penumbra run` on DIR/study.json as a real process, output in DIR/out.
pid_t start_run(const std::string& dir) {
  const std::string log = dir + "/run.log", study = dir + "/study.json", out = dir + "/out";
  const pid_t penumbra = ::fork();
  if (penumbra == 0) {
    if (!std::freopen(log.c_str(), "w", stdout) || !std::freopen(log.c_str(), "a", stderr))
      ::_exit(126);
    ::execl(PENUMBRA_BINARY, PENUMBRA_BINARY, "run", study.c_str(), "-o", out.c_str(), "--jobs",
            "1", "--no-figures", "--timeout", "600", static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return penumbra;
}

class SignalledRun : public Faults {
 protected:
  // Runs the study with a Blender that hangs (and starts a child that hangs),
  // sends `signal` to penumbra once the child runs; returns the wait status.
  int run_and_signal(int signal) {
    fs::remove_all(path("out"));
    fs::remove(path("child.pid"));
    fake_blender("echo $$ > '" + path("fake.pid") + "'; sleep 300 & echo $! > '" +
                 path("child.pid") + "'; sleep 300");
    study();  // writes study.json
    const pid_t penumbra = start_run(dir_.string());
    EXPECT_GT(penumbra, 0);
    EXPECT_TRUE(eventually([&] { return fs::exists(path("child.pid")); }, 120.0))
        << read_text(path("run.log"));
    ::kill(penumbra, signal);
    int status = 0;
    ::waitpid(penumbra, &status, 0);
    return status;
  }
  bool renderer_and_child_dead() const {
    const int fake = std::stoi(read_text(path("fake.pid")));
    const int child = std::stoi(read_text(path("child.pid")));
    return eventually([&] { return !alive(fake) && !alive(child); });
  }
};

TEST_F(SignalledRun, CtrlCOrSigtermEndsTheRendererRemovesItsWorkAndExits128PlusSignal) {
  for (const int signal : {SIGINT, SIGTERM}) {
    const int status = run_and_signal(signal);
    ASSERT_TRUE(WIFEXITED(status)) << read_text(path("run.log"));
    EXPECT_EQ(WEXITSTATUS(status), 128 + signal) << read_text(path("run.log"));
    EXPECT_NE(read_text(path("run.log")).find("run the same command again to resume"),
              std::string::npos);
    EXPECT_TRUE(renderer_and_child_dead());
    EXPECT_FALSE(fs::exists(path("out/report.json")));
    for (const auto& e : fs::directory_iterator(path("out/cache")))
      EXPECT_NE(e.path().filename().string().rfind(".penumbra", 0), 0u)
          << "left behind: " << e.path();
  }
}

TEST_F(SignalledRun, KilledRunLeavesNoRendererAndResumesWhereItStopped) {
  run_and_signal(SIGKILL);
  EXPECT_TRUE(renderer_and_child_dead()) << "the renderer outlived a kill -9 of penumbra";
  bool work_left = false;
  for (const auto& e : fs::directory_iterator(path("out/cache")))
    work_left |= e.path().filename().string().rfind(".penumbra-work.", 0) == 0;
  EXPECT_TRUE(work_left);  // kill -9 leaves it; the next run removes it

  fake_blender(fake_blender_answer(rgba_exr("good.exr", 0.25f)));
  const StudyRunStats resumed = run_study(study(), options("out"));
  EXPECT_TRUE(resumed.complete());
  EXPECT_EQ(resumed.cached, 2u);    // the evaluator's, finished before the kill
  EXPECT_EQ(resumed.rendered, 2u);  // Blender's, nothing twice
  EXPECT_GE(resumed.stale_removed, 1u);
  for (const auto& e : fs::directory_iterator(path("out/cache")))
    EXPECT_NE(e.path().filename().string().rfind(".penumbra", 0), 0u) << e.path();
  const StudyRunStats clean = run_study(study(), options("clean"));
  EXPECT_EQ(report_without_provenance(path("clean/report.json")),
            report_without_provenance(path("out/report.json")));
}

// A disk that fills during a study: every write is checked before its
// rename, so what stays is whole (each cache entry verifies, each preview
// decodes), no temporary is left, and no render whose entry could not be
// written is reported as rendered.
class FullDisk : public Faults {
 protected:
  void SetUp() override {
    Faults::SetUp();
    if (::geteuid() != 0) GTEST_SKIP() << "mounting a small tmpfs needs root";
    fs::create_directories(path("disk"));
    if (::mount("tmpfs", path("disk").c_str(), "tmpfs", 0, "size=2m") != 0)
      GTEST_SKIP() << "cannot mount a tmpfs here: " << std::strerror(errno);
    mounted_ = true;
  }
  void TearDown() override {
    if (mounted_) ::umount2(path("disk").c_str(), MNT_DETACH);
    Faults::TearDown();
  }
  // Fills what is left of the disk.
  std::string fill() const {
    return "dd if=/dev/zero of='" + path("disk/filler") + "' bs=4k >/dev/null 2>&1";
  }
  bool mounted_ = false;
};

TEST_F(FullDisk, AStudyOnAFullDiskLeavesOnlyWholeFilesAndCountsTheRenderFailed) {
  // The disk fills once the first render is cached: one worker, so the
  // next render starts after this line and meets a full disk.
  fake_blender(fake_blender_answer(rgba_exr("good.exr", 0.25f)));
  StudyOptions o = options("disk/out");
  std::vector<std::string> log;
  o.log = [&](const std::string& line) {
    log.push_back(line);
    if (line.find("] rendered ") == std::string::npos || fs::exists(path("disk/filler"))) return;
    [[maybe_unused]] const int dd = std::system(fill().c_str());  // "no space left": the point
  };
  try {
    run_study(study(), o);
  } catch (const std::exception& e) {  // the report cannot be written either
    log.push_back(e.what());
  }
  ASSERT_TRUE(fs::exists(path("disk/filler"))) << "nothing was rendered";
  std::size_t rendered = 0, failed = 0;
  for (const std::string& line : log) {
    rendered += line.find("] rendered ") != std::string::npos;
    failed += line.find("] FAILED ") != std::string::npos;
  }
  EXPECT_GE(failed, 1u);
  const RenderCache cache(path("disk/out/cache"));
  std::size_t entries = 0;
  for (const auto& e : fs::recursive_directory_iterator(path("disk/out"))) {
    const std::string name = e.path().filename().string();
    EXPECT_EQ(name.find("penumbra-tmp"), std::string::npos) << "left behind: " << e.path();
    if (!e.is_regular_file()) continue;
    if (e.path().extension() == ".exr" && e.path().parent_path() == cache.folder()) {
      std::string why;
      EXPECT_TRUE(cache.lookup(e.path().stem().string(), &why)) << e.path() << ": " << why;
      ++entries;
    } else if (e.path().extension() == ".exr" || e.path().extension() == ".png") {
      EXPECT_NO_THROW(read_image(e.path().string())) << e.path();
    }
  }
  EXPECT_EQ(rendered, entries) << "a render reported as rendered without its cache entry";
}

TEST_F(FullDisk, EveryWriteHelperFailsWithoutLeavingAFile) {
  [[maybe_unused]] const int dd = std::system(fill().c_str());  // "no space left": the point
  struct statvfs disk {};
  ASSERT_EQ(::statvfs(path("disk").c_str(), &disk), 0);
  ASSERT_EQ(disk.f_bavail, 0u) << "the disk is not full";
  Image image;
  image.width = image.height = 64;
  image.channels = {"R", "G", "B"};
  image.pixels.assign(64 * 64 * 3, 0.5f);
  EXPECT_THROW(write_exr(image, path("disk/a.exr")), OutputError);
  EXPECT_THROW(write_preview_png(image, path("disk/a.png")), OutputError);
  EXPECT_THROW(write_text_file(path("disk/a.txt"), std::string(1 << 16, 'x')), OutputError);
  // The figures: matplotlib through the harness's own writer.
  const std::string script = "import sys; sys.path.insert(0, '" + kSource + "/harness')\n" +
                             "import penumbra_plot as p\n" + "fig = p.plt.figure()\n" +
                             "fig.gca().plot(range(10000))\n" + "p.save(fig, '" + path("disk") +
                             "', 'figure')\n";
  std::ofstream(path("draw.py")) << script;
  EXPECT_NE(std::system(("/usr/bin/python3 '" + path("draw.py") + "' 2>/dev/null").c_str()), 0);
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(path("disk")))
    if (e.path().filename() != "filler") left.push_back(e.path().filename().string());
  EXPECT_TRUE(left.empty()) << "left on the full disk: " << left.front();
}

// Starts `penumbra ARGS...` as a real process, its output in DIR/LOG.
pid_t start_penumbra(const std::string& log, std::vector<std::string> args) {
  const pid_t penumbra = ::fork();
  if (penumbra == 0) {
    if (!std::freopen(log.c_str(), "w", stdout) || !std::freopen(log.c_str(), "a", stderr))
      ::_exit(126);
    std::vector<char*> argv{const_cast<char*>(PENUMBRA_BINARY)};
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(PENUMBRA_BINARY, argv.data());
    ::_exit(127);
  }
  return penumbra;
}

// Ctrl-C or SIGTERM while the figures are drawn leaves what an interrupt
// while rendering leaves: the cache, no report, exit 128 + the signal.
TEST_F(SignalledRun, AnInterruptWhileDrawingExits128PlusSignalAndLeavesNoReport) {
  fake_blender(fake_blender_answer(rgba_exr("good.exr", 0.25f)));
  const std::string python = path("fake-python");
  std::ofstream(python) << "#!/bin/sh\necho $$ > '" << path("python.pid") << "'\nsleep 300\n";
  ::chmod(python.c_str(), 0755);
  study();
  for (const int signal : {SIGINT, SIGTERM}) {
    fs::remove(path("python.pid"));
    ::setenv("PENUMBRA_PYTHON", python.c_str(), 1);
    const pid_t penumbra = start_penumbra(
        path("run.log"), {"run", path("study.json"), "-o", path("out"), "--jobs", "1"});
    ::unsetenv("PENUMBRA_PYTHON");
    ASSERT_TRUE(eventually([&] { return fs::exists(path("python.pid")); }, 120.0))
        << read_text(path("run.log"));
    ::kill(penumbra, signal);
    int status = 0;
    ::waitpid(penumbra, &status, 0);
    ASSERT_TRUE(WIFEXITED(status)) << read_text(path("run.log"));
    EXPECT_EQ(WEXITSTATUS(status), 128 + signal) << read_text(path("run.log"));
    for (const char* name : {"report.json", "metrics.csv", "metrics-long.csv", "report.html"})
      EXPECT_FALSE(fs::exists(path("out") + "/" + name)) << name;
    const int fake = std::stoi(read_text(path("python.pid")));
    EXPECT_TRUE(eventually([&] { return !alive(fake); })) << "the drawing outlived the run";
  }
}

// A second run into a folder that a first is writing stops at once, saying
// which process holds it, and renders nothing.
TEST_F(SignalledRun, ASecondRunIntoABusyFolderExitsTwoNamingTheFirst) {
  fake_blender("echo $$ > '" + path("fake.pid") + "'; sleep 300 & echo $! > '" + path("child.pid") +
               "'; sleep 300");
  study();
  const pid_t first = start_run(dir_.string());
  ASSERT_TRUE(eventually([&] { return fs::exists(path("child.pid")); }, 120.0))
      << read_text(path("run.log"));
  const std::size_t entries = cached_images("out");
  const auto start = std::chrono::steady_clock::now();
  // A short time-out: a second run that does render (the fault) ends soon.
  const CliResult second = run_penumbra({"run", path("study.json"), "-o", path("out"), "--jobs",
                                         "1", "--no-figures", "--timeout", "3"});
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(cached_images("out"), entries) << "the second run rendered";
  ::kill(first, SIGTERM);
  int status = 0;
  ::waitpid(first, &status, 0);
  EXPECT_EQ(second.code, 2) << second.err;
  EXPECT_NE(second.err.find("pid " + std::to_string(first)), std::string::npos) << second.err;
  EXPECT_LT(seconds, 30.0) << "the second run waited for the first";
}

// `penumbra report` bounds what it takes from report.json: a huge label is
// bad input, named, before any drawing starts.
TEST_F(Faults, AReportWithAHugeLabelIsBadInputNamingItsPointer) {
  StudyOptions o = options("out");
  o.figures = false;
  fake_blender(fake_blender_answer(rgba_exr("good.exr", 0.25f)));
  ASSERT_TRUE(run_study(study(), o).complete());
  json report = read_json_file(path("out/report.json"));
  report["variants"][0]["label"] = std::string(200 * 1024, 'L');
  std::ofstream(path("out/report.json")) << report.dump(1);
  const auto start = std::chrono::steady_clock::now();
  const CliResult r = run_penumbra({"report", path("out")});
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find(path("out/report.json") + ": /variants/0/label"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("65536"), std::string::npos) << r.err;
  EXPECT_LT(seconds, 10.0);
  EXPECT_FALSE(fs::exists(path("out/report.html")));
}

}  // namespace
}  // namespace penumbra
