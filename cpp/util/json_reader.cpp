#include "util/json_reader.h"

#include <cmath>
#include <cstdint>

#include <fmt/format.h>

#include "util/strict_json.h"

namespace penumbra {

using nlohmann::json;

std::optional<long long> strict_integer(const json& v, long long lo, long long hi) {
  if (v.is_number_unsigned()) {
    const auto u = v.get<std::uint64_t>();
    if (hi < 0 || u > static_cast<std::uint64_t>(hi)) return std::nullopt;
    const auto i = static_cast<long long>(u);
    return i >= lo ? std::optional(i) : std::nullopt;
  }
  if (!v.is_number_integer()) return std::nullopt;
  const auto i = v.get<std::int64_t>();
  return i >= lo && i <= hi ? std::optional<long long>(i) : std::nullopt;
}

Reader::Reader(const json& j, std::string pointer, std::string origin,
               const std::string& not_object)
    : j_(j), pointer_(std::move(pointer)), origin_(std::move(origin)) {
  if (!j_.is_object())
    fail("", not_object.empty() ? "expected an object, got " + describe(j_) : not_object);
}

void Reader::expect(std::initializer_list<std::string_view> keys) {
  declared_.assign(keys.begin(), keys.end());
  for (const auto& [key, value] : j_.items()) {
    bool known = false;
    for (std::string_view k : keys) known = known || key == k;
    if (!known) fail(key, fmt::format("unknown key (expected one of: {})", fmt::join(keys, ", ")));
  }
}

void Reader::fail(std::string_view key, const std::string& message) const {
  throw InputError(origin_, key.empty() ? pointer_ : child_pointer(key), message);
}

void Reader::fail_item(std::string_view key, std::size_t index, const std::string& message) const {
  throw InputError(origin_, item_pointer(key, index), message);
}

std::string Reader::child_pointer(std::string_view key) const {
  return pointer_ + "/" + pointer_token(key);
}

std::string Reader::item_pointer(std::string_view key, std::size_t index) const {
  return child_pointer(key) + "/" + std::to_string(index);
}

bool Reader::has(std::string_view key) {
  read_.emplace(key);
  return j_.contains(key);
}

const json& Reader::at(std::string_view key) {
  if (!has(key)) fail(key, "missing required key");
  return j_.find(key).value();
}

const json& Reader::nonempty_array(std::string_view key, std::string_view what) {
  const json& v = at(key);
  if (!v.is_array() || v.empty()) fail(key, fmt::format("expected a non-empty array of {}", what));
  return v;
}

Reader Reader::object(std::string_view key, const std::string& not_object) {
  return Reader(at(key), child_pointer(key), origin_, not_object);
}

Reader Reader::item(std::string_view key, std::size_t index, const std::string& not_object) {
  return Reader(at(key).at(index), item_pointer(key, index), origin_, not_object);
}

double Reader::number(std::string_view key, const std::function<bool(double)>& valid,
                      std::string_view domain) {
  const json& v = at(key);
  if (!v.is_number() || !std::isfinite(v.get<double>()) || !valid(v.get<double>()))
    fail(key, fmt::format("expected a number {}, got {}", domain, describe(v)));
  return v.get<double>();
}

double Reader::number_or(std::string_view key, double fallback,
                         const std::function<bool(double)>& valid, std::string_view domain) {
  return has(key) ? number(key, valid, domain) : fallback;
}

long long Reader::integer(std::string_view key, long long lo, long long hi) {
  const json& v = at(key);
  const std::optional<long long> n = strict_integer(v, lo, hi);
  if (!n) fail(key, fmt::format("expected an integer in [{}, {}], got {}", lo, hi, describe(v)));
  return *n;
}

long long Reader::integer_or(std::string_view key, long long fallback, long long lo, long long hi) {
  return has(key) ? integer(key, lo, hi) : fallback;
}

bool Reader::boolean_or(std::string_view key, bool fallback) {
  if (!has(key)) return fallback;
  const json& v = at(key);
  if (!v.is_boolean()) fail(key, "expected true or false, got " + describe(v));
  return v.get<bool>();
}

std::string Reader::string(std::string_view key) {
  const json& v = at(key);
  if (!v.is_string()) fail(key, "expected a string, got " + describe(v));
  return v.get<std::string>();
}

void Reader::finish() const {
  for (const auto& [key, value] : j_.items()) {
    if (read_.count(key)) continue;
    if (!declared_.empty())
      fail(key, fmt::format("unused key (read here: {})", fmt::join(read_, ", ")));
    fail(key, fmt::format("unknown key (expected one of: {})", fmt::join(read_, ", ")));
  }
}

std::string Reader::describe(const json& value) {
  return describe_json(value, 60);
}

}  // namespace penumbra
