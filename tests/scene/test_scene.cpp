// Scene reading: every shipped scene loads; every kind of bad input is
// rejected with a message that names the file, the JSON pointer and what was
// expected.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <string>

#include "scene/scene_json.h"

namespace penumbra {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kScenes = std::string(PENUMBRA_SOURCE_DIR) + "/scenes";

json base_scene() {
  return read_json_file(kScenes + "/cylinder-grating.json");
}

// The error message of loading `document`, or "" when it loads.
std::string error_of(const json& document) {
  try {
    scene_from_json(document, "test.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Scene, EveryShippedSceneLoads) {
  int count = 0;
  for (const auto& entry : fs::directory_iterator(kScenes)) {
    if (entry.path().extension() != ".json") continue;
    EXPECT_NO_THROW(load_scene(entry.path().string())) << entry.path();
    ++count;
  }
  EXPECT_GE(count, 6);
}

TEST(Scene, ReadsTypedValues) {
  const Scene s = load_scene(kScenes + "/sphere-weave.json");
  EXPECT_EQ(s.shape.type, ShapeType::kSphere);
  EXPECT_EQ(s.height.family, HeightFamily::kWeave);
  EXPECT_EQ(s.height.function.terms.size(), 2u);
  EXPECT_NEAR(length(s.light.direction), 1.0, 1e-15);  // normalised
  EXPECT_EQ(s.camera.width, 256);
}

struct BadCase {
  const char* what;
  std::function<void(json&)> edit;
  const char* pointer;
  const char* expected;  // a fragment of the message
};

TEST(Scene, BadInputIsRejectedWithFilePointerAndExpectation) {
  const std::vector<BadCase> cases = {
      {"missing key", [](json& j) { j["camera"].erase("width"); }, "/camera/width",
       "missing required key"},
      {"unknown key", [](json& j) { j["shape"]["radiuss"] = 1; }, "/shape/radiuss", "unknown key"},
      {"unknown top-level key", [](json& j) { j["lights"] = json::array(); }, "/lights",
       "unknown key"},
      {"wrong type", [](json& j) { j["camera"]["width"] = "big"; }, "/camera/width",
       "expected an integer in [1, 16384]"},
      {"wrong type for a vector",
       [](json& j) {
         j["camera"]["position"] = {0, 0};
       },
       "/camera/position", "expected an array of 3 numbers"},
      {"non-positive radius", [](json& j) { j["shape"]["radius"] = -1; }, "/shape/radius",
       "expected a number in [1e-6, 1e6]"},
      {"zero radius", [](json& j) { j["shape"]["radius"] = 0; }, "/shape/radius", "[1e-6, 1e6]"},
      {"non-positive height", [](json& j) { j["shape"]["height"] = 0; }, "/shape/height",
       "[1e-6, 1e6]"},
      {"huge radius", [](json& j) { j["shape"]["radius"] = 1e300; }, "/shape/radius",
       "[1e-6, 1e6]"},
      {"huge camera position",
       [](json& j) {
         j["camera"]["position"] = {0, 0, 1e300};
       },
       "/camera/position", "in [-1e+06, 1e+06]"},
      {"huge irradiance", [](json& j) { j["light"]["irradiance"] = 1e300; }, "/light/irradiance",
       "in [0, 1e9]"},
      {"edge longer than the radius", [](json& j) { j["displacement"]["edge_length"] = 2.0; },
       "/displacement/edge_length", "(0, radius = 1]"},
      {"spp 0", [](json& j) { j["camera"]["spp"] = 0; }, "/camera/spp",
       "expected an integer in [1, 65536]"},
      {"resolution 0", [](json& j) { j["camera"]["height"] = 0; }, "/camera/height",
       "expected an integer in [1, 16384]"},
      {"resolution above 16384", [](json& j) { j["camera"]["width"] = 16385; }, "/camera/width",
       "expected an integer in [1, 16384]"},
      {"amplitude reaching the axis", [](json& j) { j["height"]["amplitude"] = 1.0; },
       "/height/amplitude", "amplitude * max|h| < radius"},
      {"zero light direction",
       [](json& j) {
         j["light"]["direction"] = {0, 0, 0};
       },
       "/light/direction", "expected a non-zero vector"},
      {"zero grating direction",
       [](json& j) {
         j["height"]["direction"] = {0, 0, 0};
       },
       "/height/direction", "non-zero vector"},
      {"infinite number",
       [](json& j) { j["light"]["irradiance"] = std::numeric_limits<double>::infinity(); },
       "/light/irradiance", "expected a number"},
      {"unknown method", [](json& j) { j["terminator"]["method"] = "chiang"; },
       "/terminator/method", "valid: none, chiang2019, chiang2019-sine, estevez2019"},
      {"parameter out of range",
       [](json& j) {
         j["terminator"]["method"] = "shading-offset";
         j["terminator"]["parameters"] = {{"s", 2}};
       },
       "/terminator/parameters/s", "in [0, 1]"},
      {"parameter of another method",
       [](json& j) {
         j["terminator"]["parameters"] = {{"s", 0.5}};
       },
       "/terminator/parameters/s", "unknown key"},
      {"unknown representation", [](json& j) { j["representation"] = "displaced"; },
       "/representation", "\"smooth\", \"bump\", \"displacement\""},
      {"albedo above 1", [](json& j) { j["material"]["albedo"] = 1.5; }, "/material/albedo",
       "in [0, 1]"},
      {"wrong version", [](json& j) { j["version"] = 2; }, "/version", "version 1"},
      {"sphere light of radius 0",
       [](json& j) {
         j["light"] = {{"type", "sphere"}, {"position", {-3, 0, 0}}, {"radius", 0}, {"power", 1}};
       },
       "/light/radius", "in [1e-6, 1e6]"},
      {"area light with radiance and power",
       [](json& j) {
         j["light"] = {{"type", "sphere"},
                       {"position", {-3, 0, 0}},
                       {"radius", 0.5},
                       {"power", 1},
                       {"radiance", 1}};
       },
       "/light", "got both"},
      {"area light without radiance or power",
       [](json& j) {
         j["light"] = {{"type", "sphere"}, {"position", {-3, 0, 0}}, {"radius", 0.5}};
       },
       "/light", "\"radiance\" (W/(m^2 sr)) or \"power\" (W)"},
      {"quad with parallel edges",
       [](json& j) {
         j["light"] = {{"type", "quad"},
                       {"corner", {-3, 0, 0}},
                       {"edge_u", {0, 1, 0}},
                       {"edge_v", {0, -2, 0}},
                       {"radiance", 1}};
       },
       "/light/edge_v", "not parallel to edge_u"},
      {"quad with a zero edge",
       [](json& j) {
         j["light"] = {{"type", "quad"},
                       {"corner", {-3, 0, 0}},
                       {"edge_u", {0, 0, 0}},
                       {"edge_v", {0, 1, 0}},
                       {"radiance", 1}};
       },
       "/light/edge_u", "expected a length >= 1e-06"},
      {"negative power",
       [](json& j) {
         j["light"] = {
             {"type", "sphere"}, {"position", {-3, 0, 0}}, {"radius", 0.5}, {"power", -1}};
       },
       "/light/power", "in [0, 1e9] (W)"},
      {"unknown sampling",
       [](json& j) {
         j["light"] = {{"type", "sphere"},
                       {"position", {-3, 0, 0}},
                       {"radius", 0.5},
                       {"power", 1},
                       {"sampling", "bsdf"}};
       },
       "/light/sampling", "expected one of \"light\", \"mis\""},
      {"sampling of a delta light", [](json& j) { j["light"]["sampling"] = "mis"; },
       "/light/sampling", "unknown key"},
      {"group of one",
       [](json& j) {
         j["light"] = {{"type", "group"}, {"lights", {j["light"]}}};
       },
       "/light/lights", "expected an array of 2 to 8 lights"},
      {"nested group",
       [](json& j) {
         const json inner = {{"type", "group"}, {"lights", {j["light"], j["light"]}}};
         j["light"] = {{"type", "group"}, {"lights", {j["light"], inner}}};
       },
       "/light/lights/1/type", "groups do not nest"},
      {"bad light in a group",
       [](json& j) {
         json bad = j["light"];
         bad["irradiance"] = -1;
         j["light"] = {{"type", "group"}, {"lights", {j["light"], bad}}};
       },
       "/light/lights/1/irradiance", "in [0, 1e9]"},
      {"environment beside a quad in a group",
       [](json& j) {
         j["light"] = {{"type", "group"},
                       {"lights",
                        {{{"type", "quad"},
                          {"corner", {-3, 0, 0}},
                          {"edge_u", {0, 1, 0}},
                          {"edge_v", {0, 0, 1}},
                          {"radiance", 1}},
                         {{"type", "environment"}, {"map", "no-such-map.exr"}}}}};
       },
       "/light/lights/1/type", "an environment beside distant and point lights only"},
      {"sampling of a group",
       [](json& j) {
         j["light"] = {
             {"type", "group"}, {"lights", {j["light"], j["light"]}}, {"sampling", "mis"}};
       },
       "/light/sampling", "unknown key"},
      {"not an object", [](json& j) { j["camera"] = 3; }, "/camera", "expected an object"},
      {"too fine a tessellation",
       [](json& j) {
         j["representation"] = "displacement";
         j["displacement"]["edge_length"] = 1e-5;
       },
       "/displacement/edge_length", "million triangles"},
  };
  for (const BadCase& c : cases) {
    json document = base_scene();
    c.edit(document);
    const std::string message = error_of(document);
    EXPECT_NE(message.find(std::string("test.json: ") + c.pointer + ": "), std::string::npos)
        << c.what << ": " << message;
    EXPECT_NE(message.find(c.expected), std::string::npos) << c.what << ": " << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << c.what << ": one line";
  }
}

TEST(Scene, UnreadableAndMalformedFiles) {
  try {
    load_scene("/nonexistent/scene.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/scene.json"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos);
  }
  const fs::path bad = fs::temp_directory_path() / "penumbra-malformed.json";
  std::ofstream(bad) << "{\"version\": 1, ";
  try {
    load_scene(bad.string());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not valid JSON"), std::string::npos);
  }
  fs::remove(bad);
}

TEST(Scene, OverridesUseJsonPointers) {
  const Scene s =
      load_scene(kScenes + "/cylinder-grating.json",
                 {parse_override("/light/direction=[0,0,-1]"),
                  parse_override("/representation=smooth"), parse_override("/camera/spp=4")});
  EXPECT_EQ(s.light.direction, (Vec3{0, 0, -1}));
  EXPECT_EQ(s.representation, Representation::kSmooth);
  EXPECT_EQ(s.camera.spp, 4);
  try {
    load_scene(kScenes + "/cylinder-grating.json", {parse_override("/shape/radius=-2")});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "(after --set): /shape/radius: expected a number in [1e-6, 1e6]"),
              std::string::npos)
        << e.what();
  }
  try {
    load_scene(kScenes + "/cylinder-grating.json", {parse_override("/nope/x=1")});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nope: unknown key"), std::string::npos) << e.what();
  }
  // Objects the file leaves out are created by --set.
  json document = base_scene();
  document.erase("terminator");
  apply_overrides(document,
                  {parse_override("/terminator/parameters/s=0.25"),
                   parse_override("/terminator/method=shading-offset")},
                  "t.json");
  EXPECT_EQ(scene_from_json(document, "t.json").terminator.method.shading_offset, 0.25);
  EXPECT_THROW(parse_override("radius=1"), InputError);
}

}  // namespace
}  // namespace penumbra

namespace penumbra {
namespace {

// The fitted method's table: required, read strictly with the table file's
// own pointer in the message, and found beside the scene file.
TEST(Scene, FittedMethodReadsItsTableFile) {
  const fs::path dir = fs::temp_directory_path() / "penumbra-Scene-FittedMethodReadsItsTableFile";
  fs::remove_all(dir);
  fs::create_directories(dir / "sub");
  std::ofstream(dir / "sub" / "table.json")
      << R"({"grid": [{"input": "light", "min_deg": 0, "max_deg": 90, "step_deg": 45}],
             "values": [0.25, 0.75], "smoothness": 1})";
  std::ofstream(dir / "bad.json")
      << R"({"grid": [{"input": "light", "min_deg": 0, "max_deg": 90, "step_deg": 45}],
             "values": [0.25, -1]})";
  json scene = base_scene();
  scene["terminator"] = {{"method", "fitted"}};
  EXPECT_NE(error_of(scene).find("/terminator/parameters: method \"fitted\" needs"),
            std::string::npos)
      << error_of(scene);
  scene["terminator"]["parameters"] = {{"table", (dir / "bad.json").string()}};
  const std::string bad = error_of(scene);
  EXPECT_NE(bad.find("/terminator/parameters/table"), std::string::npos) << bad;
  EXPECT_NE(bad.find("/values/1"), std::string::npos) << bad;
  // Relative to the scene file, from any working directory.
  scene["terminator"]["parameters"] = {{"table", "sub/table.json"}};
  std::ofstream(dir / "scene.json") << scene.dump();
  const Scene loaded = load_scene((dir / "scene.json").string());
  ASSERT_TRUE(loaded.terminator.method.table);
  EXPECT_EQ(loaded.terminator.method.table->values, (std::vector<double>{0.25, 0.75}));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace penumbra
