// FNV-1a: a small, dependency-free hash for content keys and damage checks
// (not for security: nothing here defends against a deliberate collision).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
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

// Two FNV-1a hashes with different seeds over the same bytes, written as 32
// hex digits: the content keys of image maps and factor tables.
class ContentDigest {
 public:
  void add(const void* data, std::size_t bytes) {
    a_ = fnv1a(data, bytes, a_);
    b_ = fnv1a(data, bytes, b_);
  }
  std::string hex() const {
    char text[33];
    std::snprintf(text, sizeof text, "%016llx%016llx", static_cast<unsigned long long>(a_),
                  static_cast<unsigned long long>(b_));
    return text;
  }

 private:
  std::uint64_t a_ = kFnvOffset, b_ = kFnvOffset ^ 0x9e3779b97f4a7c15ull;
};

}  // namespace penumbra
