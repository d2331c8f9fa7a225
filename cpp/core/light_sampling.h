// Sampling directions towards area lights, as a Monte Carlo estimator of
// direct light needs them: each sample carries its direction, its density
// per steradian and the distance a shadow ray must clear. Pure math.
//
// The estimator of the light a shading point receives from an emitter of
// uniform radiance L is  f(wi) cos(wi) L / pdf(wi),  so a sample's weight
// L / pdf is an irradiance (W/m^2 on a plane facing wi).
#pragma once

#include <cstdint>

#include "core/vec.h"

namespace penumbra {

struct LightDirectionSample {
  Vec3 wi;                // unit, from the shading point towards the emitter
  double pdf = 0.0;       // per steradian; 0: no direction reaches the emitter
  double distance = 0.0;  // from the shading point to the emitting surface, scene units
};

// Uniform over the cone of directions the sphere (centre, radius) subtends
// at p (pbrt-v4 section 6.2.4's cone sampling; Shirley et al. 1996):
// pdf = 1 / (2 pi (1 - cos theta_max)), sin theta_max = radius / |centre - p|.
// (u1, u2) in [0,1)^2. A point on or inside the sphere gets pdf 0.
LightDirectionSample sample_sphere_light(const Vec3& centre, double radius, const Vec3& p,
                                         double u1, double u2);

// The solid angle (sr) the sphere subtends at p: 2 pi (1 - cos theta_max);
// 0 inside it.
double sphere_solid_angle(const Vec3& centre, double radius, const Vec3& p);

// A parallelogram corner + a edge_u + b edge_v, (a, b) in [0,1]^2, that
// emits on one side only: the side edge_u x edge_v points to (the usual
// component formula of the cross product). Uniform by area, turned into a
// density per steradian: pdf = d^2 / (area cos theta_l), where theta_l is
// the angle at the emitter. Behind the emitting side: pdf 0.
LightDirectionSample sample_quad_light(const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v,
                                       const Vec3& p, double u1, double u2);

// The density sample_sphere_light draws the unit direction wi with at p,
// and the distance along wi to the sphere: pdf 0 where wi misses it (the
// cone it subtends is exactly the directions that hit it) or p is inside.
// For multiple importance sampling, where another strategy drew wi.
LightDirectionSample sphere_light_pdf(const Vec3& centre, double radius, const Vec3& p,
                                      const Vec3& wi);

// The density sample_quad_light draws the unit direction wi with at p
// (d^2 / (area cos theta_l) at the point wi hits), and its distance: pdf 0
// where wi misses the parallelogram or reaches it from behind.
LightDirectionSample quad_light_pdf(const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v,
                                    const Vec3& p, const Vec3& wi);

// A quad light as the evaluator samples it: where its edges are orthogonal
// (a rectangle, to 1e-9 of |edge_u| |edge_v|) and it subtends at least
// kMinSphericalRectangle sr at p, uniformly in solid angle by the
// area-preserving map of the spherical rectangle (Urena, Fajardo and King
// 2013, "An Area-Preserving Parametrization for Spherical Rectangles", EGSR;
// as pbrt-v4's SampleSphericalRectangle): pdf = 1 / solid angle. Elsewhere,
// and for a parallelogram, by area as sample_quad_light. One-sided: behind
// the emitting side, pdf 0.
inline constexpr double kMinSphericalRectangle = 3e-4;  // sr; below, the angles cancel
LightDirectionSample sample_rectangle_light(const Vec3& corner, const Vec3& edge_u,
                                            const Vec3& edge_v, const Vec3& p, double u1,
                                            double u2);
// Its density at the unit direction wi, and the distance there; 0 where wi
// misses the quad or reaches it from behind.
LightDirectionSample rectangle_light_pdf(const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v,
                                         const Vec3& p, const Vec3& wi);
// The solid angle (sr) a rectangle subtends at p, from its spherical
// rectangle's angles (Girard's theorem); 0 on its plane.
double rectangle_solid_angle(const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v,
                             const Vec3& p);

// A cosine-weighted direction about the unit normal n, (u1, u2) in [0,1)^2
// (Malley's method: a uniform point of the unit disk lifted onto the
// hemisphere; pbrt-v4 section A.5.3), and its density cos / pi per
// steradian (0 below the plane of n).
Vec3 sample_cosine_direction(const Vec3& n, double u1, double u2);
double cosine_direction_pdf(const Vec3& n, const Vec3& wi);

// The irradiance (W/m^2) at p on a plane of unit normal n from a convex
// planar polygon of uniform radiance L, wholly above that plane and facing
// p (Lambert 1760; the contour-integral form, e.g. Arvo 1995 eq. 2):
//   E = L/2 sum_i  gamma_i  n . (r_i x r_{i+1}) / |r_i x r_{i+1}|
// with r_i = v_i - p and gamma_i the angle between r_i and r_{i+1}. The
// vertices go round the polygon so that the sum is positive for a polygon
// above the plane; either order works (the absolute value is taken).
double polygon_irradiance(const Vec3* vertices, int count, const Vec3& p, const Vec3& n,
                          double radiance);

// The same polygon's vector irradiance at p (Gershun's light vector,
// W/m^2): the integral of L w dw over the directions w it subtends, by
// Stokes' theorem  L/2 sum_i gamma_i (r_i x r_{i+1}) / |r_i x r_{i+1}|
// (Arvo 1995, eq. 2 before its dot product with n), turned to point from p
// towards the polygon's plane. n . it is polygon_irradiance for any n the
// whole polygon is above. Zero for p in the polygon's plane.
Vec3 polygon_light_vector(const Vec3* vertices, int count, const Vec3& p, double radiance);

// A bijection of [0, n), n >= 1, chosen by `seed`: an invertible hash on
// the next power of two, walked until it lands below n (the cycle-walking
// construction of Kensler 2013, "Correlated multi-jittered sampling",
// Pixar Technical Memo 13-01). It shuffles a pixel's light strata so that
// they are stratified without following the camera's strata.
std::uint32_t permute_index(std::uint32_t i, std::uint32_t n, std::uint32_t seed);

}  // namespace penumbra
