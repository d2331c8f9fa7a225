#include "core/shading.h"

#include "core/schuessler.h"

namespace penumbra {

NormalAdjustment effective_adjustment(const TerminatorSettings& t) {
  const NormalAdjustment own = method_info(t.method.method).adjustment;
  return own != NormalAdjustment::kNone ? own : t.normal_adjustment;
}

double unshadowed_value(const Material& m, const Vec3& ns, const Vec3& wi, const Vec3& wo) {
  const double cos_theta_s = dot(ns, wi);
  if (!(cos_theta_s > 0.0)) return 0.0;
  const LobeValues lobes = evaluate_lobes(m, ns, wi, wo);
  return (lobes.diffuse + lobes.specular) * cos_theta_s;
}

double factor_scaled_value(const Material& m, const Vec3& ns, const Vec3& wi, const Vec3& wo,
                           Lobes lobes) {
  const double cos_theta_s = dot(ns, wi);
  if (!(cos_theta_s > 0.0)) return 0.0;
  const LobeValues values = evaluate_lobes(m, ns, wi, wo);
  return (lobes == Lobes::kAll ? values.diffuse + values.specular : values.diffuse) * cos_theta_s;
}

namespace {

Shaded effective(double value, const Material& m, const ShadingPoint& p) {
  const double raw = unshadowed_value(m, p.ns, p.wi, p.wo);
  return raw > 0.0 ? Shaded{value, value / raw, true} : Shaded{value, 0.0, false};
}

double microfacet_value(TerminatorMethod method, const Material& m, const Vec3& ng,
                        const ShadingPoint& p, Pcg32* rng) {
  switch (method) {
    case TerminatorMethod::kSchuessler2017:
      return schuessler2017(m, ng, p.ns, p.wi, p.wo);
    case TerminatorMethod::kSchuessler2017Shadowing:
      return schuessler2017_shadowing(m, ng, p.ns, p.wi, p.wo);
    case TerminatorMethod::kSchuessler2017Walk: {
      // Without a generator (contour plots) the walk is averaged over a
      // fixed-seed batch, so that it stays a deterministic function.
      if (rng) return schuessler2017_walk(m, ng, p.ns, p.wi, p.wo, *rng);
      Pcg32 local(0x5c4e55);
      constexpr int kSamples = 4096;
      double sum = 0.0;
      for (int k = 0; k < kSamples; ++k) sum += schuessler2017_walk(m, ng, p.ns, p.wi, p.wo, local);
      return sum / kSamples;
    }
    default:
      return 0.0;
  }
}

// The lobes around their (possibly adjusted) normals, each scaled by the
// factor where the factor applies to it.
double lobe_value(const Material& m, const AdjustedNormals& a, const ShadingPoint& p,
                  double diffuse_factor, double specular_factor) {
  double value = 0.0;
  const double cos_d = dot(a.ns_diffuse, p.wi);
  if (cos_d > 0.0 && !(a.reject_diffuse && a.reject_specular)) {
    const LobeValues lobes = evaluate_lobes(m, a.ns_diffuse, p.wi, p.wo);
    if (!a.reject_diffuse) value += lobes.diffuse * diffuse_factor * cos_d;
    if (!a.reject_specular && a.ns_specular == a.ns_diffuse)
      value += lobes.specular * specular_factor * cos_d;
  }
  if (!a.reject_specular && a.ns_specular != a.ns_diffuse && m.specular_weight > 0.0) {
    const double cos_s = dot(a.ns_specular, p.wi);
    if (cos_s > 0.0)
      value += evaluate_lobes(m, a.ns_specular, p.wi, p.wo).specular * specular_factor * cos_s;
  }
  return value;
}

}  // namespace

Shaded shade(const TerminatorSettings& t, const Material& m, const ShadingPoint& p, Pcg32* rng) {
  const MethodInfo& info = method_info(t.method.method);
  const bool use_ni = info.reference_is_ni || t.reference_normal == ReferenceNormal::kInterpolated;
  const Vec3& ng_ref = use_ni ? p.ni : p.ng;
  if (info.kind == MethodKind::kMicrofacet)
    return effective(microfacet_value(info.method, m, ng_ref, p, rng), m, p);
  const NormalAdjustment adjustment = effective_adjustment(t);
  const AdjustedNormals a = adjust_normal(adjustment, p);
  // The factor sees the normal the diffuse lobe is shaded with.
  const double factor = terminator_factor(t.method, ng_ref, a.ns_diffuse, p.wi, p.wo, p.visibility);
  const bool on_specular = info.lobes == FactorLobes::kAll ||
                           (info.lobes == FactorLobes::kScene && t.lobes == Lobes::kAll);
  const double value = lobe_value(m, a, p, factor, on_specular ? factor : 1.0);
  if (adjustment == NormalAdjustment::kNone) return {value, factor, true};
  return effective(value, m, p);
}

}  // namespace penumbra
