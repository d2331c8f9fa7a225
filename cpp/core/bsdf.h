// Material lobes in the shading frame of Ns. Values are BSDF values (1/sr).
#pragma once

#include "core/roughness_filter.h"
#include "core/vec.h"

namespace penumbra {

// A specular lobe widened by a roughness filter (roughness_filter.h) for
// one shading point: replaces the isotropic GGX of specular_roughness with
// `alpha2` in the frame (tangent projected onto Ns, Ns x that, Ns).
struct FilteredSpecular {
  bool active = false;
  FilteredDistribution distribution = FilteredDistribution::kGgx;
  Covariance2 alpha2;
  Vec3 tangent;
};

// Diffuse albedo plus an optional GGX specular lobe. Fresnel is left out
// (F = 1) on purpose: the lobe exists so that a study can choose whether a
// terminator factor touches specular light, not to model a real material.
struct Material {
  double albedo = 0.8;              // diffuse reflectance, [0,1]
  double specular_weight = 0.0;     // [0,1]; diffuse is scaled by 1 - weight
  double specular_roughness = 0.3;  // GGX alpha, (0,1]
  FilteredSpecular filtered;        // set per sample by a filtered map, never by a scene
};

// GGX normal distribution D(m) for cos_theta_m = dot(m, n) (Walter et al. 2007).
double ggx_d(double cos_theta_m, double alpha);
// Height-correlated Smith masking-shadowing (Heitz 2014) for unit cosines.
double ggx_g2(double cos_theta_i, double cos_theta_o, double alpha);

struct LobeValues {
  double diffuse = 0.0;   // BSDF value of the diffuse lobe, 1/sr
  double specular = 0.0;  // BSDF value of the specular lobe, 1/sr
};

// Both lobes for directions wi, wo (unit) around the shading normal ns.
// Zero where wi lies below ns; the specular lobe also where wo does.
LobeValues evaluate_lobes(const Material& m, const Vec3& ns, const Vec3& wi, const Vec3& wo);

}  // namespace penumbra
