// Each line of the vector code below mirrors an expression of shape.cpp,
// height.cpp or vec.h operation for operation (the comments name which):
// that is what keeps the bits equal to the scalar path's. Built without
// floating-point contraction (CMakeLists.txt), which would fuse a multiply
// and an add where the scalar code rounds twice.
#include "core/ray_packet.h"

#include <cmath>

#include <limits>
#include "core/sin_cos.h"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "core/ray_packet.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace penumbra {
namespace HWY_NAMESPACE {
namespace {

namespace hn = hwy::HWY_NAMESPACE;
using D = hn::ScalableTag<double>;
using V = hn::Vec<D>;
constexpr std::size_t kMaxLanes = HWY_MAX_BYTES / sizeof(double);

struct V3 {
  V x, y, z;
};

V3 splat(D d, const Vec3& a) {
  return {hn::Set(d, a.x), hn::Set(d, a.y), hn::Set(d, a.z)};
}
V3 load3(D d, const double* x, const double* y, const double* z, std::size_t i) {
  return {hn::Load(d, x + i), hn::Load(d, y + i), hn::Load(d, z + i)};
}
void store3(D d, const V3& a, double* x, double* y, double* z, std::size_t i) {
  hn::Store(a.x, d, x + i);
  hn::Store(a.y, d, y + i);
  hn::Store(a.z, d, z + i);
}
// dot(a, b) of vec.h: (a.x b.x + a.y b.y) + a.z b.z.
V dot3(const V3& a, const V3& b) {
  return hn::Add(hn::Add(hn::Mul(a.x, b.x), hn::Mul(a.y, b.y)), hn::Mul(a.z, b.z));
}
V3 sub3(const V3& a, const V3& b) {
  return {hn::Sub(a.x, b.x), hn::Sub(a.y, b.y), hn::Sub(a.z, b.z)};
}
V3 add3(const V3& a, const V3& b) {
  return {hn::Add(a.x, b.x), hn::Add(a.y, b.y), hn::Add(a.z, b.z)};
}
V3 scale3(const V3& a, V s) {
  return {hn::Mul(a.x, s), hn::Mul(a.y, s), hn::Mul(a.z, s)};
}
// normalize() of vec.h: a * (1 / sqrt(dot(a, a))).
V3 normalize3(D d, const V3& a) {
  return scale3(a, hn::Div(hn::Set(d, 1.0), hn::Sqrt(dot3(a, a))));
}
// cross() of vec.h.
V3 cross3(const V3& a, const V3& b) {
  return {hn::Sub(hn::Mul(a.y, b.z), hn::Mul(a.z, b.y)),
          hn::Sub(hn::Mul(a.z, b.x), hn::Mul(a.x, b.z)),
          hn::Sub(hn::Mul(a.x, b.y), hn::Mul(a.y, b.x))};
}

// Frame::to_local and Frame::to_world of vec.h.
struct VFrame {
  V3 s, t, n;
  V3 to_local(const V3& v) const { return {dot3(v, s), dot3(v, t), dot3(v, n)}; }
  V3 to_world(const V3& v) const {
    return add3(add3(scale3(s, v.x), scale3(t, v.y)), scale3(n, v.z));
  }
};

// solve_quadratic of shape.cpp: the roots in ascending order, and where
// there are any (a NaN discriminant passes, as there, and gives NaN roots).
struct Roots {
  V lo, hi;
  hn::Mask<D> real;
};
Roots solve_quadratic(D d, V a, V b, V c) {
  const V discriminant = hn::Sub(hn::Mul(b, b), hn::Mul(a, c));
  const auto real = hn::Not(hn::Or(hn::Lt(discriminant, hn::Zero(d)), hn::Eq(a, hn::Zero(d))));
  const V q = hn::Neg(hn::Add(b, hn::CopySign(hn::Sqrt(discriminant), b)));
  const V r0 = hn::Div(q, a);
  const V r1 = hn::IfThenElse(hn::Ne(q, hn::Zero(d)), hn::Div(c, q), r0);
  const auto swap = hn::Gt(r0, r1);
  return {hn::IfThenElse(swap, r1, r0), hn::IfThenElse(swap, r0, r1), real};
}

// The packet's constants: the shape and its frame as vectors.
struct VShape {
  VFrame frame;
  V3 center, axis;
  V radius, half_height, inv_radius;
};

// intersect() for a cylinder without caps, then cylinder_side() at the hit.
void cylinder_lanes(D d, const VShape& s, const RayPacket& r, HitPacket* h, std::size_t i) {
  const V zero = hn::Zero(d), infinity = hn::Set(d, std::numeric_limits<double>::infinity());
  const V3 o = s.frame.to_local(sub3(load3(d, r.ox, r.oy, r.oz, i), s.center));
  const V3 dir = s.frame.to_local(load3(d, r.dx, r.dy, r.dz, i));
  const Roots roots = solve_quadratic(
      d, hn::Add(hn::Mul(dir.x, dir.x), hn::Mul(dir.y, dir.y)),
      hn::Add(hn::Mul(o.x, dir.x), hn::Mul(o.y, dir.y)),
      hn::Sub(hn::Add(hn::Mul(o.x, o.x), hn::Mul(o.y, o.y)), hn::Mul(s.radius, s.radius)));
  // for_each_cylinder_hit: a root is a candidate within the height, the
  // first candidate in (t_min, t_max) is the hit.
  const auto usable = [&](V t) {
    const V z = hn::Add(o.z, hn::Mul(t, dir.z));
    return hn::And(hn::And(roots.real, hn::Le(hn::Abs(z), s.half_height)),
                   hn::And(hn::Gt(t, zero), hn::Lt(t, infinity)));
  };
  const auto lo_hit = usable(roots.lo);
  const auto found = hn::Or(lo_hit, usable(roots.hi));
  const V t = hn::IfThenElse(lo_hit, roots.lo, roots.hi);
  const V3 local = add3(o, scale3(dir, t));
  // cylinder_side.
  const V inv_r = hn::Div(hn::Set(d, 1.0),
                          hn::Sqrt(hn::Add(hn::Mul(local.x, local.x), hn::Mul(local.y, local.y))));
  const V3 radial{hn::Mul(local.x, inv_r), hn::Mul(local.y, inv_r), zero};
  const V3 n = s.frame.to_world(radial);
  const V3 p =
      add3(s.center,
           s.frame.to_world({hn::Mul(s.radius, radial.x), hn::Mul(s.radius, radial.y), local.z}));
  hn::Store(hn::IfThenElseZero(found, hn::Set(d, 1.0)), d, h->found + i);
  hn::Store(t, d, h->t + i);
  hn::Store(local.z, d, h->v + i);
  store3(d, p, h->px, h->py, h->pz, i);
  store3(d, n, h->nx, h->ny, h->nz, i);
  store3(d, cross3(s.axis, n), h->t1x, h->t1y, h->t1z, i);
  store3(d, s.axis, h->t2x, h->t2y, h->t2z, i);
}

// intersect() for a sphere, then sphere_at_direction() and Frame::from_z.
void sphere_lanes(D d, const VShape& s, const RayPacket& r, HitPacket* h, std::size_t i) {
  const V zero = hn::Zero(d), one = hn::Set(d, 1.0);
  const V3 o = s.frame.to_local(sub3(load3(d, r.ox, r.oy, r.oz, i), s.center));
  const V3 dir = s.frame.to_local(load3(d, r.dx, r.dy, r.dz, i));
  const Roots roots = solve_quadratic(d, dot3(dir, dir), dot3(o, dir),
                                      hn::Sub(dot3(o, o), hn::Mul(s.radius, s.radius)));
  const V t = hn::IfThenElse(hn::Gt(roots.lo, zero), roots.lo, roots.hi);
  const auto found = hn::And(
      roots.real,
      hn::And(hn::Gt(t, zero), hn::Lt(t, hn::Set(d, std::numeric_limits<double>::infinity()))));
  const V3 n = s.frame.to_world(normalize3(d, add3(o, scale3(dir, t))));
  const V3 p = add3(s.center, scale3(n, s.radius));
  // Frame::from_z(n).
  const V sign = hn::CopySign(one, n.z);
  const V a = hn::Div(hn::Set(d, -1.0), hn::Add(sign, n.z));
  const V b = hn::Mul(hn::Mul(n.x, n.y), a);
  const V3 t1{hn::Add(one, hn::Mul(hn::Mul(hn::Mul(sign, n.x), n.x), a)), hn::Mul(sign, b),
              hn::Mul(hn::Neg(sign), n.x)};
  const V3 t2{b, hn::Add(sign, hn::Mul(hn::Mul(n.y, n.y), a)), hn::Neg(n.y)};
  hn::Store(hn::IfThenElseZero(found, one), d, h->found + i);
  hn::Store(t, d, h->t + i);
  hn::Store(zero, d, h->v + i);
  store3(d, p, h->px, h->py, h->pz, i);
  store3(d, n, h->nx, h->ny, h->nz, i);
  store3(d, t1, h->t1x, h->t1y, h->t1z, i);
  store3(d, t2, h->t2x, h->t2y, h->t2z, i);
}

// sin_cos of core/sin_cos.h, lane by lane the same operations; lanes
// beyond its reduction go to it one by one (it hands them to the C library).
struct VSinCos {
  V sin, cos;
};
VSinCos sin_cos_lanes(D d, V x) {
  using namespace sin_cos_detail;
  if (!hn::AllTrue(d, hn::Le(hn::Abs(x), hn::Set(d, kSinCosReduced)))) {
    HWY_ALIGN_MAX double in[kMaxLanes], sines[kMaxLanes], cosines[kMaxLanes];
    hn::Store(x, d, in);
    for (std::size_t i = 0; i < hn::Lanes(d); ++i) {
      const SinCos sc = sin_cos(in[i]);
      sines[i] = sc.sin, cosines[i] = sc.cos;
    }
    return {hn::Load(d, sines), hn::Load(d, cosines)};
  }
  const auto set = [d](double v) { return hn::Set(d, v); };
  const V j = hn::Round(hn::Mul(x, set(kTwoOverPi)));
  const V r = hn::Sub(
      hn::Sub(hn::Sub(hn::Sub(x, hn::Mul(j, set(kPiOver2Part1))), hn::Mul(j, set(kPiOver2Part2))),
              hn::Mul(j, set(kPiOver2Part3))),
      hn::Mul(j, set(kPiOver2Tail)));
  const V z = hn::Mul(r, r);
  // kS1 + z (kS2 + z (... + z kS6)) and the same for kC1..kC6, inside out.
  const auto horner = [&](double c1, double c2, double c3, double c4, double c5, double c6) {
    V p = hn::Add(set(c5), hn::Mul(z, set(c6)));
    for (const double c : {c4, c3, c2, c1}) p = hn::Add(set(c), hn::Mul(z, p));
    return p;
  };
  const V s = hn::Add(r, hn::Mul(hn::Mul(z, r), horner(kS1, kS2, kS3, kS4, kS5, kS6)));
  const V one = set(1.0), half_z = hn::Mul(set(0.5), z);
  const V w = hn::Sub(one, half_z);
  const V c = hn::Add(w, hn::Add(hn::Sub(hn::Sub(one, w), half_z),
                                 hn::Mul(z, hn::Mul(z, horner(kC1, kC2, kC3, kC4, kC5, kC6)))));
  const V quadrant = hn::Sub(j, hn::Mul(set(4.0), hn::Floor(hn::Mul(j, set(0.25)))));
  const auto odd = hn::Or(hn::Eq(quadrant, one), hn::Eq(quadrant, set(3.0)));
  const V sin_r = hn::IfThenElse(odd, c, s), cos_r = hn::IfThenElse(odd, s, c);
  const auto cos_negative = hn::Or(hn::Eq(quadrant, one), hn::Eq(quadrant, set(2.0)));
  return {hn::IfThenElse(hn::Ge(quadrant, set(2.0)), hn::Neg(sin_r), sin_r),
          hn::IfThenElse(cos_negative, hn::Neg(cos_r), cos_r)};
}

// The sines and cosines of 2 pi dot(k, P) + phase of one term at every hit.
void sine_term(D d, const SineTerm& term, const HitPacket& h, std::size_t lanes, double* sines,
               double* cosines) {
  const V3 k = splat(d, term.k);
  const V two_pi = hn::Set(d, 2.0 * kPi), phase = hn::Set(d, term.phase);
  for (std::size_t i = 0; i < lanes; i += hn::Lanes(d)) {
    V arg = hn::Add(hn::Mul(two_pi, dot3(k, load3(d, h.px, h.py, h.pz, i))), phase);
    // A missed ray's lane holds NaN; its height is never read, and a NaN
    // would send the whole vector to the scalar fallback.
    arg = hn::IfThenElseZero(hn::Eq(arg, arg), arg);
    const VSinCos sc = sin_cos_lanes(d, arg);
    hn::Store(sc.sin, d, sines + i);
    hn::Store(sc.cos, d, cosines + i);
  }
}

// evaluate_height at every hit point into h, gx, gy, gz.
void height_lanes(D d, const HeightFunction& f, HitPacket* h, std::size_t lanes) {
  const std::size_t step = hn::Lanes(d);
  for (std::size_t i = 0; i < lanes; i += step) {
    const V start =
        hn::Set(d, f.combine == HeightCombine::kProduct && !f.terms.empty() ? 1.0 : 0.0);
    hn::Store(start, d, h->h + i);
    store3(d, {hn::Zero(d), hn::Zero(d), hn::Zero(d)}, h->gx, h->gy, h->gz, i);
  }
  if (f.combine == HeightCombine::kSum) {
    for (const SineTerm& term : f.terms) {
      sine_term(d, term, *h, lanes, h->sines[0], h->cosines[0]);
      const V weight = hn::Set(d, term.weight), scale = hn::Set(d, 2.0 * kPi * term.weight);
      const V3 k = splat(d, term.k);
      for (std::size_t i = 0; i < lanes; i += step) {
        hn::Store(hn::Add(hn::Load(d, h->h + i), hn::Mul(weight, hn::Load(d, h->sines[0] + i))), d,
                  h->h + i);
        const V3 g = scale3(k, hn::Mul(scale, hn::Load(d, h->cosines[0] + i)));
        store3(d, add3(load3(d, h->gx, h->gy, h->gz, i), g), h->gx, h->gy, h->gz, i);
      }
    }
    return;
  }
  const std::size_t m = std::min<std::size_t>(f.terms.size(), kMaxProductFactors);
  for (std::size_t j = 0; j < m; ++j)
    sine_term(d, f.terms[j], *h, lanes, h->sines[j], h->cosines[j]);
  for (std::size_t i = 0; i < lanes; i += step) {
    V value = hn::Load(d, h->h + i);
    for (std::size_t j = 0; j < m; ++j) value = hn::Mul(value, hn::Load(d, h->sines[j] + i));
    hn::Store(value, d, h->h + i);
    V3 g = load3(d, h->gx, h->gy, h->gz, i);
    for (std::size_t j = 0; j < m; ++j) {
      V others = hn::Set(d, 1.0);
      for (std::size_t l = 0; l < m; ++l)
        if (l != j) others = hn::Mul(others, hn::Load(d, h->sines[l] + i));
      const V factor =
          hn::Mul(hn::Mul(hn::Set(d, 2.0 * kPi), hn::Load(d, h->cosines[j] + i)), others);
      g = add3(g, scale3(splat(d, f.terms[j].k), factor));
    }
    store3(d, g, h->gx, h->gy, h->gz, i);
  }
}

// displaced_normal of shape.cpp with kappa1, kappa2 of the shape.
void bump_lanes(D d, double amplitude, double kappa1, double kappa2, HitPacket* h, std::size_t i) {
  const V a = hn::Set(d, amplitude), one = hn::Set(d, 1.0);
  const V ah = hn::Mul(a, hn::Load(d, h->h + i));
  const V c1 = hn::Add(one, hn::Mul(ah, hn::Set(d, kappa1)));
  const V c2 = hn::Add(one, hn::Mul(ah, hn::Set(d, kappa2)));
  const V3 grad = load3(d, h->gx, h->gy, h->gz, i);
  const V3 t1 = load3(d, h->t1x, h->t1y, h->t1z, i), t2 = load3(d, h->t2x, h->t2y, h->t2z, i);
  const V3 n = load3(d, h->nx, h->ny, h->nz, i);
  const V3 v =
      sub3(sub3(scale3(n, hn::Mul(c1, c2)), scale3(t1, hn::Mul(hn::Mul(a, dot3(grad, t1)), c2))),
           scale3(t2, hn::Mul(hn::Mul(a, dot3(grad, t2)), c1)));
  store3(d, normalize3(d, v), h->nsx, h->nsy, h->nsz, i);
}

void copy_normals(D d, HitPacket* h, std::size_t i) {
  store3(d, load3(d, h->nx, h->ny, h->nz, i), h->nsx, h->nsy, h->nsz, i);
}

// occluded() of shape.cpp for a cylinder without caps or a sphere: any root
// in (t_min, t_max), for the cylinder within its height.
hn::Mask<D> occluded_lanes(D d, const VShape& s, bool sphere, const V3& origin, const V3& direction,
                           V t_min, V t_max) {
  const V3 o = s.frame.to_local(sub3(origin, s.center));
  const V3 dir = s.frame.to_local(direction);
  const V r2 = hn::Mul(s.radius, s.radius);
  const Roots roots =
      sphere ? solve_quadratic(d, dot3(dir, dir), dot3(o, dir), hn::Sub(dot3(o, o), r2))
             : solve_quadratic(d, hn::Add(hn::Mul(dir.x, dir.x), hn::Mul(dir.y, dir.y)),
                               hn::Add(hn::Mul(o.x, dir.x), hn::Mul(o.y, dir.y)),
                               hn::Sub(hn::Add(hn::Mul(o.x, o.x), hn::Mul(o.y, o.y)), r2));
  const auto blocks = [&](V t) {
    auto in_range = hn::And(hn::Gt(t, t_min), hn::Lt(t, t_max));
    if (!sphere)
      in_range = hn::And(in_range, hn::Le(hn::Abs(hn::Add(o.z, hn::Mul(t, dir.z))), s.half_height));
    return in_range;
  };
  return hn::And(roots.real, hn::Or(blocks(roots.lo), blocks(roots.hi)));
}

// acos_approx of vec.h, in degrees as the evaluator stores its angles.
V degrees_acos(D d, V x) {
  const V one = hn::Set(d, 1.0), abs_x = hn::Abs(x);
  const V a = hn::IfThenElse(hn::Lt(one, abs_x), one, abs_x);  // std::min(|x|, 1)
  V p = hn::Add(hn::Set(d, 0.0066700901), hn::Mul(a, hn::Set(d, -0.0012624911)));
  for (const double c :
       {-0.0170881256, 0.0308918810, -0.0501743046, 0.0889789874, -0.2145988016, 1.5707963050})
    p = hn::Add(hn::Set(d, c), hn::Mul(a, p));
  const V r = hn::Mul(hn::Sqrt(hn::Sub(one, a)), p);
  const V angle = hn::IfThenElse(hn::Lt(x, hn::Zero(d)), hn::Sub(hn::Set(d, kPi), r), r);
  return hn::Mul(angle, hn::Set(d, 180.0 / kPi));
}

// The light's direction and distance (sample_light of the evaluator), the
// shadow ray, and the angles of the normals turned towards the viewer.
void light_lanes(D d, const VShape& s, bool sphere, const PacketLighting& lighting,
                 const RayPacket& r, HitPacket* h, std::size_t i) {
  const V3 p = load3(d, h->px, h->py, h->pz, i);
  V3 wi = splat(d, lighting.light);
  V distance = hn::Set(d, std::numeric_limits<double>::infinity());
  if (!lighting.distant) {
    const V3 to_light = sub3(wi, p);
    distance = hn::Sqrt(dot3(to_light, to_light));
    wi = scale3(to_light, hn::Div(hn::Set(d, 1.0), distance));
  }
  const auto blocked =
      occluded_lanes(d, s, sphere, p, wi, hn::Set(d, lighting.shadow_t_min), distance);
  hn::Store(hn::IfThenElseZero(blocked, hn::Set(d, 1.0)), d, h->blocked + i);
  const V3 dir = load3(d, r.dx, r.dy, r.dz, i);
  const V3 wo{hn::Neg(dir.x), hn::Neg(dir.y), hn::Neg(dir.z)};
  V3 n = load3(d, h->nx, h->ny, h->nz, i), ns = load3(d, h->nsx, h->nsy, h->nsz, i);
  // Two-sided, as the evaluator turns them.
  const auto flip = hn::Lt(dot3(n, wo), hn::Zero(d));
  n = {hn::IfThenElse(flip, hn::Neg(n.x), n.x), hn::IfThenElse(flip, hn::Neg(n.y), n.y),
       hn::IfThenElse(flip, hn::Neg(n.z), n.z)};
  ns = {hn::IfThenElse(flip, hn::Neg(ns.x), ns.x), hn::IfThenElse(flip, hn::Neg(ns.y), ns.y),
        hn::IfThenElse(flip, hn::Neg(ns.z), ns.z)};
  hn::Store(degrees_acos(d, dot3(n, wi)), d, h->theta + i);
  hn::Store(degrees_acos(d, dot3(ns, n)), d, h->deviation + i);
  hn::Store(degrees_acos(d, dot3(n, wo)), d, h->view + i);
}

}  // namespace

void TracePacket(const Shape& shape, const HeightFunction& height, double amplitude, bool bump,
                 const PacketLighting& lighting, const RayPacket& rays, HitPacket* hits) {
  const D d;
  const std::size_t step = hn::Lanes(d);
  const std::size_t lanes = (rays.count + step - 1) / step * step;
  const VShape s{{splat(d, shape.frame.s), splat(d, shape.frame.t), splat(d, shape.frame.n)},
                 splat(d, shape.center),
                 splat(d, shape.axis),
                 hn::Set(d, shape.radius),
                 hn::Set(d, 0.5 * shape.height),
                 hn::Set(d, 1.0 / shape.radius)};
  const bool sphere = shape.type == ShapeType::kSphere;
  // As cylinder_side and sphere_at_direction set them.
  hits->kappa1 = 1.0 / shape.radius;
  hits->kappa2 = sphere ? 1.0 / shape.radius : 0.0;
  for (std::size_t i = 0; i < lanes; i += step) {
    if (sphere)
      sphere_lanes(d, s, rays, hits, i);
    else
      cylinder_lanes(d, s, rays, hits, i);
  }
  // displaced_normal returns the base normal itself without an amplitude.
  if (!bump || amplitude == 0.0) {
    for (std::size_t i = 0; i < lanes; i += step) copy_normals(d, hits, i);
  } else {
    height_lanes(d, height, hits, lanes);
    for (std::size_t i = 0; i < lanes; i += step)
      bump_lanes(d, amplitude, hits->kappa1, hits->kappa2, hits, i);
  }
  for (std::size_t i = 0; i < lanes; i += step) light_lanes(d, s, sphere, lighting, rays, hits, i);
}

void CameraRays(const PacketCamera& camera, const SamplePacket& samples, RayPacket* rays) {
  const D d;
  const std::size_t step = hn::Lanes(d);
  const V3 position = splat(d, camera.position), direction = splat(d, camera.direction);
  const V3 right = splat(d, camera.right), up = splat(d, camera.up);
  const V nx = hn::Set(d, camera.nx), ny = hn::Set(d, camera.ny), half = hn::Set(d, 0.5);
  const V width = hn::Set(d, camera.width), height = hn::Set(d, camera.height);
  for (std::size_t k = 0; k < rays->count; k += step) {
    const V a = hn::Div(hn::Add(hn::Load(d, samples.sx + k), hn::Load(d, samples.jx + k)), nx);
    const V b = hn::Div(hn::Add(hn::Load(d, samples.sy + k), hn::Load(d, samples.jy + k)), ny);
    const V x0 = hn::Sub(hn::Div(hn::Add(hn::Load(d, samples.i + k), a), width), half);
    const V y0 = hn::Sub(half, hn::Div(hn::Add(hn::Load(d, samples.j + k), b), height));
    V3 origin = position, dir = direction;
    if (camera.perspective)
      dir = normalize3(d, add3(add3(direction, scale3(right, x0)), scale3(up, y0)));
    else
      origin = add3(add3(position, scale3(right, x0)), scale3(up, y0));
    store3(d, origin, rays->ox, rays->oy, rays->oz, k);
    store3(d, dir, rays->dx, rays->dy, rays->dz, k);
  }
}

const char* TargetName() {
  return hwy::TargetName(HWY_TARGET);
}

}  // namespace HWY_NAMESPACE
}  // namespace penumbra
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace penumbra {

HWY_EXPORT(TracePacket);
HWY_EXPORT(TargetName);
HWY_EXPORT(CameraRays);

void camera_rays(const PacketCamera& camera, const SamplePacket& samples, RayPacket* rays) {
  HWY_DYNAMIC_DISPATCH(CameraRays)(camera, samples, rays);
}

const char* packet_target() {
  return HWY_DYNAMIC_DISPATCH(TargetName)();
}

void trace_packet(const Shape& shape, const HeightFunction& height, double amplitude, bool bump,
                  const PacketLighting& lighting, const RayPacket& rays, HitPacket* hits) {
  HWY_DYNAMIC_DISPATCH(TracePacket)(shape, height, amplitude, bump, lighting, rays, hits);
}

bool packet_supports(const Shape& shape) {
  return shape.type == ShapeType::kSphere || (shape.type == ShapeType::kCylinder && !shape.caps);
}

double HitPacket::hit(std::size_t i, SurfaceGeometry* g) const {
  // Field by field: a whole SurfaceGeometry built and copied here cost the
  // evaluator more than the packet (stores forwarded to wider loads stall).
  g->p = {px[i], py[i], pz[i]};
  g->n = {nx[i], ny[i], nz[i]};
  g->t1 = {t1x[i], t1y[i], t1z[i]};
  g->t2 = {t2x[i], t2y[i], t2z[i]};
  g->v = v[i];
  g->u = 0.0;
  g->kappa1 = kappa1;
  g->kappa2 = kappa2;
  g->displaceable = true;
  return t[i];
}

}  // namespace penumbra
#endif
