#include "core/shape.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace penumbra {
namespace {

// Roots of a t^2 + 2 b t + c = 0 in ascending order, stable against
// cancellation. Returns false when there is no real root.
bool solve_quadratic(double a, double b, double c, double* t0, double* t1) {
  const double discriminant = b * b - a * c;
  if (discriminant < 0.0 || a == 0.0) return false;
  const double q = -(b + std::copysign(std::sqrt(discriminant), b));
  double r0 = q / a;
  double r1 = q != 0.0 ? c / q : r0;
  if (r0 > r1) std::swap(r0, r1);
  *t0 = r0;
  *t1 = r1;
  return true;
}

SurfaceGeometry cylinder_side(const Shape& s, const Vec3& local) {
  SurfaceGeometry g;
  g.v = local.z;
  const double inv_r = 1.0 / std::sqrt(local.x * local.x + local.y * local.y);
  const Vec3 radial{local.x * inv_r, local.y * inv_r, 0.0};
  g.n = s.frame.to_world(radial);
  g.p = s.center + s.frame.to_world({s.radius * radial.x, s.radius * radial.y, g.v});
  g.t2 = s.axis;
  g.t1 = cross(g.t2, g.n);
  g.kappa1 = 1.0 / s.radius;
  g.kappa2 = 0.0;
  return g;
}

SurfaceGeometry cylinder_cap(const Shape& s, const Vec3& local, double sign) {
  SurfaceGeometry g;
  g.n = s.axis * sign;
  g.p = s.center + s.frame.to_world({local.x, local.y, sign * 0.5 * s.height});
  const Frame f = Frame::from_z(g.n);
  g.t1 = f.s;
  g.t2 = f.t;
  g.displaceable = false;
  return g;
}

SurfaceGeometry sphere_at_direction(const Shape& s, const Vec3& local_n) {
  SurfaceGeometry g;
  g.n = s.frame.to_world(local_n);
  g.p = s.center + g.n * s.radius;
  const Frame f = Frame::from_z(g.n);
  g.t1 = f.s;
  g.t2 = f.t;
  g.kappa1 = g.kappa2 = 1.0 / s.radius;
  return g;
}

SurfaceGeometry plane_at(const Shape& s, double x, double y) {
  SurfaceGeometry g;
  g.n = s.axis;
  g.p = s.center + s.frame.s * x + s.frame.t * y;
  g.t1 = s.frame.s;
  g.t2 = s.frame.t;
  return g;
}

// The plane's hit distance along a local ray, or a negative value when the
// ray is parallel to it or misses the rectangle.
double plane_hit(const Shape& s, const Vec3& o, const Vec3& d) {
  if (d.z == 0.0) return -1.0;
  const double t = -o.z / d.z;
  const double x = o.x + t * d.x, y = o.y + t * d.y;
  if (std::abs(x) > 0.5 * s.width || std::abs(y) > 0.5 * s.height) return -1.0;
  return t;
}

// Candidate hits in ascending t; calls visit(t, kind) for each, kind 0 side,
// +1 / -1 caps. Stops when visit returns true.
template <typename Visit>
void for_each_cylinder_hit(const Shape& s, const Vec3& o, const Vec3& d, Visit&& visit) {
  double candidates[4];
  int kinds[4];
  int count = 0;
  double t0, t1;
  if (solve_quadratic(d.x * d.x + d.y * d.y, o.x * d.x + o.y * d.y,
                      o.x * o.x + o.y * o.y - s.radius * s.radius, &t0, &t1)) {
    for (double t : {t0, t1}) {
      const double z = o.z + t * d.z;
      if (std::abs(z) <= 0.5 * s.height) {
        candidates[count] = t;
        kinds[count++] = 0;
      }
    }
  }
  if (s.caps && d.z != 0.0) {
    for (double sign : {-1.0, 1.0}) {
      const double t = (sign * 0.5 * s.height - o.z) / d.z;
      const double x = o.x + t * d.x, y = o.y + t * d.y;
      if (x * x + y * y <= s.radius * s.radius) {
        candidates[count] = t;
        kinds[count++] = static_cast<int>(sign);
      }
    }
  }
  // Insertion sort of at most four entries.
  for (int i = 1; i < count; ++i)
    for (int j = i; j > 0 && candidates[j] < candidates[j - 1]; --j) {
      std::swap(candidates[j], candidates[j - 1]);
      std::swap(kinds[j], kinds[j - 1]);
    }
  for (int i = 0; i < count; ++i)
    if (visit(candidates[i], kinds[i])) return;
}

// A mesh has no closed form: a caller that reached here routed it wrong.
void refuse_mesh(const Shape& s) {
  if (s.type == ShapeType::kMesh)
    throw std::logic_error(
        "a mesh shape is traced by the evaluator's mesh tracers, not analytically");
}

}  // namespace

Shape with_frame(Shape shape) {
  shape.frame = Frame::from_z(shape.axis);
  return shape;
}

bool intersect(const Shape& s, const Ray& ray, double t_min, double t_max, Hit* hit) {
  refuse_mesh(s);
  const Vec3 o = s.frame.to_local(ray.origin - s.center);
  const Vec3 d = s.frame.to_local(ray.direction);
  if (s.type == ShapeType::kPlane) {
    const double t = plane_hit(s, o, d);
    if (!(t > t_min && t < t_max)) return false;
    hit->t = t;
    hit->geometry = plane_at(s, o.x + t * d.x, o.y + t * d.y);
    return true;
  }
  if (s.type == ShapeType::kSphere) {
    double t0, t1;
    if (!solve_quadratic(dot(d, d), dot(o, d), dot(o, o) - s.radius * s.radius, &t0, &t1))
      return false;
    const double t = t0 > t_min ? t0 : t1;
    if (!(t > t_min && t < t_max)) return false;
    hit->t = t;
    hit->geometry = sphere_at_direction(s, normalize(o + d * t));
    return true;
  }
  bool found = false;
  for_each_cylinder_hit(s, o, d, [&](double t, int kind) {
    if (!(t > t_min && t < t_max)) return false;
    const Vec3 local = o + d * t;
    hit->t = t;
    hit->geometry = kind == 0 ? cylinder_side(s, local) : cylinder_cap(s, local, kind);
    found = true;
    return true;
  });
  return found;
}

bool occluded(const Shape& s, const Ray& ray, double t_min, double t_max) {
  refuse_mesh(s);
  const Vec3 o = s.frame.to_local(ray.origin - s.center);
  const Vec3 d = s.frame.to_local(ray.direction);
  if (s.type == ShapeType::kPlane) {
    const double t = plane_hit(s, o, d);
    return t > t_min && t < t_max;
  }
  if (s.type == ShapeType::kSphere) {
    double t0, t1;
    if (!solve_quadratic(dot(d, d), dot(o, d), dot(o, o) - s.radius * s.radius, &t0, &t1))
      return false;
    return (t0 > t_min && t0 < t_max) || (t1 > t_min && t1 < t_max);
  }
  bool blocked = false;
  for_each_cylinder_hit(s, o, d, [&](double t, int) {
    blocked = t > t_min && t < t_max;
    return blocked;
  });
  return blocked;
}

SurfaceGeometry surface_at(const Shape& s, double u, double v) {
  refuse_mesh(s);
  const double sin_v = std::sin(v);
  SurfaceGeometry g =
      s.type == ShapeType::kPlane ? plane_at(s, u, v)
      : s.type == ShapeType::kSphere
          ? sphere_at_direction(s, {sin_v * std::cos(u), sin_v * std::sin(u), std::cos(v)})
          : cylinder_side(s, {std::cos(u), std::sin(u), v});
  g.u = u;
  g.v = v;
  return g;
}

SurfaceGeometry base_geometry_under(const Shape& s, const Vec3& p, int cap) {
  refuse_mesh(s);
  const Vec3 local = s.frame.to_local(p - s.center);
  if (cap != 0) return cylinder_cap(s, local, cap);
  if (s.type == ShapeType::kPlane)
    return plane_at(s, std::clamp(local.x, -0.5 * s.width, 0.5 * s.width),
                    std::clamp(local.y, -0.5 * s.height, 0.5 * s.height));
  if (s.type == ShapeType::kSphere) return sphere_at_direction(s, normalize(local));
  return cylinder_side(s, {local.x, local.y, std::clamp(local.z, -0.5 * s.height, 0.5 * s.height)});
}

Vec3 displaced_normal(const SurfaceGeometry& g, double amplitude, const HeightSample& h) {
  if (!g.displaceable || amplitude == 0.0) return g.n;
  const double c1 = 1.0 + amplitude * h.h * g.kappa1;
  const double c2 = 1.0 + amplitude * h.h * g.kappa2;
  const double g1 = dot(h.gradient, g.t1);
  const double g2 = dot(h.gradient, g.t2);
  return normalize(g.n * (c1 * c2) - g.t1 * (amplitude * g1 * c2) - g.t2 * (amplitude * g2 * c1));
}

}  // namespace penumbra
