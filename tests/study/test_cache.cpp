// The render cache: what its key covers, that damaged entries are refused,
// and that changing the code behind one renderer's pixels re-renders exactly
// that renderer's entries.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdlib>
#include <fstream>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "fake_blender.h"
#include "image/image_io.h"
#include "renderers/code_digest.h"
#include "renderers/renderers.h"
#include "study/cache.h"
#include "study/study.h"
#include "temp_dir_test.h"
#include "util/strict_json.h"

namespace penumbra {
namespace {

using nlohmann::json;
const std::string kSource = PENUMBRA_SOURCE_DIR;

TEST(RenderKey, ChangesWithEveryInputAndOnlyWithThem) {
  const json scene = {{"camera", {{"width", 16}}}, {"representation", "bump"}};
  const RendererIdentity id{"Blender 3.4.1", "digest-a"};
  const std::string key = render_key(scene, RendererKind::kBlender, id);
  EXPECT_EQ(key.size(), 32u);
  EXPECT_EQ(key.find_first_not_of("0123456789abcdef"), std::string::npos);
  EXPECT_EQ(render_key(scene, RendererKind::kBlender, id), key);  // deterministic
  json other = scene;
  other["camera"]["width"] = 17;
  std::set<std::string> keys{
      key, render_key(other, RendererKind::kBlender, id),
      render_key(scene, RendererKind::kPovray, id),
      render_key(scene, RendererKind::kBlender, {"Blender 3.4.2", "digest-a"}),
      render_key(scene, RendererKind::kBlender, {"Blender 3.4.1", "digest-b"})};
  EXPECT_EQ(keys.size(), 5u) << "every input must change the key";
}

TEST(CodeDigest, EachRendererHasItsOwnAndBlenderCoversItsScript) {
  const CodeDigests& d = build_code_digests();
  EXPECT_EQ(std::string(d.evaluator).size(), 16u);
  EXPECT_NE(std::string(d.evaluator), external_code_digest("povray"));
  EXPECT_NE(std::string(external_code_digest("povray")), external_code_digest("blender"));
  RenderSettings s;
  const std::string evaluator = pixel_code_digest(RendererKind::kEvaluator, s);
  const std::string povray = pixel_code_digest(RendererKind::kPovray, s);
  EXPECT_NE(evaluator, povray);
  EXPECT_EQ(povray.rfind(evaluator, 0), 0u) << "every renderer's entry holds evaluator channels";

  const std::string copy = ::testing::TempDir() + "/penumbra-digest-script.py";
  std::ofstream(copy) << "print('one')\n";
  s.blender_script = copy;
  const std::string first = pixel_code_digest(RendererKind::kBlender, s);
  EXPECT_EQ(pixel_code_digest(RendererKind::kBlender, s), first);
  std::ofstream(copy) << "print('two')\n";
  EXPECT_NE(pixel_code_digest(RendererKind::kBlender, s), first);
  EXPECT_EQ(pixel_code_digest(RendererKind::kEvaluator, s), evaluator);
  std::remove(copy.c_str());
}

class Cache : public TempDirTest {
 protected:
  Image image(float value) const {
    Image im;
    im.width = im.height = 4;
    im.channels = {"R", "G", "B", "A"};
    im.pixels.assign(4 * 4 * 4, value);
    return im;
  }
};

TEST_F(Cache, StoredEntriesVerifyAndDamagedOnesAreRefusedWithAReason) {
  const RenderCache cache(path(""));
  const std::string key(32, 'a'), other(32, 'b');
  EXPECT_FALSE(cache.contains(key));
  cache.store(key, image(0.5f), {{"penumbra:method", "none"}});
  ASSERT_TRUE(cache.contains(key));
  std::string reason;
  const std::optional<Image> back = cache.lookup(key, &reason);
  ASSERT_TRUE(back) << reason;
  EXPECT_EQ(back->pixels, image(0.5f).pixels);
  EXPECT_EQ(RenderCache::relative_exr(key), "cache/" + key + ".exr");
  // An entry copied under another key is not that key's render.
  std::filesystem::copy_file(cache.exr_path(key), cache.exr_path(other));
  EXPECT_FALSE(cache.lookup(other, &reason));
  EXPECT_NE(reason.find("carries key"), std::string::npos) << reason;
  // Pixels that changed after the checksum was written.
  write_exr(image(0.25f), cache.exr_path(key),
            {{"penumbra:key", key}, {"penumbra:checksum", image_checksum(image(0.5f))}});
  EXPECT_FALSE(cache.lookup(key, &reason));
  EXPECT_NE(reason.find("checksum"), std::string::npos) << reason;
  cache.remove(key);
  EXPECT_FALSE(cache.contains(key));
}

// A study with the evaluator and a fake Blender (it copies a fixed image);
// the Blender script is a copy that the test edits, as a developer would.
class CacheInvalidation : public TempDirTest {
 protected:
  void SetUp() override {
    TempDirTest::SetUp();
    Image im;
    im.width = im.height = 16;
    im.channels = {"R", "G", "B", "A"};
    im.pixels.assign(16 * 16 * 4, 0.25f);
    write_exr(im, path("blender.exr"));
    const std::string fake = path("fake-blender");
    std::ofstream(fake) << fake_blender_text(fake_blender_answer(path("blender.exr")));
    ::chmod(fake.c_str(), 0755);
    std::filesystem::copy_file(kSource + "/harness/blender_render.py", path("script.py"));
    ::setenv("PENUMBRA_BLENDER", fake.c_str(), 1);
    ::setenv("PENUMBRA_BLENDER_SCRIPT", path("script.py").c_str(), 1);
    const json doc = {{"version", 1},
                      {"scenes", {kSource + "/scenes/calibration/sphere.json"}},
                      {"set",
                       {{"/camera/width", 16},
                        {"/camera/height", 16},
                        {"/camera/spp", 2},
                        {"/displacement/edge_length", 0.05}}},
                      {"methods", {"none", "chiang2019"}},
                      {"renderers", {"evaluator", "blender"}},
                      // No convergence check renders: the test counts renders.
                      {"ground_truth", {{"max_edge_refinements", 0}}}};
    std::ofstream(path("study.json")) << doc.dump(2);
  }
  void TearDown() override {
    ::unsetenv("PENUMBRA_BLENDER");
    ::unsetenv("PENUMBRA_BLENDER_SCRIPT");
    TempDirTest::TearDown();
  }
  StudyRunStats run() const {
    StudyOptions o;
    o.output_dir = path("out");
    o.figures = false;
    return run_study(load_study(path("study.json")), o);
  }
};

TEST_F(CacheInvalidation, EditingTheBlenderScriptRerendersOnlyBlenderEntries) {
  // Evaluator: displacement, none, chiang2019; Blender: displacement, none, chiang2019.
  const StudyRunStats first = run();
  ASSERT_TRUE(first.complete()) << (first.failures.empty() ? "" : first.failures[0]);
  EXPECT_EQ(first.rendered, 6u);
  const StudyRunStats again = run();
  EXPECT_EQ(again.rendered, 0u);
  EXPECT_EQ(again.cached, 6u);
  std::ofstream(path("script.py"), std::ios::app) << "\n# an edit\n";
  const StudyRunStats edited = run();
  EXPECT_EQ(edited.rendered, 3u) << "the three Blender renders, and only those";
  EXPECT_EQ(edited.cached, 3u);
  const json report = read_json_file(path("out/report.json"));
  for (const json& v : report.at("variants"))
    for (const json& r : v.at("renders")) {
      const std::string exr = path("out/" + r.at("exr").get<std::string>());
      EXPECT_TRUE(std::filesystem::exists(exr)) << exr;
    }
}

}  // namespace
}  // namespace penumbra
