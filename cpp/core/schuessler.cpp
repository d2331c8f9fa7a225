#include "core/schuessler.h"

#include <algorithm>
#include <cmath>

namespace penumbra {
namespace {

// Below this <wp,Ng> the perturbed facet is vertical: its area per unit
// macro-surface grows without bound and its visible share vanishes.
constexpr double kMinCosP = 1e-9;
// Below this sine the tangent facet has no direction: wp == Ng.
constexpr double kMinSinP = 1e-12;

// The plain base BSDF around ng times <l,ng>: what the microsurface reduces
// to without a perturbation.
double plain_throughput(const Material& m, const Vec3& ng, const Vec3& l, const Vec3& v) {
  return facet_throughput(m, ng, l, v);
}

// The microsurface lies in the macro-surface: light and viewer below it
// see nothing of it (the ports return 0 there too).
bool sees_macro_surface(const Vec3& ng, const Vec3& l, const Vec3& v) {
  return dot(ng, l) > 0.0 && dot(ng, v) > 0.0;
}

Vec3 cosine_sample(const Vec3& n, Pcg32& rng) {
  const double u1 = rng.next_double(), u2 = rng.next_double();
  const double r = std::sqrt(u1), phi = 2.0 * kPi * u2;
  const double z = std::sqrt(std::max(0.0, 1.0 - u1));
  return Frame::from_z(n).to_world({r * std::cos(phi), r * std::sin(phi), z});
}

}  // namespace

MicrosurfaceFacets make_facets(const Vec3& ng, const Vec3& wp) {
  MicrosurfaceFacets f;
  f.ng = ng;
  f.wp = wp;
  f.cos_p = std::min(dot(wp, ng), 1.0);
  const Vec3 across = wp - ng * f.cos_p;
  f.sin_p = length(across);
  f.degenerate = !(f.cos_p > kMinCosP) || !(f.sin_p > kMinSinP);
  f.wt = f.degenerate ? Vec3{} : -across / f.sin_p;
  return f;
}

double projected_area_p(const MicrosurfaceFacets& f, const Vec3& w) {
  return clamped_dot(w, f.wp) / f.cos_p;
}

double projected_area_t(const MicrosurfaceFacets& f, const Vec3& w) {
  return clamped_dot(w, f.wt) * f.sin_p / f.cos_p;
}

double lambda_p(const MicrosurfaceFacets& f, const Vec3& w) {
  const double ap = projected_area_p(f, w), at = projected_area_t(f, w);
  return ap + at > 0.0 ? ap / (ap + at) : 0.0;
}

double schuessler_g1(const MicrosurfaceFacets& f, const Vec3& w, const Vec3& wm) {
  if (!(dot(w, wm) > 0.0)) return 0.0;
  const double area = projected_area_p(f, w) + projected_area_t(f, w);
  // Below the macro-surface every ray is blocked.
  return area > 0.0 ? std::clamp(dot(w, f.ng) / area, 0.0, 1.0) : 0.0;
}

Vec3 mirror_on_tangent(const MicrosurfaceFacets& f, const Vec3& w) {
  return w - f.wt * (2.0 * dot(w, f.wt));
}

double facet_throughput(const Material& m, const Vec3& wp, const Vec3& l, const Vec3& v) {
  // A facet is one-sided: light and viewer must both see its front.
  if (!(dot(wp, v) > 0.0)) return 0.0;
  const double cos_l = dot(wp, l);
  if (!(cos_l > 0.0)) return 0.0;
  const LobeValues lobes = evaluate_lobes(m, wp, l, v);
  return (lobes.diffuse + lobes.specular) * cos_l;
}

double schuessler2017_shadowing(const Material& m, const Vec3& ng, const Vec3& wp, const Vec3& l,
                                const Vec3& v) {
  if (!sees_macro_surface(ng, l, v)) return 0.0;
  const MicrosurfaceFacets f = make_facets(ng, wp);
  if (f.degenerate) return f.cos_p > kMinCosP ? plain_throughput(m, ng, l, v) : 0.0;
  // The bumped BSDF as it is (no masking of the viewer), times the tangent
  // facet's shadowing of the light.
  const double cos_l = dot(wp, l);
  if (!(cos_l > 0.0)) return 0.0;
  const LobeValues lobes = evaluate_lobes(m, wp, l, v);
  return (lobes.diffuse + lobes.specular) * cos_l * schuessler_g1(f, l, wp);
}

double schuessler2017(const Material& m, const Vec3& ng, const Vec3& wp, const Vec3& l,
                      const Vec3& v) {
  if (!sees_macro_surface(ng, l, v)) return 0.0;
  const MicrosurfaceFacets f = make_facets(ng, wp);
  if (f.degenerate) return f.cos_p > kMinCosP ? plain_throughput(m, ng, l, v) : 0.0;
  const double lp = lambda_p(f, v);
  // v -> p -> l
  double value = lp * facet_throughput(m, wp, l, v) * schuessler_g1(f, l, wp);
  // v -> p -> t -> l: p sends light towards the mirror image l' of l, the
  // tangent facet blocks it (1 - G1) and mirrors it out towards l.
  const Vec3 l_mirrored = mirror_on_tangent(f, l);
  value += lp * facet_throughput(m, wp, l_mirrored, v) * (1.0 - schuessler_g1(f, l_mirrored, wp)) *
           schuessler_g1(f, l, f.wt);
  // v -> t -> p -> l: the mirror keeps the ray's downward course, so it
  // meets p for certain, seen from the mirror image v' of v.
  const Vec3 v_mirrored = mirror_on_tangent(f, v);
  value += (1.0 - lp) * facet_throughput(m, wp, l, v_mirrored) * schuessler_g1(f, l, wp);
  return value;
}

double schuessler2017_walk(const Material& m, const Vec3& ng, const Vec3& wp, const Vec3& l,
                           const Vec3& v, Pcg32& rng, int max_p_visits) {
  if (!sees_macro_surface(ng, l, v)) return 0.0;
  const MicrosurfaceFacets f = make_facets(ng, wp);
  if (f.degenerate) return f.cos_p > kMinCosP ? plain_throughput(m, ng, l, v) : 0.0;
  const Vec3 l_mirrored = mirror_on_tangent(f, l);
  const double g1_l_p = schuessler_g1(f, l, wp);
  const double via_t = (1.0 - schuessler_g1(f, l_mirrored, wp)) * schuessler_g1(f, l, f.wt);
  // The direction back along the ray at the current visit of p.
  Vec3 seen_from = rng.next_double() < lambda_p(f, v) ? v : mirror_on_tangent(f, v);
  double throughput = 1.0, value = 0.0;
  for (int visit = 0; visit < max_p_visits; ++visit) {
    if (!(dot(seen_from, wp) > 0.0)) break;
    // Next-event estimation: the light reaches p directly or off the mirror.
    value += throughput * (facet_throughput(m, wp, l, seen_from) * g1_l_p +
                           facet_throughput(m, wp, l_mirrored, seen_from) * via_t);
    // Continue: cosine sampling on p, weight f cos / pdf = pi f.
    const Vec3 d = cosine_sample(wp, rng);
    const LobeValues lobes = evaluate_lobes(m, wp, d, seen_from);
    throughput *= kPi * (lobes.diffuse + lobes.specular);
    if (!(throughput > 0.0) || rng.next_double() < schuessler_g1(f, d, wp)) break;
    // Blocked: the ray meets the tangent facet and is mirrored; it leaves
    // the surface, or meets p again.
    const Vec3 d_mirrored = mirror_on_tangent(f, d);
    if (rng.next_double() < schuessler_g1(f, d_mirrored, f.wt)) break;
    seen_from = -d_mirrored;
  }
  return value;
}

}  // namespace penumbra
