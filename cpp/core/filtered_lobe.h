// The lobes a roughness filter hands to shading (roughness_filter.h),
// evaluated: anisotropic GGX and Beckmann with a full slope-space alpha^2
// tensor A (Heitz 2014, "Understanding the Masking-Shadowing Function",
// sec. 5: elliptical slope distributions and their projected roughness),
// height-correlated Smith masking-shadowing, Fresnel left out (F = 1) as in
// bsdf.h. Directions are unit vectors in the lobe's frame (z = the normal).
#pragma once

#include "core/roughness_filter.h"
#include "core/vec.h"

namespace penumbra {

// Slope-space density P22 at slope s = (-m.x / m.z, -m.y / m.z), 1/slope^2.
double slope_density(FilteredDistribution distribution, const Covariance2& alpha2, double s_x,
                     double s_y);
// D(m) = P22 / cos^4(theta_m), 1/sr; 0 for m.z <= 0.
double lobe_d(FilteredDistribution distribution, const Covariance2& alpha2, const Vec3& m);
// Smith's Lambda for direction w with the projected roughness
// alpha_w^2 = phi^T A phi, phi the unit azimuth of w.
double lobe_lambda(FilteredDistribution distribution, const Covariance2& alpha2, const Vec3& w);
// D G2 / (4 cos_i cos_o), 1/sr; 0 where either direction is below the
// surface. kSchillingBlinnPhong has no normalised form in its source and is
// refused (std::invalid_argument).
double lobe_brdf(FilteredDistribution distribution, const Covariance2& alpha2, const Vec3& wi,
                 const Vec3& wo);

}  // namespace penumbra
