// The input half of the second hostile audit: image files whose headers
// lie, non-finite results, outputs that would replace an input, NaN and Inf
// options, files that are not files, and where a relative map is looked
// for. Each case must end in exit 2 with one line naming the file (exit 1
// with one line for a broken installation), leave nothing half-written, and
// stay within bounded memory and time.
#include <gtest/gtest.h>

#include "cli_test.h"
#include "robustness/hostile_images.h"
#include "temp_dir_test.h"

#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "image/exr_file.h"
#include "image/image_io.h"
#include "util/resource_usage.h"
#include "util/strict_json.h"

namespace penumbra {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kSource = PENUMBRA_SOURCE_DIR;

// Exit 2, one printable line starting "penumbra: error: " that holds `needle`.
void expect_one_line(const CliResult& r, const std::string& needle, const std::string& what,
                     int code = 2) {
  EXPECT_EQ(r.code, code) << what << "\n" << r.err;
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << what << ": not one line:\n" << r.err;
  EXPECT_EQ(r.err.rfind("penumbra: ", 0), 0u) << what << ": " << r.err;
  EXPECT_NE(r.err.find(needle), std::string::npos) << what << ": no \"" << needle << "\" in\n"
                                                   << r.err;
  for (char c : r.err.substr(0, r.err.size() - 1))
    EXPECT_GE(static_cast<unsigned char>(c), 0x20) << what << ": a control character in " << r.err;
}

class HostileInputs : public TempDirTest {
 protected:
  std::string write_heights(const std::string& name, int w, int h,
                            const std::function<float(int, int)>& height) const {
    Image image;
    image.width = w, image.height = h, image.channels = {"Y"};
    image.pixels.resize(std::size_t(w) * h);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) image.at(x, y, 0) = height(x, y);
    write_exr_file(image, path(name), {});  // unchecked: hostile values are the point
    return path(name);
  }
  std::string rgba(const std::string& name, float value) const {
    Image image;
    image.width = image.height = 8, image.channels = {"R", "G", "B", "A"};
    image.pixels.assign(8 * 8 * 4, value);
    write_exr(image, path(name));
    return path(name);
  }
  // A small sphere whose /height is the height map `file`.
  std::string map_scene(const std::string& file, const std::string& name = "scene.json") const {
    json doc = read_json_file(kSource + "/scenes/sphere-grating.json");
    doc["camera"]["width"] = 16, doc["camera"]["height"] = 16, doc["camera"]["spp"] = 1;
    doc["height"] = {{"type", "height-map"}, {"file", file}, {"amplitude", 0.01}};
    std::ofstream(path(name)) << doc.dump();
    return path(name);
  }
  std::string lying_png(const std::string& name, std::uint32_t w, std::uint32_t h,
                        int colour = 0) const {
    write_bytes(path(name), png_bytes(w, h, 8, colour));
    return path(name);
  }
  // Runs `args` with file descriptor 2 captured: libpng writes there.
  CliResult run(const std::vector<std::string>& args, std::string* fd2 = nullptr) const {
    Fd2Capture capture;
    CliResult r = run_penumbra(args);
    const std::string printed = capture.text();
    if (fd2) *fd2 = printed;
    return r;
  }
};

// ---- 1. lying headers: refused from the header, before any pixel --------------

TEST_F(HostileInputs, LyingImageHeadersAreRefusedBeforeDecoding) {
  const std::string huge = lying_png("huge.png", 65536, 65536);
  ASSERT_LT(fs::file_size(huge), 80u);  // 65 bytes declaring 16 GiB of float
  const std::string big = lying_png("big.png", 20000, 20000, 2);  // RGB: 4.5 GiB as float
  const std::string exr =
      path("huge.exr");  // a real 8x8 OpenEXR whose data window says 65536 x 65536
  write_bytes(exr, exr_with_window(file_bytes(rgba("small.exr", 0.5f)), 0, 0, 65535, 65535));
  const std::string ref = rgba("ref.exr", 0.5f);
  const double rss_before = peak_rss_mib();
  const auto start = std::chrono::steady_clock::now();
  for (const std::string& file : {huge, big, exr}) {
    const std::string name = fs::path(file).filename().string();
    const std::vector<std::vector<std::string>> commands = {
        {"render", map_scene(file), "-o", path("out.exr"), "--quiet"},
        {"pyramid", file, "-o", path("pyr"), "--quiet"},
        {"filtering", file, "-o", path("filt"), "--quiet"},
        {"compare", file, ref, "--no-mask"},
        {"compare", ref, ref, "--mask", file}};
    for (const auto& args : commands) {
      std::string fd2;
      const CliResult r = run(args, &fd2);
      const std::string what = args[0] + " on " + name;
      expect_one_line(r, name, what);
      EXPECT_NE(r.err.find("declares"), std::string::npos) << what << ": " << r.err;
      EXPECT_EQ(fd2.find("libpng"), std::string::npos) << what << ": an extra line " << fd2;
    }
  }
  EXPECT_FALSE(fs::exists(path("out.exr")) || fs::exists(path("pyr")) || fs::exists(path("filt")));
  // Decoding any of them allocates gigabytes and takes seconds.
  EXPECT_LT(peak_rss_mib() - rss_before, 512.0);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 60.0);
}

TEST_F(HostileInputs, MaxMemoryLowersTheImageLimit) {
  // 1024^2 Y heights are 4 MiB as float: within the limit, above 1 MiB.
  const std::string map = write_heights("h.exr", 1024, 1024, [](int, int) { return 0.0f; });
  const CliResult r =
      run({"render", map_scene(map), "-o", path("out.exr"), "--quiet", "--max-memory", "0.001"});
  expect_one_line(r, "h.exr", "render --max-memory 0.001");
  EXPECT_NE(r.err.find("--max-memory"), std::string::npos) << r.err;
  EXPECT_EQ(run({"render", map_scene(map), "-o", path("out.exr"), "--quiet"}).code, 0);
}

// ---- 12. unreadable inputs are bad input, the file named ---------------------

TEST_F(HostileInputs, UnreadableImagesAreBadInputNamingTheFile) {
  const std::string ref = rgba("ref.exr", 0.5f);
  // A valid 4x4 grey PNG cut inside its pixel data.
  std::string rows;
  for (int y = 0; y < 4; ++y) rows += std::string(1, '\0') + std::string(4, '\x40');
  std::string truncated = png_bytes(4, 4, 8, 0, rows);
  truncated = truncated.substr(0, truncated.find("IDAT") + 12);
  write_bytes(path("truncated.png"), truncated);
  static const char kGif[] =
      "GIF89a\x04\x00\x04\x00\x80\x00\x00\xff\xff\xff\x00\x00\x00!\xf9\x04\x01\x00\x00\x00"
      "\x00,\x00\x00\x00\x00\x04\x00\x04\x00\x00\x02\x04\x84\x8f\xa9\x0b\x00;";
  write_bytes(path("gif.exr"), std::string(kGif, sizeof kGif - 1));
  write_bytes(path("nochannels.exr"), exr_without_channels(file_bytes(rgba("four.exr", 0.5f))));
  fs::create_symlink(path("loop-b.exr"), path("loop-a.exr"));
  fs::create_symlink(path("loop-a.exr"), path("loop-b.exr"));
  for (const char* name : {"truncated.png", "gif.exr", "nochannels.exr", "loop-a.exr"}) {
    std::string fd2;
    expect_one_line(run({"compare", path(name), ref, "--no-mask"}, &fd2), name,
                    std::string("compare ") + name);
    EXPECT_EQ(fd2.find("libpng"), std::string::npos) << name << ": an extra line " << fd2;
    expect_one_line(run({"pyramid", path(name), "-o", path("pyr"), "--quiet"}), name,
                    std::string("pyramid ") + name);
    expect_one_line(run({"render", map_scene(path(name)), "-o", path("o.exr"), "--quiet"}), name,
                    std::string("render with map ") + name);
  }
  EXPECT_FALSE(fs::exists(path("pyr")) || fs::exists(path("o.exr")));
}

// ---- 3, 9. results that cannot be finite -------------------------------------

TEST_F(HostileInputs, PyramidAndFilteringRefuseInputsWhoseResultCannotBeFinite) {
  const std::string e30 =
      write_heights("e30.exr", 8, 8, [](int x, int) { return float(x) * 1e30f; });
  const std::string e38 =
      write_heights("e38.exr", 8, 8, [](int x, int) { return float(x) * 1e38f; });
  const std::string checker =
      write_heights("checker.exr", 8, 8, [](int x, int y) { return (x + y) % 2 ? 1e18f : -1e18f; });
  const std::string ramp =
      write_heights("ramp.exr", 8, 8, [](int x, int) { return 0.1f * float(x); });
  const std::vector<std::vector<std::string>> cases = {
      {e30}, {e38}, {checker}, {ramp, "--texel-size", "1e-300"}, {ramp, "--height-scale", "1e300"}};
  for (const auto& c : cases) {
    for (const char* command : {"pyramid", "filtering"}) {
      std::vector<std::string> args{command, c[0], "-o", path("out"), "--quiet"};
      args.insert(args.end(), c.begin() + 1, c.end());
      const std::string what = std::string(command) + " " + fs::path(c[0]).filename().string() +
                               (c.size() > 1 ? " " + c[1] + " " + c[2] : "");
      expect_one_line(run(args), fs::path(c[0]).filename().string(), what);
      EXPECT_FALSE(fs::exists(path("out"))) << what << ": wrote " << path("out");
    }
  }
  // The same map at ordinary scales is measured: the refusal is the scale's.
  EXPECT_EQ(run({"pyramid", ramp, "-o", path("out"), "--quiet"}).code, 0);
}

TEST_F(HostileInputs, BakeRefusesAnExtentThatOverflowsAndNoImageIsWrittenNonFinite) {
  const std::string scene = kSource + "/scenes/sphere-grating.json";
  const CliResult r =
      run({"bake", scene, "-o", path("map.exr"), "--size", "8", "--extent", "1e308"});
  expect_one_line(r, "sphere-grating.json", "bake --extent 1e308");
  EXPECT_NE(r.err.find("--extent"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("map.exr")));
  // The shared check every image writer runs, whatever the command.
  Image image;
  image.width = image.height = 2, image.channels = {"Y"};
  image.pixels = {0.0f, std::numeric_limits<float>::infinity(), 1.0f, 2.0f};
  EXPECT_THROW(write_exr(image, path("inf.exr")), OutputError);
  image.channels = {"R", "G", "B"}, image.pixels.assign(12, std::nanf(""));
  EXPECT_THROW(write_preview_png(image, path("nan.png")), OutputError);
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(dir_)) left.push_back(e.path().filename().string());
  EXPECT_TRUE(left.empty()) << "left " << left.front();
}

// ---- 8. an output that is an input ------------------------------------------

TEST_F(HostileInputs, RenderRefusesToWriteOverItsOwnMap) {
  const std::string map =
      write_heights("h.exr", 16, 16, [](int x, int) { return 0.01f * float(x); });
  const std::string before = file_bytes(map);
  const std::string scene = map_scene("h.exr");  // relative: from the scene's folder
  for (const std::string& output : {map, path("sub/../h.exr")}) {
    fs::create_directories(path("sub"));
    expect_one_line(run({"render", scene, "-o", output, "--quiet"}), "h.exr", "-o " + output);
  }
  expect_one_line(run({"render", scene, "-o", path("o.exr"), "--preview", map, "--quiet"}), "h.exr",
                  "--preview over the map");
  EXPECT_EQ(file_bytes(map), before) << "the map was replaced";
  EXPECT_EQ(run({"render", scene, "-o", path("o.exr"), "--quiet"}).code, 0);
}

// ---- 10. a filtering study with a bad map -----------------------------------

TEST_F(HostileInputs, FilteringStudyWithANaNMapNamesStudyAndPointerAndWritesNothing) {
  write_heights("nan.exr", 8, 8,
                [](int x, int y) { return x == 2 && y == 3 ? std::nanf("") : 0.0f; });
  const json study = {{"version", 1},
                      {"name", "nan-map"},
                      {"filtering",
                       {{"maps", {{{"name", "nan"}, {"file", "nan.exr"}}}},
                        {"runs", {{{"name", "box"}}}},
                        {"max_level", 2},
                        {"footprints", 2}}}};
  std::ofstream(path("study.json")) << study.dump();
  const CliResult r = run({"run", path("study.json"), "-o", path("out"), "--quiet"});
  expect_one_line(r, "study.json", "filtering study with a NaN map");
  EXPECT_NE(r.err.find("/filtering/maps/0/file"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("nan.exr"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("out"))) << "a refused study left " << path("out");
}

// ---- 13. NaN and Inf options -------------------------------------------------

TEST_F(HostileInputs, EveryFloatingPointOptionRefusesNanAndInf) {
  const std::string ref = rgba("ref.exr", 0.5f);
  const std::string map = write_heights("h.exr", 8, 8, [](int x, int) { return 0.1f * float(x); });
  const std::string scene = kSource + "/scenes/sphere-grating.json";
  const std::vector<std::vector<std::string>> cases = {
      {"pyramid", map, "-o", path("p"), "--texel-size", "nan"},
      {"pyramid", map, "-o", path("p"), "--height-scale", "inf"},
      {"filtering", map, "-o", path("f"), "--texel-size", "nan"},
      {"compare", ref, ref, "--scale", "nan"},
      {"compare", ref, ref, "--max-profile-rmse", "nan"},
      {"compare", ref, ref, "--threshold=nan"},
      {"compare", ref, ref, "--threshold=-inf"},
      {"bake", scene, "-o", path("b.exr"), "--extent", "nan"},
      {"bake", scene, "-o", path("b.exr"), "--extent", "1e400"},
      {"render", scene, "-o", path("r.exr"), "--max-memory", "nan"},
      {"render", scene, "-o", path("r.exr"), "--timeout", "inf"},
      {"run", kSource + "/scenes/studies/smoke.json", "-o", path("s"), "--max-memory", "NaN"}};
  for (const auto& args : cases) {
    std::string what;
    for (const std::string& a : args) what += a + " ";
    expect_one_line(run(args), "finite", what);
  }
  for (const char* dir : {"p", "f", "b.exr", "r.exr", "s"}) EXPECT_FALSE(fs::exists(path(dir)));
  EXPECT_EQ(run({"pyramid", map, "-o", path("p"), "--texel-size", "0.125", "-q"}).code, 0);
}

// ---- 14. messages ------------------------------------------------------------

TEST_F(HostileInputs, NonFilesAreCalledWhatTheyAre) {
  fs::create_directories(path("folder.exr"));
  ASSERT_EQ(::mkfifo(path("fifo.exr").c_str(), 0644), 0);
  const std::string ref = rgba("ref.exr", 0.5f);
  const std::vector<std::pair<std::string, std::string>> inputs = {
      {path("folder.exr"), "folder"},
      {path("fifo.exr"), "FIFO"},
      {"/dev/zero", "character device"},
      {"/dev/null", "character device"}};
  for (const auto& [file, kind] : inputs) {
    for (const auto& args : std::vector<std::vector<std::string>>{
             {"pyramid", file, "-o", path("p"), "-q"},
             {"compare", file, ref, "--no-mask"},
             {"compare", ref, ref, "--mask", file},
             {"render", map_scene(file), "-o", path("o.exr"), "-q"}}) {
      const CliResult r = run(args);
      expect_one_line(r, kind, args[0] + " " + file);
      EXPECT_EQ(r.err.find("no such file"), std::string::npos) << r.err;
    }
  }
  // As a scene (a FIFO would block the reader, /dev/zero never end), also
  // one a study names.
  for (const auto& [file, kind] : inputs) {
    expect_one_line(run({"render", file, "-o", path("o.exr"), "-q"}), kind, "scene " + file);
    const json study = {{"version", 1},
                        {"name", "s"},
                        {"scenes", {file}},
                        {"methods", {"none"}},
                        {"renderers", {"evaluator"}}};
    std::ofstream(path("study.json")) << study.dump();
    expect_one_line(run({"run", path("study.json"), "-o", path("out"), "--dry-run"}), kind,
                    "study scene " + file);
  }
}

TEST_F(HostileInputs, CompareEscapesControlCharactersInFileNames) {
  const std::string ref = rgba("ref.exr", 0.5f);
  const std::string odd = path("a\n\x1b[2Jb.exr");
  const CliResult missing = run({"compare", odd, ref, "--no-mask"});
  expect_one_line(missing, "\\x1b[2J", "a missing file with a newline and ESC");
  fs::copy_file(ref, odd);
  const CliResult r = run({"compare", odd, ref, "--no-mask"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out.find('\x1b'), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("a\\n\\x1b[2Jb.exr"), std::string::npos) << r.out;
}

// A tmpfs of `kib` KiB at `dir`; false (the test skips) where mounting is not allowed.
bool mount_small_tmpfs(const std::string& dir, int kib) {
  fs::create_directories(dir);
  const std::string options = "size=" + std::to_string(kib) + "k";
  return ::mount("tmpfs", dir.c_str(), "tmpfs", 0, options.c_str()) == 0;
}

TEST_F(HostileInputs, FullDiskPreCheckReadsInUnitsAndLeavesNoFolders) {
  const std::string disk = path("disk");
  if (!mount_small_tmpfs(disk, 64))
    GTEST_SKIP() << "mounting a 64 KiB tmpfs needs root (CAP_SYS_ADMIN); not run";
  const json study = {{"version", 1},
                      {"name", "full"},
                      {"scenes", {kSource + "/scenes/calibration/cylinder.json"}},
                      {"set", {{"/camera/width", 48}, {"/camera/height", 48}, {"/camera/spp", 1}}},
                      {"methods", {"none"}},
                      {"renderers", {"evaluator"}}};
  std::ofstream(path("study.json")) << study.dump();
  const std::string out = disk + "/study";
  const CliResult r = run({"run", path("study.json"), "-o", out, "--quiet", "--no-figures"});
  const CliResult render =
      run({"render", kSource + "/scenes/sphere-grating.json", "-o", disk + "/big.exr", "--quiet"});
  const bool study_left = fs::exists(out);
  ::umount(disk.c_str());
  expect_one_line(r, "free", "study on a 64 KiB disk");
  EXPECT_EQ(r.err.find("0.00 GiB"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("KiB free"), std::string::npos) << r.err;
  EXPECT_FALSE(study_left) << "the refused study left its folders";
  expect_one_line(render, "MiB", "render of 256x256 on a 64 KiB disk");
}

// ---- 15. a relative map set on the command line or by a study --------------

TEST_F(HostileInputs, RelativeMapFromSetOrAxisIsFoundBesideTheScene) {
  fs::create_directories(path("scenes/maps"));
  write_heights("scenes/maps/h.exr", 16, 16, [](int x, int) { return 0.01f * float(x); });
  const std::string scene = map_scene("maps/h.exr", "scenes/scene.json");
  ASSERT_NE(fs::current_path(), fs::path(path("scenes")));
  const CliResult set =
      run({"render", scene, "-o", path("o.exr"), "-q", "--set", "/height/file=maps/h.exr"});
  EXPECT_EQ(set.code, 0) << set.err;
  const CliResult missing =
      run({"render", scene, "-o", path("o.exr"), "-q", "--set", "/height/file=maps/none.exr"});
  expect_one_line(missing, fs::path(path("scenes/maps/none.exr")).lexically_normal().string(),
                  "a missing relative map shows where it was looked for");
  json study = {{"version", 1},
                {"name", "axis"},
                {"scenes", {"scenes/scene.json"}},
                {"axes", {{{"pointer", "/height/file"}, {"values", {"maps/h.exr"}}}}},
                {"methods", {"none"}},
                {"renderers", {"evaluator"}}};
  std::ofstream(path("study.json")) << study.dump();
  const CliResult axis = run({"run", path("study.json"), "-o", path("out"), "--dry-run"});
  EXPECT_EQ(axis.code, 0) << axis.err;
}

// ---- 18. a binary without its runtime module ---------------------------------

TEST_F(HostileInputs, BinaryWithoutItsImageModuleSaysSoAtStartUp) {
  const std::string copy = path("bin/penumbra");
  fs::create_directories(path("bin"));
  fs::copy_file(PENUMBRA_BINARY, copy);
  const std::string command = "cd " + dir_.string() + " && " + copy + " run " + kSource +
                              "/scenes/studies/smoke.json -o " + path("out") +
                              " --quiet > stdout.txt 2> stderr.txt";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status)) << "killed by a signal";
  EXPECT_EQ(WEXITSTATUS(status), 1);
  CliResult r{WEXITSTATUS(status), file_bytes(path("stdout.txt")), file_bytes(path("stderr.txt"))};
  expect_one_line(r, "libpenumbra_oiio.so", "a copied binary", 1);
  EXPECT_NE(r.err.find(path("bin")), std::string::npos) << "where it looked: " << r.err;
  EXPECT_FALSE(fs::exists(path("out")));
}

}  // namespace
}  // namespace penumbra
