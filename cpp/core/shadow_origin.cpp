#include "core/shadow_origin.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace penumbra {

namespace {

constexpr MethodParameter kEpsilonParameters[] = {
    {"distance", "scene units", 1e-9, 1e3, 0.01,
     "how far the origin moves along the geometric normal Ng"},
};
constexpr MethodParameter kCyclesParameters[] = {
    {"cutoff", "dimensionless (a cosine)", 0.0, 1.0, 0.1,
     "Cycles' object Geometry Offset: the full offset applies while dot(Ng, wi) < cutoff/2 and "
     "fades out at dot(Ng, wi) = cutoff; 0 disables it"},
};

constexpr MethodParameter kOsprayParameters[] = {
    {"ulp", "dimensionless (relative)", 0.0, 1e-3, 0x1.0fp-21,
     "OSPRay's ulpEpsilon: the offset is ulp times the largest coordinate magnitude of the "
     "triangle's vertices and the hit point"},
};

constexpr MethodParameter kPhongParameters[] = {
    {"alpha", "dimensionless", 0.0, 1.0, 0.75,
     "Phong tessellation's shape factor: 0 the flat triangle, 1 the full quadratic patch; "
     "Boubekeur and Alexa recommend 3/4"},
};

constexpr std::array<OffsetMethodInfo, 7> kOffsetMethods{{
    {OffsetMethod::kNone,
     "none",
     "-",
     "the hit point on the flat triangle (the triangle itself is skipped)",
     {}},
    {OffsetMethod::kEpsilon, "epsilon", "common hack",
     "P + distance * Ng: one fixed lift everywhere", kEpsilonParameters},
    {OffsetMethod::kGist2020,
     "gist2020",
     "pixnblox gist (2020), shared/seeds",
     "mean of P's projections onto the vertices' tangent planes, where that lies above P "
     "(convex patch); P elsewhere",
     {}},
    {OffsetMethod::kHanika2021,
     "hanika2021",
     "Hanika, \"Hacking the Shadow Terminator\", Ray Tracing Gems II ch. 4",
     "P lifted only towards the tangent planes it lies below; crack-free along shared edges",
     {}},
    {OffsetMethod::kCyclesGeometryOffset, "cycles-geometry-offset",
     "Blender Cycles 3.x object \"Geometry Offset\"",
     "parabolic surface through the vertices, clamped by a linear envelope, applied near the "
     "triangle's horizon",
     kCyclesParameters},
    {OffsetMethod::kOspray, "ospray",
     "RenderKit/ospray 675c216b91a7 modules/cpu/render/pathtracer/NextEventEstimation.ispc "
     "(org - 2 epsilon Ng where dot(Ng, dir) < 0) after common/World.ih postIntersect "
     "(P + epsilon Ng)",
     "P + epsilon Ng for a light on Ng's side, P - epsilon Ng for a light below it; epsilon "
     "relative to the coordinates' magnitude",
     kOsprayParameters},
    {OffsetMethod::kPhong2008, "phong2008",
     "Boubekeur and Alexa, \"Phong Tessellation\", ACM TOG 27(5), SIGGRAPH Asia 2008, "
     "eq. 3-4",
     "P moved onto the Phong surface: (1 - alpha) P + alpha times the barycentric mean of P's "
     "projections onto the vertices' tangent planes, convex or not",
     kPhongParameters},
}};

}  // namespace

std::span<const OffsetMethodInfo> all_offset_methods() {
  return kOffsetMethods;
}

const OffsetMethodInfo& offset_method_info(OffsetMethod method) {
  for (const OffsetMethodInfo& info : kOffsetMethods)
    if (info.method == method) return info;
  return kOffsetMethods[0];
}

double* offset_parameter(OffsetSettings* settings) {
  switch (settings->method) {
    case OffsetMethod::kEpsilon:
      return &settings->epsilon;
    case OffsetMethod::kCyclesGeometryOffset:
      return &settings->cutoff;
    case OffsetMethod::kOspray:
      return &settings->ulp;
    case OffsetMethod::kPhong2008:
      return &settings->alpha;
    case OffsetMethod::kNone:
    case OffsetMethod::kGist2020:
    case OffsetMethod::kHanika2021:
      return nullptr;
  }
  return nullptr;
}

const double* offset_parameter(const OffsetSettings& settings) {
  return offset_parameter(const_cast<OffsetSettings*>(&settings));
}

std::optional<OffsetMethod> offset_method_from_id(std::string_view id) {
  for (const OffsetMethodInfo& info : kOffsetMethods)
    if (info.id == id) return info.method;
  return std::nullopt;
}

Vec3 gist2020_origin(const ShadingTriangle& t, const Vec3& p, const Vec3& ns) {
  Vec3 s;
  for (int k = 0; k < 3; ++k) s += (p - t.n[k] * dot(p - t.v[k], t.n[k])) * t.b[k];
  return dot(s - p, ns) > 0.0 ? s : p;
}

Vec3 hanika2021_origin(const ShadingTriangle& t, const Vec3& p) {
  Vec3 lifted = p;
  for (int k = 0; k < 3; ++k) lifted += t.n[k] * (-t.b[k] * std::min(0.0, dot(p - t.v[k], t.n[k])));
  return lifted;
}

Vec3 phong2008_origin(const ShadingTriangle& t, const Vec3& p, double alpha) {
  Vec3 projected;
  for (int k = 0; k < 3; ++k) projected += (p - t.n[k] * dot(p - t.v[k], t.n[k])) * t.b[k];
  return p * (1.0 - alpha) + projected * alpha;
}

double ospray_epsilon(const ShadingTriangle& t, const Vec3& p, double ulp) {
  auto largest = [](const Vec3& v) {
    return std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
  };
  double magnitude = largest(p);
  for (const Vec3& v : t.v) magnitude = std::max(magnitude, largest(v));
  return ulp * magnitude;
}

Vec3 ospray_origin(const Vec3& p, const Vec3& ng, const Vec3& wi, double epsilon) {
  const Vec3 lifted = p + ng * epsilon;
  // Below Ng the ray must start on the far side, where the light is.
  return dot(ng, wi) < 0.0 ? lifted - ng * (2.0 * epsilon) : lifted;
}

Vec3 cycles_smooth_surface_offset(const CyclesTriangle& t, const Vec3& ng) {
  const Vec3* v = t.v;
  const Vec3* n = t.n;
  const double u = t.u, w1 = t.v_weight, w2 = 1.0 - u - w1;
  const Vec3 p = v[0] * u + v[1] * w1 + v[2] * w2;
  const Vec3 normal = n[0] * u + n[1] * w1 + n[2] * w2;  // unnormalised, as in Cycles
  // Parabolic approximation: zero at the vertices, its edge coefficients from
  // how the normals turn along each edge.
  const double a = dot(n[2] - n[0], v[0] - v[2]);
  const double b = dot(n[2] - n[1], v[1] - v[2]);
  const double c = dot(n[1] - n[0], v[1] - v[0]);
  double h = a * u * (u - 1.0) + (a + b + c) * u * w1 + b * w1 * (w1 - 1.0);
  if (dot(normal, ng) > 0.0) {
    double e[3];
    for (int k = 0; k < 3; ++k) {
      const Vec3& o1 = v[(k + 1) % 3];
      const Vec3& o2 = v[(k + 2) % 3];
      const double reach = std::max({dot(o1 - v[k], n[k]), dot(o2 - v[k], n[k]), 0.0});
      e[k] = std::max(dot(v[k] - p, n[k]) + reach, 0.0);
    }
    h = std::max(std::min({e[0], e[1], e[2]}), 0.5 * h);
  } else {  // the stored normals face away from Ng: Cycles mirrors the envelope
    double e[3];
    for (int k = 0; k < 3; ++k) {
      const Vec3& o1 = v[(k + 1) % 3];
      const Vec3& o2 = v[(k + 2) % 3];
      const double reach = std::max({dot(v[k] - o1, n[k]), dot(v[k] - o2, n[k]), 0.0});
      e[k] = std::max(dot(p - v[k], n[k]) + reach, 0.0);
    }
    h = std::min(-std::min({e[0], e[1], e[2]}), 0.5 * h);
  }
  return normal * h;
}

double cycles_offset_amount(double cutoff, double nl, double ngl) {
  if (!(cutoff > 0.0)) return 0.0;
  const double amount = nl < cutoff ? 2.0 - (ngl + nl) / cutoff : 1.0 - ngl / cutoff;
  return std::clamp(amount, 0.0, 1.0);
}

ShadowOrigin shadow_ray_origin(const OffsetSettings& settings, const ShadowQuery& q) {
  const double ngl = dot(q.ng, q.wi);
  auto lifted = [&](const Vec3& origin) { return ShadowOrigin{origin, ngl > 0.0}; };
  switch (settings.method) {
    case OffsetMethod::kNone:
      return {q.p, true};
    case OffsetMethod::kEpsilon:
      return lifted(q.p + q.ng * settings.epsilon);
    case OffsetMethod::kGist2020: {
      const Vec3 s = gist2020_origin(q.triangle, q.p, q.ns);
      return s == q.p ? ShadowOrigin{q.p, true} : lifted(s);
    }
    case OffsetMethod::kHanika2021: {
      const Vec3 s = hanika2021_origin(q.triangle, q.p);
      return s == q.p ? ShadowOrigin{q.p, true} : lifted(s);
    }
    case OffsetMethod::kCyclesGeometryOffset: {
      // Cycles: N and Ng are flipped towards the viewer, the vertex normals
      // are not; a light behind N mirrors Ng (transmission).
      double nl = dot(q.ns, q.wi);
      const bool transmit = nl < 0.0;
      nl = std::abs(nl);
      const Vec3 ng = transmit ? -q.ng : q.ng;
      const double cycles_ngl = dot(ng, q.wi);
      const double amount = cycles_offset_amount(settings.cutoff, nl, cycles_ngl);
      if (!(amount > 0.0)) return {q.p, true};
      CyclesTriangle t;
      for (int k = 0; k < 3; ++k) {
        t.v[k] = q.triangle.v[k];
        t.n[k] = q.backfacing ? -q.triangle.n[k] : q.triangle.n[k];
      }
      t.u = q.triangle.b[0];
      t.v_weight = q.triangle.b[1];
      return {q.p + cycles_smooth_surface_offset(t, ng) * amount, cycles_ngl > 0.0};
    }
    case OffsetMethod::kOspray:
      return lifted(ospray_origin(q.p, q.ng, q.wi, ospray_epsilon(q.triangle, q.p, settings.ulp)));
    case OffsetMethod::kPhong2008: {
      const Vec3 s = phong2008_origin(q.triangle, q.p, settings.alpha);
      return s == q.p ? ShadowOrigin{q.p, true} : lifted(s);
    }
  }
  return {q.p, true};
}

}  // namespace penumbra
