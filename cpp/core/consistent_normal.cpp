#include "core/consistent_normal.h"

#include <algorithm>
#include <cmath>

namespace penumbra {

double consistent_normal_q(double alpha) {
  const double s = std::sin(std::clamp(alpha, 0.0, 0.5 * kPi));
  return (1.0 - s) / (1.0 + s);
}

Vec3 consistent_normal(const Vec3& wo, const Vec3& ni, double alpha) {
  if (alpha <= 0.0) return ni;
  const double q = consistent_normal_q(alpha);
  const double b = dot(wo, ni);
  const double g = 1.0 - q * (1.0 - b);
  // wo opposite Ni (b = -1) is below every triangle the bound covers; the
  // guard keeps the square root finite there.
  const double rho = std::sqrt(q * (1.0 + g) / std::max(1.0 + b, 1e-12));
  // Unit length: |r|^2 = g^2 + rho^2 (1 - b^2) = g^2 + q (1 + g)(1 - b) = 1.
  const Vec3 reflected = (g + rho * b) * ni - rho * wo;
  const Vec3 half = wo + reflected;
  // A view in the plane at the bound reflects straight back along the
  // plane; the normal that does so is perpendicular to wo in its plane with Ni.
  if (dot(half, half) < 1e-24) return normalize(ni - wo * b);
  return normalize(half);
}

std::vector<double> consistent_normal_alphas(const TriangleMesh& mesh) {
  const std::size_t vertices = mesh.vertex_count();
  std::vector<double> cos_min(vertices, 1.0);
  auto at = [](const std::vector<float>& a, unsigned k) {
    return Vec3{a[3 * std::size_t(k)], a[3 * std::size_t(k) + 1], a[3 * std::size_t(k) + 2]};
  };
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const unsigned* index = &mesh.triangles[3 * t];
    const Vec3 v0 = at(mesh.positions, index[0]), v1 = at(mesh.positions, index[1]),
               v2 = at(mesh.positions, index[2]);
    Vec3 ng = normalize(cross(v1 - v0, v2 - v0));
    const Vec3 n[3] = {at(mesh.normals, index[0]), at(mesh.normals, index[1]),
                       at(mesh.normals, index[2])};
    if (dot(ng, n[0] + n[1] + n[2]) < 0.0) ng = -ng;
    for (int k = 0; k < 3; ++k)
      cos_min[index[k]] = std::min(cos_min[index[k]], dot(normalize(n[k]), ng));
  }
  std::vector<double> alpha(vertices);
  for (std::size_t k = 0; k < vertices; ++k) {
    const double c = std::clamp(cos_min[k], -1.0, 1.0);
    alpha[k] = std::min(std::acos(c) * (1.0 + 0.03632 * (1.0 - c) * (1.0 - c)), 0.5 * kPi);
  }
  return alpha;
}

}  // namespace penumbra
