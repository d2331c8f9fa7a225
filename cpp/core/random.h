// Deterministic random numbers: the same bits on every platform and thread
// count (std:: distributions are implementation-defined, so they are avoided).
#pragma once

#include <cstdint>

namespace penumbra {

// SplitMix64 finaliser (Steele et al. 2014): decorrelates seeds derived from
// consecutive integers such as pixel indices.
constexpr std::uint64_t mix64(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

// Element n of the SplitMix64 sequence from `key` (Steele et al. 2014) as a
// uniform double in [0, 1) with 53 random bits: a counter-based draw, which
// depends on nothing drawn before it.
constexpr double splitmix_double(std::uint64_t key, std::uint64_t n) {
  return static_cast<double>(mix64(key + n * 0x9e3779b97f4a7c15ull) >> 11u) * 0x1.0p-53;
}

// PCG32 (O'Neill 2014, XSH-RR variant).
class Pcg32 {
 public:
  explicit Pcg32(std::uint64_t seed, std::uint64_t stream = 0x5851f42d4c957f2dull)
      : increment_((stream << 1u) | 1u) {
    next_u32();
    state_ += seed;
    next_u32();
  }

  std::uint32_t next_u32() {
    const std::uint64_t old = state_;
    state_ = old * 6364136223846793005ull + increment_;
    const auto xorshifted = static_cast<std::uint32_t>(((old >> 18u) ^ old) >> 27u);
    const auto rot = static_cast<std::uint32_t>(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
  }

  // Uniform in [0,1) with 53 random bits.
  double next_double() {
    const std::uint64_t hi = next_u32() >> 5u;  // 27 bits
    const std::uint64_t lo = next_u32() >> 6u;  // 26 bits
    return static_cast<double>((hi << 26u) | lo) * 0x1.0p-53;
  }

 private:
  std::uint64_t state_ = 0;
  std::uint64_t increment_;
};

}  // namespace penumbra
