// Schuessler, Heitz, Hanika, Dachsbacher 2017, "Microfacet-based Normal
// Mapping for Robust Monte Carlo Path Tracing", ACM TOG 36(6): the bumped
// normal becomes a microsurface of two facets, the perturbed facet wp (the
// base BSDF) and a tangent facet wt perpendicular to Ng (a perfect mirror),
// with the projected areas that make it a height field. Reference sheet,
// section 2; README's method table cites the source read.
//
// All functions work in any orthonormal space with unit vectors; `ng` is the
// macro-surface normal. Values are "throughputs": reflected radiance per
// unit irradiance normal to the light direction, i.e. the microsurface BSDF
// times <l,Ng> (1/sr).
#pragma once

#include "core/bsdf.h"
#include "core/random.h"
#include "core/vec.h"

namespace penumbra {

// The microsurface of one shading point.
struct MicrosurfaceFacets {
  Vec3 ng;          // macro normal
  Vec3 wp;          // perturbed facet (the bumped normal)
  Vec3 wt;          // tangent facet: -(wp's part across ng), normalised
  double cos_p;     // <wp,Ng>
  double sin_p;     // sqrt(1 - <wp,Ng>^2)
  bool degenerate;  // wp == Ng (no tangent facet) or wp at or below the horizon
};

MicrosurfaceFacets make_facets(const Vec3& ng, const Vec3& wp);

// Projected areas of the facets seen from w, per unit macro-surface area.
double projected_area_p(const MicrosurfaceFacets& f, const Vec3& w);  // <w,wp>/<wp,Ng>
double projected_area_t(const MicrosurfaceFacets& f, const Vec3& w);  // <w,wt> sin/cos
// Probability that a ray arriving from w meets facet p first.
double lambda_p(const MicrosurfaceFacets& f, const Vec3& w);
// Masking of a ray leaving facet wm towards w: [<w,wm> > 0] min(1, <w,Ng>/(ap+at)).
double schuessler_g1(const MicrosurfaceFacets& f, const Vec3& w, const Vec3& wm);
// w mirrored on the tangent facet's plane.
Vec3 mirror_on_tangent(const MicrosurfaceFacets& f, const Vec3& w);

// The base material on facet p, as the evaluator's lobes (both sides checked).
double facet_throughput(const Material& m, const Vec3& wp, const Vec3& l, const Vec3& v);

// Light from l, viewer at v. The explicit evaluation with a mirror tangent
// facet: paths v->p->l, v->p->t->l and v->t->p->l.
double schuessler2017(const Material& m, const Vec3& ng, const Vec3& wp, const Vec3& l,
                      const Vec3& v);
// The plain bumped BSDF times the tangent facet's shadowing G1(l, wp), no
// inter-reflection: the variant Chiang et al. 2019 call overly dark (their
// Fig. 3c: light along Ns is shadowed, by cos^2 of the deviation).
double schuessler2017_shadowing(const Material& m, const Vec3& ng, const Vec3& wp, const Vec3& l,
                                const Vec3& v);
// The walk's default cap on visits of facet p; the walk's tail beyond it
// carries less than albedo^16 of the energy (below 3e-2 at albedo 0.8).
inline constexpr int kSchuesslerWalkVisits = 16;

// One sample of the random walk between the facets, with next-event
// estimation of the (delta) light at every visit of facet p; unbiased for
// paths with at most `max_p_visits` visits of p. Cosine-weighted sampling on
// p works for both lobes of the base material.
double schuessler2017_walk(const Material& m, const Vec3& ng, const Vec3& wp, const Vec3& l,
                           const Vec3& v, Pcg32& rng, int max_p_visits = kSchuesslerWalkVisits);
}  // namespace penumbra
