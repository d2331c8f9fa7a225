// Field readers shared by the study file's sections: each throws an
// InputError naming the file and the JSON pointer of the field it checks.
#pragma once

#include <initializer_list>
#include <string>

#include <nlohmann/json.hpp>

namespace penumbra {

// pointer + "/" + key (the key is used as written: study keys need no escape).
std::string child(const std::string& pointer, const std::string& key);

// Refuses any key of `object` not in `known`, listing the known ones.
void reject_unknown(const nlohmann::json& object, std::initializer_list<const char*> known,
                    const std::string& file, const std::string& pointer);

// object[key], or an InputError "missing required key".
const nlohmann::json& require(const nlohmann::json& object, const char* key,
                              const std::string& file, const std::string& pointer);

// The value of an integer in [lo, hi], or -1 when `v` is not one (no
// truncation: 4294967297 is not 1).
long long strict_integer(const nlohmann::json& v, long long lo, long long hi);

}  // namespace penumbra
