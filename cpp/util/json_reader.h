// Reading one JSON object of an input file strictly, the way Mitsuba and
// pbrt read scenes: the Reader records every key it is asked for, and
// finish() refuses the keys nobody asked for, so that a misspelt or misplaced
// key is an error naming the file and its JSON pointer, never a silent
// default. Scene files (scene/scene_json.h) and study files
// (study/study_file.h) are both read through it.
#pragma once

#include <cstddef>
#include <functional>
#include <initializer_list>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace penumbra {

// The value of an integer in [lo, hi], or nullopt when `v` is not one (no
// truncation: 4294967297 is not 1, 2.0 is not 2).
std::optional<long long> strict_integer(const nlohmann::json& v, long long lo, long long hi);

class Reader {
 public:
  // `j` at `pointer` in the file `origin`. `not_object` is the error when
  // `j` is not an object; empty: "expected an object, got <j>".
  Reader(const nlohmann::json& j, std::string pointer, std::string origin,
         const std::string& not_object = "");

  // Declares every key the object may hold, in the order an error lists
  // them, and refuses any other key now, before any other check: for formats
  // that name their keys up front (studies). finish() then refuses a
  // declared key that is present but was never read.
  void expect(std::initializer_list<std::string_view> keys);

  // Throws InputError at the key's pointer ("" : the object's own).
  [[noreturn]] void fail(std::string_view key, const std::string& message) const;
  // Throws InputError at element `index` of the array under `key`.
  [[noreturn]] void fail_item(std::string_view key, std::size_t index,
                              const std::string& message) const;
  std::string child_pointer(std::string_view key) const;
  std::string item_pointer(std::string_view key, std::size_t index) const;

  // Whether the object has `key`; either way the key counts as read.
  bool has(std::string_view key);
  // The value of a required key ("missing required key" otherwise).
  const nlohmann::json& at(std::string_view key);
  // The array under a required key, which may not be empty: "expected a
  // non-empty array of <what>" otherwise.
  const nlohmann::json& nonempty_array(std::string_view key, std::string_view what);
  // The object under `key`, and the object at element `index` of the array
  // under `key`, as Readers of their own.
  Reader object(std::string_view key, const std::string& not_object = "");
  Reader item(std::string_view key, std::size_t index, const std::string& not_object = "");

  // Typed values; each error says what was expected and shows what was found.
  double number(std::string_view key, const std::function<bool(double)>& valid,
                std::string_view domain);
  double number_or(std::string_view key, double fallback, const std::function<bool(double)>& valid,
                   std::string_view domain);
  long long integer(std::string_view key, long long lo, long long hi);
  long long integer_or(std::string_view key, long long fallback, long long lo, long long hi);
  bool boolean_or(std::string_view key, bool fallback);
  std::string string(std::string_view key);
  // One of a fixed set of names (a table of {name, value}, core/enum_names.h);
  // the error lists them.
  template <typename Enum, typename Names>
  Enum choice(std::string_view key, const Names& options,
              std::optional<Enum> fallback = std::nullopt) {
    if (fallback && !has(key)) return *fallback;
    const nlohmann::json& v = at(key);
    std::string names;
    for (const auto& [name, value] : options) {
      if (v.is_string() && v.get<std::string>() == name) return value;
      names += (names.empty() ? "\"" : ", \"") + std::string(name) + "\"";
    }
    fail(key, "expected one of " + names + ", got " + describe(v));
  }

  // Refuses every key that was not read: "unknown key" with the keys read
  // (sorted) or, after expect(), "unused key" with the keys read here.
  void finish() const;

  const std::string& pointer() const { return pointer_; }
  const std::string& origin() const { return origin_; }
  static std::string describe(const nlohmann::json& value);

 private:
  const nlohmann::json& j_;
  std::string pointer_, origin_;
  std::set<std::string, std::less<>> read_;
  std::vector<std::string> declared_;  // expect(), in order; empty: none
};

}  // namespace penumbra
