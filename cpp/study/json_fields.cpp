#include "study/json_fields.h"

#include <cstdint>

#include "util/strict_json.h"

namespace penumbra {
using nlohmann::json;

std::string child(const std::string& pointer, const std::string& key) {
  return pointer + "/" + key;
}

void reject_unknown(const json& object, std::initializer_list<const char*> known,
                    const std::string& file, const std::string& pointer) {
  for (const auto& [key, value] : object.items()) {
    bool ok = false;
    for (const char* k : known) ok = ok || key == k;
    if (!ok) {
      std::string names;
      for (const char* k : known) names += (names.empty() ? "" : ", ") + std::string(k);
      throw InputError(file, child(pointer, key), "unknown key (expected one of: " + names + ")");
    }
  }
}

const json& require(const json& object, const char* key, const std::string& file,
                    const std::string& pointer) {
  if (!object.contains(key)) throw InputError(file, child(pointer, key), "missing required key");
  return object.at(key);
}

// The value of an integer in [lo, hi], or -1 when `v` is not one (no
// truncation: 4294967297 is not 1).
long long strict_integer(const json& v, long long lo, long long hi) {
  if (v.is_number_unsigned()) {
    const auto u = v.get<std::uint64_t>();
    return u >= static_cast<std::uint64_t>(lo) && u <= static_cast<std::uint64_t>(hi)
               ? static_cast<long long>(u)
               : -1;
  }
  if (!v.is_number_integer()) return -1;
  const auto i = v.get<std::int64_t>();
  return i >= lo && i <= hi ? i : -1;
}

}  // namespace penumbra
