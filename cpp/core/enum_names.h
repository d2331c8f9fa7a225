// One name table per enumeration, declared beside it: the scene reader takes
// its choices from the table and to_string() reads the same table, so a name
// is written once.
#pragma once

#include <span>

namespace penumbra {

template <typename Enum>
struct EnumName {
  const char* name;
  Enum value;
};

template <typename Enum>
const char* name_of(std::span<const EnumName<Enum>> table, Enum value) {
  for (const EnumName<Enum>& entry : table)
    if (entry.value == value) return entry.name;
  return "?";
}

}  // namespace penumbra
