// Small value types for the pure-math core: no I/O, no allocation.
// Double precision throughout: the evaluator is a reference, and the shadowing
// factors are most sensitive exactly where vectors are nearly parallel.
#pragma once

#include <algorithm>
#include <cmath>

namespace penumbra {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kInvPi = 1.0 / kPi;

inline double degrees(double radians) {
  return radians * (180.0 / kPi);
}
inline double radians(double degrees) {
  return degrees * (kPi / 180.0);
}

struct Vec3 {
  double x = 0, y = 0, z = 0;

  constexpr Vec3() = default;
  constexpr Vec3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}

  constexpr double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr Vec3 operator-() const { return {-x, -y, -z}; }
  constexpr Vec3& operator+=(const Vec3& b) {
    x += b.x;
    y += b.y;
    z += b.z;
    return *this;
  }
  constexpr Vec3& operator*=(double s) {
    x *= s;
    y *= s;
    z *= s;
    return *this;
  }
  friend constexpr bool operator==(const Vec3& a, const Vec3& b) = default;
};

constexpr Vec3 operator+(const Vec3& a, const Vec3& b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
constexpr Vec3 operator-(const Vec3& a, const Vec3& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
constexpr Vec3 operator*(const Vec3& a, double s) {
  return {a.x * s, a.y * s, a.z * s};
}
constexpr Vec3 operator*(double s, const Vec3& a) {
  return a * s;
}
constexpr Vec3 operator/(const Vec3& a, double s) {
  return a * (1.0 / s);
}

constexpr double dot(const Vec3& a, const Vec3& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
// <a,b> of the reference sheet: the cosine clamped to the upper hemisphere.
inline double clamped_dot(const Vec3& a, const Vec3& b) {
  return std::max(0.0, dot(a, b));
}
constexpr Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double length_squared(const Vec3& a) {
  return dot(a, a);
}
inline double length(const Vec3& a) {
  return std::sqrt(dot(a, a));
}
inline Vec3 normalize(const Vec3& a) {
  return a / length(a);
}
inline bool is_finite(const Vec3& a) {
  return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}

// Angle between unit vectors, accurate also when they are nearly parallel
// or antiparallel (acos of the dot product loses half the digits there).
inline double angle_between(const Vec3& a, const Vec3& b) {
  return std::atan2(length(cross(a, b)), dot(a, b));
}

// acos to within 2e-8 radians on [-1, 1] (Abramowitz & Stegun 4.4.46), about
// three times cheaper than std::acos. For analysis channels stored as float
// degrees (resolution ~1e-5 degrees near 180); not for shading.
inline double acos_approx(double x) {
  const double a = std::min(std::abs(x), 1.0);
  const double p =
      1.5707963050 +
      a * (-0.2145988016 +
           a * (0.0889789874 +
                a * (-0.0501743046 +
                     a * (0.0308918810 +
                          a * (-0.0170881256 + a * (0.0066700901 + a * -0.0012624911))))));
  const double r = std::sqrt(1.0 - a) * p;
  return x < 0.0 ? kPi - r : r;
}

// v rotated by the rotation that takes unit a to unit b about a x b (the
// identity for a == b). Undefined for b == -a.
inline Vec3 rotate_between(const Vec3& a, const Vec3& b, const Vec3& v) {
  const Vec3 k = cross(a, b);
  const double c = dot(a, b);
  return v * c + cross(k, v) + k * (dot(k, v) / (1.0 + c));
}

// Orthonormal basis around a unit vector n (Duff et al. 2017, branchless).
struct Frame {
  Vec3 s, t, n;

  static Frame from_z(const Vec3& n) {
    const double sign = std::copysign(1.0, n.z);
    const double a = -1.0 / (sign + n.z);
    const double b = n.x * n.y * a;
    return {
        {1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x}, {b, sign + n.y * n.y * a, -n.y}, n};
  }
  Vec3 to_local(const Vec3& v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
  Vec3 to_world(const Vec3& v) const { return s * v.x + t * v.y + n * v.z; }
};

}  // namespace penumbra
