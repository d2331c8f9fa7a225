#include "core/light_sampling.h"

#include <algorithm>
#include <cmath>

namespace penumbra {

namespace {

// 1 - cos theta_max without the cancellation of 1 - sqrt(1 - s2) for a
// small or distant sphere (s2 = sin^2 theta_max).
double one_minus_cos_max(double sin2_max) {
  const double cos_max = std::sqrt(std::max(0.0, 1.0 - sin2_max));
  return sin2_max / (1.0 + cos_max);
}

// The spherical rectangle a rectangle subtends at p, in the rectangle's
// frame (x along edge_u, y along edge_v, z towards p's far side so that
// z0 < 0), as Urena et al. 2013 set it up (their section 3).
struct SphericalRectangle {
  Vec3 x, y, z;
  double x0 = 0, y0 = 0, z0 = 0, x1 = 0, y1 = 0;
  double b0 = 0, b1 = 0, k = 0, solid_angle = 0;
};

bool is_rectangle(const Vec3& edge_u, const Vec3& edge_v) {
  return std::abs(dot(edge_u, edge_v)) <= 1e-9 * length(edge_u) * length(edge_v);
}

SphericalRectangle spherical_rectangle(const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v,
                                       const Vec3& p) {
  SphericalRectangle r;
  const double exl = length(edge_u), eyl = length(edge_v);
  r.x = edge_u / exl, r.y = edge_v / eyl, r.z = cross(r.x, r.y);
  const Vec3 d = corner - p;
  r.z0 = dot(d, r.z);
  if (r.z0 > 0.0) r.z = -r.z, r.z0 = -r.z0;
  r.x0 = dot(d, r.x), r.y0 = dot(d, r.y);
  r.x1 = r.x0 + exl, r.y1 = r.y0 + eyl;
  if (!(r.z0 < 0.0)) return r;  // on the plane: nothing subtended
  const Vec3 v00{r.x0, r.y0, r.z0}, v01{r.x0, r.y1, r.z0}, v10{r.x1, r.y0, r.z0},
      v11{r.x1, r.y1, r.z0};
  const Vec3 n0 = normalize(cross(v00, v10)), n1 = normalize(cross(v10, v11));
  const Vec3 n2 = normalize(cross(v11, v01)), n3 = normalize(cross(v01, v00));
  const auto angle = [](const Vec3& a, const Vec3& b) {
    return std::acos(std::clamp(-dot(a, b), -1.0, 1.0));
  };
  const double g0 = angle(n0, n1), g1 = angle(n1, n2), g2 = angle(n2, n3), g3 = angle(n3, n0);
  r.b0 = n0.z, r.b1 = n2.z;
  r.k = 2.0 * kPi - g2 - g3;
  r.solid_angle = std::max(0.0, g0 + g1 - r.k);
  return r;
}

// Whether the emitting side (edge_u x edge_v) faces p.
bool faces(const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v, const Vec3& p) {
  return dot(cross(edge_u, edge_v), p - corner) > 0.0;
}

}  // namespace

double rectangle_solid_angle(const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v,
                             const Vec3& p) {
  return spherical_rectangle(corner, edge_u, edge_v, p).solid_angle;
}

LightDirectionSample sample_rectangle_light(const Vec3& corner, const Vec3& edge_u,
                                            const Vec3& edge_v, const Vec3& p, double u1,
                                            double u2) {
  if (!is_rectangle(edge_u, edge_v)) return sample_quad_light(corner, edge_u, edge_v, p, u1, u2);
  if (!faces(corner, edge_u, edge_v, p)) return {};
  const SphericalRectangle r = spherical_rectangle(corner, edge_u, edge_v, p);
  if (!(r.solid_angle >= kMinSphericalRectangle))
    return sample_quad_light(corner, edge_u, edge_v, p, u1, u2);
  // u1 picks the x of the point by the area to its left (their eq. 7-9),
  // u2 its y uniformly in the sine of the elevation along that line (eq. 10-12).
  const double au = u1 * r.solid_angle + r.k;
  const double fu = (std::cos(au) * r.b0 - r.b1) / std::sin(au);
  const double cu =
      std::clamp(std::copysign(1.0, fu) / std::sqrt(fu * fu + r.b0 * r.b0), -1.0, 1.0);
  const double xu =
      std::clamp(-(cu * r.z0) / std::sqrt(std::max(1e-300, 1.0 - cu * cu)), r.x0, r.x1);
  const double dd = std::sqrt(xu * xu + r.z0 * r.z0);
  const double h0 = r.y0 / std::sqrt(dd * dd + r.y0 * r.y0);
  const double h1 = r.y1 / std::sqrt(dd * dd + r.y1 * r.y1);
  const double hv = h0 + u2 * (h1 - h0), hv2 = hv * hv;
  const double yv =
      hv2 < 1.0 - 1e-12 ? std::clamp(hv * dd / std::sqrt(1.0 - hv2), r.y0, r.y1) : r.y1;
  const Vec3 to_point = r.x * xu + r.y * yv + r.z * r.z0;
  const double distance = length(to_point);
  if (!(distance > 0.0)) return {};
  return {to_point / distance, 1.0 / r.solid_angle, distance};
}

LightDirectionSample rectangle_light_pdf(const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v,
                                         const Vec3& p, const Vec3& wi) {
  const LightDirectionSample hit = quad_light_pdf(corner, edge_u, edge_v, p, wi);
  if (!(hit.pdf > 0.0) || !is_rectangle(edge_u, edge_v)) return hit;
  const double solid_angle = rectangle_solid_angle(corner, edge_u, edge_v, p);
  if (!(solid_angle >= kMinSphericalRectangle)) return hit;
  return {wi, 1.0 / solid_angle, hit.distance};
}

double sphere_solid_angle(const Vec3& centre, double radius, const Vec3& p) {
  const double d2 = length_squared(centre - p);
  const double r2 = radius * radius;
  if (d2 <= r2) return 0.0;
  return 2.0 * kPi * one_minus_cos_max(r2 / d2);
}

LightDirectionSample sample_sphere_light(const Vec3& centre, double radius, const Vec3& p,
                                         double u1, double u2) {
  const Vec3 to_centre = centre - p;
  const double d2 = length_squared(to_centre);
  const double r2 = radius * radius;
  if (d2 <= r2) return {};
  const double d = std::sqrt(d2);
  const double cap = one_minus_cos_max(r2 / d2);  // 1 - cos theta_max
  // cos theta uniform in [cos theta_max, 1]: 1 - cos theta = u1 cap, and
  // sin^2 theta = (1 - cos)(1 + cos), both without cancellation.
  const double one_minus_cos = u1 * cap;
  const double cos_theta = 1.0 - one_minus_cos;
  const double sin_theta = std::sqrt(std::max(0.0, one_minus_cos * (2.0 - one_minus_cos)));
  const double phi = 2.0 * kPi * u2;
  const Frame frame = Frame::from_z(to_centre / d);
  const Vec3 wi =
      normalize(frame.to_world({sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta}));
  // The nearer root of |p + t wi - centre| = radius; the discriminant is
  // r^2 - d^2 sin^2 theta >= 0 inside the cone (clamped for rounding).
  const double b = dot(wi, to_centre);
  const double distance = b - std::sqrt(std::max(0.0, r2 - (d2 - b * b)));
  return {wi, 1.0 / (2.0 * kPi * cap), std::max(distance, 0.0)};
}

LightDirectionSample sample_quad_light(const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v,
                                       const Vec3& p, double u1, double u2) {
  const Vec3 normal_area = cross(edge_u, edge_v);  // |.| = area
  const double area = length(normal_area);
  const Vec3 to_light = corner + edge_u * u1 + edge_v * u2 - p;
  const double d2 = length_squared(to_light);
  if (!(area > 0.0) || !(d2 > 0.0)) return {};
  const double d = std::sqrt(d2);
  const Vec3 wi = to_light / d;
  const double cos_light = -dot(normal_area, wi) / area;
  if (!(cos_light > 0.0)) return {};
  return {wi, d2 / (area * cos_light), d};
}

LightDirectionSample sphere_light_pdf(const Vec3& centre, double radius, const Vec3& p,
                                      const Vec3& wi) {
  const Vec3 to_centre = centre - p;
  const double d2 = length_squared(to_centre);
  const double r2 = radius * radius;
  if (d2 <= r2) return {};
  const double b = dot(wi, to_centre);
  const double discriminant = r2 - (d2 - b * b);
  if (!(b > 0.0) || discriminant < 0.0) return {};
  const double cap = one_minus_cos_max(r2 / d2);
  return {wi, 1.0 / (2.0 * kPi * cap), std::max(b - std::sqrt(discriminant), 0.0)};
}

LightDirectionSample quad_light_pdf(const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v,
                                    const Vec3& p, const Vec3& wi) {
  const Vec3 normal_area = cross(edge_u, edge_v);
  const double area2 = length_squared(normal_area);
  const double facing = -dot(normal_area, wi);  // area cos theta_l
  if (!(area2 > 0.0) || !(facing > 0.0)) return {};
  const double t = -dot(normal_area, corner - p) / facing;
  if (!(t > 0.0)) return {};
  // x - corner = a edge_u + b edge_v: a and b by the cross products with
  // the other edge, projected on the normal.
  const Vec3 x = p + wi * t - corner;
  const double a = dot(cross(x, edge_v), normal_area) / area2;
  const double b = dot(cross(edge_u, x), normal_area) / area2;
  if (a < 0.0 || a > 1.0 || b < 0.0 || b > 1.0) return {};
  return {wi, t * t / facing, t};
}

Vec3 sample_cosine_direction(const Vec3& n, double u1, double u2) {
  const double r = std::sqrt(u1), phi = 2.0 * kPi * u2;
  const double z = std::sqrt(std::max(0.0, 1.0 - u1));
  return normalize(Frame::from_z(n).to_world({r * std::cos(phi), r * std::sin(phi), z}));
}

double cosine_direction_pdf(const Vec3& n, const Vec3& wi) {
  return std::max(0.0, dot(n, wi)) / kPi;
}

Vec3 polygon_light_vector(const Vec3* vertices, int count, const Vec3& p, double radiance) {
  Vec3 sum;
  for (int i = 0; i < count; ++i) {
    const Vec3 a = normalize(vertices[i] - p);
    const Vec3 b = normalize(vertices[(i + 1) % count] - p);
    const Vec3 c = cross(a, b);
    const double sin_gamma = length(c);
    if (!(sin_gamma > 0.0)) continue;
    sum += c * (std::atan2(sin_gamma, dot(a, b)) / sin_gamma);
  }
  // Every direction the polygon subtends points to the far side of p along
  // its plane's normal m, so the integral of w does too; the sum's sign
  // follows the winding, which this fixes.
  Vec3 m = cross(vertices[1] - vertices[0], vertices[count - 1] - vertices[0]);
  const double side = dot(m, vertices[0] - p);
  if (side == 0.0) return {};
  if (side < 0.0) m = -m;
  return sum * (dot(sum, m) < 0.0 ? -0.5 * radiance : 0.5 * radiance);
}

double polygon_irradiance(const Vec3* vertices, int count, const Vec3& p, const Vec3& n,
                          double radiance) {
  return std::abs(dot(n, polygon_light_vector(vertices, count, p, radiance)));
}

std::uint32_t permute_index(std::uint32_t i, std::uint32_t n, std::uint32_t seed) {
  if (n <= 1) return 0;
  std::uint32_t mask = n - 1;
  mask |= mask >> 1, mask |= mask >> 2, mask |= mask >> 4, mask |= mask >> 8, mask |= mask >> 16;
  // Each step is a bijection of [0, mask]: xor with a constant, a
  // multiplication by an odd number and a right xor-shift modulo a power
  // of two. Walking the cycle from i until it falls below n keeps it a
  // bijection of [0, n).
  do {
    i ^= seed;
    i *= 0xe170893du;
    i &= mask;
    i ^= i >> 4;
    i ^= seed >> 16;
    i *= 0x0929eb3fu;
    i &= mask;
    i ^= i >> 7;
    i *= 0x6935fa69u | 1u;
    i &= mask;
    i ^= i >> 11;
  } while (i >= n);
  return (i + seed) % n;
}

}  // namespace penumbra
