// FNV-1a: a small, dependency-free hash for content keys and damage checks
// (not for security: nothing here defends against a deliberate collision).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace penumbra {

inline constexpr std::uint64_t kFnvOffset = 0xcbf29ce484222325ull;
inline constexpr std::uint64_t kFnvPrime = 0x100000001b3ull;

// Continues the FNV-1a hash `h` over `bytes`.
inline std::uint64_t fnv1a(const void* data, std::size_t bytes, std::uint64_t h = kFnvOffset) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * kFnvPrime;
  return h;
}
inline std::uint64_t fnv1a(std::string_view text, std::uint64_t h = kFnvOffset) {
  return fnv1a(text.data(), text.size(), h);
}

}  // namespace penumbra
