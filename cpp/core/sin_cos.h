// sin and cos of one argument, within 3 ulp where |x| <= kSinCosReduced,
// written so that a SIMD lane can perform the same operations and get the
// same bits (core/ray_packet.cpp mirrors it): the height functions are
// evaluated one point at a time and a packet at a time, and both must give
// one render. The C library's sin and cos cannot serve: glibc picks its
// code by CPU (an FMA variant on recent x86), and no vector library
// promises its bits.
//
// The method is fdlibm's (Sun Microsystems 1993, as in FreeBSD's msun):
// x = j pi/2 + r with |r| <= pi/4, pi/2 split in three 33-bit parts so that
// j times each is exact for |j| < 2^20, and a tail; then the minimax
// polynomials of __kernel_sin and __kernel_cos on r, and the quadrant
// j mod 4. Without fdlibm's second word of r it rounds r twice, hence up to
// 3 ulp rather than 1 (against long double sinl and cosl: 2.5 ulp at most;
// tests/core/test_height_shape.cpp).
#pragma once

#include <cmath>

namespace penumbra {

struct SinCos {
  double sin = 0.0, cos = 1.0;
};

namespace sin_cos_detail {
inline constexpr double kTwoOverPi = 6.36619772367581382433e-01;
inline constexpr double kPiOver2Part1 = 1.57079632673412561417e+00;  // first 33 bits
inline constexpr double kPiOver2Part2 = 6.07710050630396597660e-11;  // next 33 bits
inline constexpr double kPiOver2Part3 = 2.02226624871116645580e-21;  // next 33 bits
inline constexpr double kPiOver2Tail = 8.47842766036889956997e-32;   // the rest
inline constexpr double kS1 = -1.66666666666666324348e-01;
inline constexpr double kS2 = 8.33333333332248946124e-03;
inline constexpr double kS3 = -1.98412698298579493134e-04;
inline constexpr double kS4 = 2.75573137070700676789e-06;
inline constexpr double kS5 = -2.50507602534068634195e-08;
inline constexpr double kS6 = 1.58969099521155010221e-10;
inline constexpr double kC1 = 4.16666666666666019037e-02;
inline constexpr double kC2 = -1.38888888888741095749e-03;
inline constexpr double kC3 = 2.48015872894767294178e-05;
inline constexpr double kC4 = -2.75573143513906633035e-07;
inline constexpr double kC5 = 2.08757232129817482790e-09;
inline constexpr double kC6 = -1.13596475577881948265e-11;
}  // namespace sin_cos_detail

// Beyond this |x| (j reaches 2^20 near 1.6e6) the reduction is no longer
// exact and the C library's sin and cos answer instead.
inline constexpr double kSinCosReduced = 1.0e6;

inline SinCos sin_cos(double x) {
  using namespace sin_cos_detail;
  if (!(std::abs(x) <= kSinCosReduced)) return {std::sin(x), std::cos(x)};
  const double j = std::nearbyint(x * kTwoOverPi);
  const double r =
      (((x - j * kPiOver2Part1) - j * kPiOver2Part2) - j * kPiOver2Part3) - j * kPiOver2Tail;
  const double z = r * r;
  const double s = r + (z * r) * (kS1 + z * (kS2 + z * (kS3 + z * (kS4 + z * (kS5 + z * kS6)))));
  const double half_z = 0.5 * z;
  const double w = 1.0 - half_z;
  const double c = w + (((1.0 - w) - half_z) +
                        z * (z * (kC1 + z * (kC2 + z * (kC3 + z * (kC4 + z * (kC5 + z * kC6)))))));
  const double quadrant = j - 4.0 * std::floor(j * 0.25);  // 0, 1, 2 or 3
  const bool odd = quadrant == 1.0 || quadrant == 3.0;
  const double sin_r = odd ? c : s, cos_r = odd ? s : c;
  return {quadrant >= 2.0 ? -sin_r : sin_r, quadrant == 1.0 || quadrant == 2.0 ? -cos_r : cos_r};
}

}  // namespace penumbra
