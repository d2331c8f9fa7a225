// Consistent normal interpolation (Reshetov, Soupikov and Mark, "Consistent
// Normal Interpolation", ACM TOG 29(6), SIGGRAPH Asia 2010): a shading
// normal for smooth-shaded meshes that depends on the view, bent just enough
// that the mirror reflection of any view above the triangle stays above it,
// and continuous across edges because it is built from per-vertex scalars.
//
// Each vertex carries alpha, the largest angle between its normal and the
// normals of the triangles around it (widened for interpolation, below);
// a point interpolates alpha and the vertex normals (Ni) with its
// barycentric weights. The paper's eq. 1 compresses the reflected
// direction's angle from Ni: with b = <wo,Ni>, the reflected direction's
// cosine to Ni becomes g = 1 - q (1 - b), q = (1 - sin alpha) / (1 + sin
// alpha). A view in the triangle's plane (the most grazing one, b >= -sin
// alpha) then reflects to g >= sin alpha, at most 90 degrees - alpha from
// Ni, which is within alpha of Ng: on or above the plane. The normal is the
// half vector of wo and that reflected direction. alpha = 0 (flat
// vertices, or a mesh that converged to its surface) gives q = 1 and Ni.
#pragma once

#include <vector>

#include "core/grid_mesh.h"
#include "core/vec.h"

namespace penumbra {

// The paper's q(alpha) (eq. 1), alpha in radians, [0, pi/2].
double consistent_normal_q(double alpha);

// The consistent normal at a point seen from direction wo (unit, towards the
// viewer, on Ni's side of the triangle), Ni the unit interpolated normal and
// alpha the interpolated per-vertex angle (radians).
Vec3 consistent_normal(const Vec3& wo, const Vec3& ni, double alpha);

// Per-vertex alpha of a mesh with vertex normals: the largest angle between
// the vertex normal and the normals of its triangles (taken on the vertex
// normals' side), times (1 + 0.03632 (1 - cos)^2), the widening the paper's
// listing applies so that the barycentric interpolation of alpha bounds the
// angle of the interpolated normal (as in jbikker/lighthouse2 e61e65444d8e
// lib/RenderSystem/host_mesh.cpp). Radians, capped at pi/2.
std::vector<double> consistent_normal_alphas(const TriangleMesh& mesh);

}  // namespace penumbra
