// The strict reader that scene and study files share (util/json_reader.h):
// what it refuses, and the file and JSON pointer its errors name.
#include <gtest/gtest.h>

#include <string>

#include <nlohmann/json.hpp>

#include "util/json_reader.h"
#include "util/strict_json.h"

namespace penumbra {
namespace {

using nlohmann::json;

// The InputError `read` throws, as "POINTER|MESSAGE".
template <typename F>
std::string refusal(F read) {
  try {
    read();
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "f.json");
    const std::string what = e.what();
    const std::string prefix = "f.json: " + e.pointer() + (e.pointer().empty() ? "" : ": ");
    EXPECT_EQ(what.rfind(prefix, 0), 0u) << what;
    return e.pointer() + "|" + what.substr(prefix.size());
  }
  ADD_FAILURE() << "accepted";
  return "";
}

TEST(JsonReader, FinishRefusesTheKeysNobodyReadListingThoseRead) {
  const json j = {{"b", 1}, {"a", 2}, {"typo", 3}};
  Reader r(j, "/x", "f.json");
  EXPECT_EQ(r.integer("b", 0, 9), 1);
  EXPECT_FALSE(r.has("c"));
  EXPECT_EQ(r.integer("a", 0, 9), 2);
  EXPECT_EQ(refusal([&] { r.finish(); }), "/x/typo|unknown key (expected one of: a, b, c)");
}

TEST(JsonReader, ExpectRefusesAnUnknownKeyFirstListingTheKeysInTheirOrder) {
  // The unknown key is reported before the missing one.
  const json j = {{"zeta", 1}};
  Reader r(j, "/s", "f.json");
  EXPECT_EQ(refusal([&] {
              r.expect({"version", "name"});
            }),
            "/s/zeta|unknown key (expected one of: version, name)");
  const json k = {{"name", "n"}};
  Reader s(k, "/s", "f.json");
  s.expect({"version", "name"});
  EXPECT_EQ(refusal([&] { s.at("version"); }), "/s/version|missing required key");
}

TEST(JsonReader, ExpectedKeysThatWereNotReadAreUnused) {
  const json j = {{"version", 1}, {"name", "n"}};
  Reader r(j, "", "f.json");
  r.expect({"version", "name"});
  r.integer("version", 1, 1);
  EXPECT_EQ(refusal([&] { r.finish(); }), "/name|unused key (read here: version)");
}

TEST(JsonReader, PointersEscapeKeysAndIndexArrays) {
  const json j = {{"a/b~c", 1}, {"list", {json::object(), 5}}};
  Reader r(j, "/top", "f.json");
  EXPECT_EQ(refusal([&] { r.expect({"list"}); }),
            "/top/a~1b~0c|unknown key (expected one of: list)");
  EXPECT_EQ(r.item_pointer("list", 1), "/top/list/1");
  Reader first = r.item("list", 0);
  EXPECT_EQ(first.pointer(), "/top/list/0");
  EXPECT_EQ(refusal([&] { r.item("list", 1, "expected a map"); }), "/top/list/1|expected a map");
  EXPECT_EQ(refusal([&] { r.fail_item("list", 0, "no"); }), "/top/list/0|no");
}

TEST(JsonReader, NotAnObjectSaysWhatWasFoundOrTheCallersWords) {
  EXPECT_EQ(refusal([] { Reader(json(3), "/p", "f.json"); }), "/p|expected an object, got 3");
  EXPECT_EQ(refusal([] { Reader(json::array(), "", "f.json", "expected a JSON object"); }),
            "|expected a JSON object");
}

TEST(JsonReader, IntegersAreNeverTruncatedOrRounded) {
  EXPECT_EQ(strict_integer(json(4294967297ll), 0, 100), std::nullopt);
  EXPECT_EQ(strict_integer(json(18446744073709551615ull), -5, 100), std::nullopt);
  EXPECT_EQ(strict_integer(json(2.0), 0, 100), std::nullopt);
  EXPECT_EQ(strict_integer(json(true), 0, 100), std::nullopt);
  EXPECT_EQ(strict_integer(json(-3), -5, 100), -3);
  const json j = {{"n", 4294967297ll}};
  Reader r(j, "", "f.json");
  EXPECT_EQ(refusal([&] { r.integer("n", 1, 10); }),
            "/n|expected an integer in [1, 10], got 4294967297");
}

TEST(JsonReader, TypedValuesSayWhatWasExpected) {
  enum class Edge { kWrap, kClamp };
  struct Name {
    const char* name;
    Edge value;
  };
  const Name names[] = {{"wrap", Edge::kWrap}, {"clamp", Edge::kClamp}};
  const json j = {{"x", "big"}, {"e", "mirror"}, {"b", 1}, {"s", 2}};
  Reader r(j, "", "f.json");
  EXPECT_EQ(refusal([&] {
              r.number(
                  "x", [](double) { return true; }, "in [0, 1]");
            }),
            "/x|expected a number in [0, 1], got \"big\"");
  EXPECT_EQ(refusal([&] { r.choice<Edge>("e", names); }),
            "/e|expected one of \"wrap\", \"clamp\", got \"mirror\"");
  EXPECT_EQ(r.choice<Edge>("missing", names, Edge::kClamp), Edge::kClamp);
  EXPECT_EQ(refusal([&] { r.boolean_or("b", false); }), "/b|expected true or false, got 1");
  EXPECT_EQ(refusal([&] { r.string("s"); }), "/s|expected a string, got 2");
  EXPECT_DOUBLE_EQ(r.number_or(
                       "y", 0.5, [](double) { return true; }, ""),
                   0.5);
}

TEST(JsonReader, ListsMustBeNonEmptyArrays) {
  const json j = {{"empty", json::array()}, {"word", "a"}, {"list", {1, 2}}};
  Reader r(j, "/s", "f.json");
  EXPECT_EQ(refusal([&] { r.nonempty_array("empty", "maps"); }),
            "/s/empty|expected a non-empty array of maps");
  EXPECT_EQ(refusal([&] { r.nonempty_array("word", "maps"); }),
            "/s/word|expected a non-empty array of maps");
  EXPECT_EQ(refusal([&] { r.nonempty_array("none", "maps"); }), "/s/none|missing required key");
  EXPECT_EQ(r.nonempty_array("list", "numbers").size(), 2u);
}

}  // namespace
}  // namespace penumbra
