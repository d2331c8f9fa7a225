#include "core/surface_map.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/mesh_surface.h"
#include "util/hash.h"

namespace penumbra {
namespace {

// Uniform cubic B-spline weights of the four control points around a
// fraction f in [0, 1), and their derivatives in f.
struct CubicWeights {
  double w[4], dw[4];
};

CubicWeights bspline_weights(double f) {
  const double f2 = f * f, f3 = f2 * f, g = 1.0 - f;
  CubicWeights c;
  c.w[0] = g * g * g / 6.0;
  c.w[1] = (3.0 * f3 - 6.0 * f2 + 4.0) / 6.0;
  c.w[2] = (-3.0 * f3 + 3.0 * f2 + 3.0 * f + 1.0) / 6.0;
  c.w[3] = f3 / 6.0;
  c.dw[0] = -0.5 * g * g;
  c.dw[1] = 0.5 * (3.0 * f2 - 4.0 * f);
  c.dw[2] = 0.5 * (-3.0 * f2 + 2.0 * f + 1.0);
  c.dw[3] = 0.5 * f2;
  return c;
}

int texel_index(int i, int size, MapEdge edge) {
  if (edge == MapEdge::kClamp) return std::clamp(i, 0, size - 1);
  const int m = i % size;
  return m < 0 ? m + size : m;
}

// Azimuth in [0, 2 pi) of a local direction, as surface_at() measures it.
double azimuth(double x, double y) {
  const double phi = std::atan2(y, x);
  return phi < 0.0 ? phi + 2.0 * kPi : phi;
}

// Largest |difference| of channel 0 between neighbours along x (dx = 1) or
// y, and of second differences, with the map's edge rule.
struct TexelDifferences {
  double max_abs = 0.0, dx = 0.0, dy = 0.0, dxx = 0.0, dyy = 0.0, dxy = 0.0;
};

TexelDifferences texel_differences(const SurfaceMap& m) {
  TexelDifferences d;
  auto at = [&](int x, int y) {
    return double(m.texels[std::size_t(texel_index(y, m.height, m.edge)) * m.width +
                           texel_index(x, m.width, m.edge)]);
  };
  for (int y = 0; y < m.height; ++y)
    for (int x = 0; x < m.width; ++x) {
      const double c = at(x, y);
      d.max_abs = std::max(d.max_abs, std::abs(c));
      d.dx = std::max(d.dx, std::abs(at(x + 1, y) - c));
      d.dy = std::max(d.dy, std::abs(at(x, y + 1) - c));
      d.dxx = std::max(d.dxx, std::abs(at(x + 1, y) - 2.0 * c + at(x - 1, y)));
      d.dyy = std::max(d.dyy, std::abs(at(x, y + 1) - 2.0 * c + at(x, y - 1)));
      d.dxy = std::max(d.dxy, std::abs(at(x + 1, y + 1) - at(x + 1, y) - at(x, y + 1) + c));
    }
  return d;
}

}  // namespace

SurfaceParameters surface_parameters(const Shape& s, const Vec3& p) {
  const Vec3 local = s.frame.to_local(p - s.center);
  SurfaceParameters out;
  if (s.type == ShapeType::kPlane) {
    out.u = local.x / s.width + 0.5;
    out.v = local.y / s.height + 0.5;
    out.dp_du = s.frame.s * s.width;
    out.dp_dv = s.frame.t * s.height;
    return out;
  }
  if (s.type == ShapeType::kCylinder) {
    const double phi = azimuth(local.x, local.y);
    out.u = phi / (2.0 * kPi);
    out.v = (local.z + 0.5 * s.height) / s.height;
    out.dp_du = s.frame.to_world({-std::sin(phi), std::cos(phi), 0.0}) * (2.0 * kPi * s.radius);
    out.dp_dv = s.axis * s.height;
    return out;
  }
  const Vec3 d = normalize(local);
  const double phi = azimuth(d.x, d.y);
  const double theta = std::acos(std::clamp(d.z, -1.0, 1.0));
  const double sin_theta = std::sin(theta), cos_theta = std::cos(theta);
  const double cos_phi = std::cos(phi), sin_phi = std::sin(phi);
  out.u = phi / (2.0 * kPi);
  out.v = 1.0 - theta / kPi;
  out.dp_du = s.frame.to_world({-sin_phi, cos_phi, 0.0}) * (2.0 * kPi * s.radius * sin_theta);
  // v grows as the polar angle falls.
  out.dp_dv =
      s.frame.to_world({cos_theta * cos_phi, cos_theta * sin_phi, -sin_theta}) * (-kPi * s.radius);
  return out;
}

void triangle_parameters(const Shape& shape, const Vec3 corners[3], double u[3], double v[3]) {
  bool pole[3];
  for (int k = 0; k < 3; ++k) {
    const SurfaceParameters p = surface_parameters(shape, corners[k]);
    u[k] = p.u, v[k] = p.v;
    pole[k] = !(length(p.dp_du) > 1e-9 * shape.radius);
  }
  if (std::max({u[0], u[1], u[2]}) - std::min({u[0], u[1], u[2]}) > 0.5)
    for (int k = 0; k < 3; ++k)
      if (u[k] < 0.5) u[k] += 1.0;
  double sum = 0.0;
  int count = 0;
  for (int k = 0; k < 3; ++k)
    if (!pole[k]) sum += u[k], ++count;
  for (int k = 0; k < 3; ++k)
    if (pole[k] && count > 0) u[k] = sum / count;
}

SurfaceGeometry surface_at_parameters(const Shape& s, double u, double v) {
  switch (s.type) {
    case ShapeType::kPlane:
      return surface_at(s, (u - 0.5) * s.width, (v - 0.5) * s.height);
    case ShapeType::kCylinder:
      return surface_at(s, 2.0 * kPi * u, (v - 0.5) * s.height);
    case ShapeType::kSphere:
    case ShapeType::kMesh:  // refused by surface_at: image maps on meshes are not read yet
      break;
  }
  return surface_at(s, 2.0 * kPi * u, kPi * (1.0 - v));
}

MapLengths map_lengths(const Shape& s) {
  switch (s.type) {
    case ShapeType::kPlane:
      return {s.width, s.height};
    case ShapeType::kCylinder:
      return {2.0 * kPi * s.radius, s.height};
    case ShapeType::kSphere:
    case ShapeType::kMesh:
      break;
  }
  return {2.0 * kPi * s.radius, kPi * s.radius};
}

MapSample sample_map(const SurfaceMap& m, double s, double t, int channel) {
  const double x = s * m.width - 0.5, y = (1.0 - t) * m.height - 0.5;
  const double fx = std::floor(x), fy = std::floor(y);
  const CubicWeights wx = bspline_weights(x - fx), wy = bspline_weights(y - fy);
  const int x0 = static_cast<int>(fx) - 1, y0 = static_cast<int>(fy) - 1;
  const int stride = m.channels();
  MapSample out;
  double d_dx = 0.0, d_dy = 0.0;
  for (int b = 0; b < 4; ++b) {
    const std::size_t row = std::size_t(texel_index(y0 + b, m.height, m.edge)) * m.width;
    double along = 0.0, along_dx = 0.0;
    for (int a = 0; a < 4; ++a) {
      const double c =
          m.texels[(row + texel_index(x0 + a, m.width, m.edge)) * stride + std::size_t(channel)];
      along += wx.w[a] * c;
      along_dx += wx.dw[a] * c;
    }
    out.value += wy.w[b] * along;
    d_dx += wy.w[b] * along_dx;
    d_dy += wy.dw[b] * along;
  }
  out.d_ds = d_dx * m.width;
  out.d_dt = -d_dy * m.height;  // rows run down as t runs up
  return out;
}

namespace {

// A mesh triangle's texture coordinates at barycentrics (1 - b1 - b2, b1,
// b2) and the gradients of its affine u and v in its plane: grad u =
// alpha e1 + beta e2 with <grad u, e_j> = u_j - u_0 (the Gram system).
struct MeshUv {
  double u = 0.0, v = 0.0;
  Vec3 grad_u, grad_v;
};

MeshUv mesh_uv(const MeshSurface& m, std::uint32_t triangle, double b1, double b2) {
  const float* uv = &m.uvs[6 * std::size_t(triangle)];
  const unsigned* c = &m.mesh.triangles[3 * std::size_t(triangle)];
  const auto vertex = [&](int k) {
    const float* p = &m.mesh.positions[3 * std::size_t(c[k])];
    return Vec3{p[0], p[1], p[2]};
  };
  const double b0 = 1.0 - b1 - b2;
  MeshUv out;
  out.u = b0 * uv[0] + b1 * uv[2] + b2 * uv[4];
  out.v = b0 * uv[1] + b1 * uv[3] + b2 * uv[5];
  const Vec3 e1 = vertex(1) - vertex(0), e2 = vertex(2) - vertex(0);
  const double g11 = dot(e1, e1), g12 = dot(e1, e2), g22 = dot(e2, e2);
  const double det = g11 * g22 - g12 * g12;
  if (!(det > 0.0)) return out;
  const auto gradient = [&](double d1, double d2) {
    return (e1 * (g22 * d1 - g12 * d2) + e2 * (g11 * d2 - g12 * d1)) / det;
  };
  out.grad_u = gradient(double(uv[2]) - uv[0], double(uv[4]) - uv[0]);
  out.grad_v = gradient(double(uv[3]) - uv[1], double(uv[5]) - uv[1]);
  return out;
}

}  // namespace

HeightSample mesh_height_at(const HeightFunction& function, const SurfaceMap* map,
                            const MeshSurface& mesh, const SurfaceGeometry& g) {
  if (!map || map->kind != MapKind::kHeight) return evaluate_height(function, g.p);
  const SurfaceMap& image = *map;
  const MeshUv q = mesh_uv(mesh, g.triangle, g.u, g.v);
  const MapSample m = sample_map(image, q.u * image.tiles_u, q.v * image.tiles_v);
  HeightSample out;
  out.h = m.value;
  out.gradient = q.grad_u * (m.d_ds * image.tiles_u) + q.grad_v * (m.d_dt * image.tiles_v);
  return out;
}

namespace {

Vec3 mesh_normal_map_normal(const SurfaceMap& map, const MeshSurface& mesh,
                            const SurfaceGeometry& g) {
  const MeshUv q = mesh_uv(mesh, g.triangle, g.u, g.v);
  const double s = q.u * map.tiles_u, t = q.v * map.tiles_v;
  const Vec3 c{sample_map(map, s, t, 0).value, sample_map(map, s, t, 1).value,
               sample_map(map, s, t, 2).value};
  const Vec3 n_tangent = c * 2.0 - Vec3{1.0, 1.0, 1.0};
  const unsigned* corner = &mesh.mesh.triangles[3 * std::size_t(g.triangle)];
  const float* tangents = &mesh.tangents[12 * std::size_t(g.triangle)];
  const double b[3] = {1.0 - g.u - g.v, g.u, g.v};
  Vec3 tangent, normal;
  for (int k = 0; k < 3; ++k) {
    const float* t_k = &tangents[4 * k];
    const float* n_k = &mesh.mesh.normals[3 * std::size_t(corner[k])];
    tangent += Vec3{t_k[0], t_k[1], t_k[2]} * b[k];
    normal += Vec3{n_k[0], n_k[1], n_k[2]} * b[k];
  }
  const Vec3 bitangent = cross(normal, tangent) * double(tangents[3]);
  const Vec3 n = tangent * n_tangent.x + bitangent * n_tangent.y + normal * n_tangent.z;
  const double len = length(n);
  return len > 0.0 ? n / len : g.n;
}

}  // namespace

HeightSample height_at(const HeightFunction& function, const SurfaceMap* map, const Shape& shape,
                       const SurfaceGeometry& g) {
  if (!map || map->kind != MapKind::kHeight) return evaluate_height(function, g.p);
  if (shape.type == ShapeType::kMesh) return mesh_height_at(function, map, *shape.mesh, g);
  const SurfaceParameters q = surface_parameters(shape, g.p);
  const MapSample m = sample_map(*map, q.u * map->tiles_u, q.v * map->tiles_v);
  HeightSample out;
  out.h = m.value;
  // The surface gradient of an orthogonal parameterisation: h_u P_u / |P_u|^2
  // + h_v P_v / |P_v|^2 (the P_u term is dropped at a sphere's pole).
  const double pu2 = length_squared(q.dp_du), pv2 = length_squared(q.dp_dv);
  if (pu2 > 1e-24) out.gradient += q.dp_du * (m.d_ds * map->tiles_u / pu2);
  if (pv2 > 1e-24) out.gradient += q.dp_dv * (m.d_dt * map->tiles_v / pv2);
  return out;
}

Vec3 normal_map_normal(const SurfaceMap& map, const Shape& shape, const SurfaceGeometry& g) {
  if (shape.type == ShapeType::kMesh) return mesh_normal_map_normal(map, *shape.mesh, g);
  const SurfaceParameters q = surface_parameters(shape, g.p);
  const double s = q.u * map.tiles_u, t = q.v * map.tiles_v;
  const Vec3 c{sample_map(map, s, t, 0).value, sample_map(map, s, t, 1).value,
               sample_map(map, s, t, 2).value};
  const Vec3 n_tangent = c * 2.0 - Vec3{1.0, 1.0, 1.0};
  const double pu = length(q.dp_du);
  // At a sphere's pole the tangent is undefined: the map's normal is read
  // along the base normal only.
  if (!(pu > 1e-12)) return g.n;
  const Vec3 tangent = q.dp_du / pu;
  const Vec3 bitangent = normalize(q.dp_dv);
  const Vec3 n = tangent * n_tangent.x + bitangent * n_tangent.y + g.n * n_tangent.z;
  const double len = length(n);
  return len > 0.0 ? n / len : g.n;
}

HeightBounds height_bounds(const HeightFunction& function, const SurfaceMap* map,
                           const Shape& shape) {
  if (!map || map->kind != MapKind::kHeight)
    return {max_abs_height(function), max_gradient_norm(function), max_hessian_norm(function)};
  const TexelDifferences d = texel_differences(*map);
  const MapLengths lengths = map_lengths(shape);
  const double length_u =
      lengths.u * (shape.type == ShapeType::kSphere ? std::sin(kPi / 6.0) : 1.0);
  // Texels per scene unit along u and v.
  const double pu = map->width * map->tiles_u / length_u;
  const double pv = map->height * map->tiles_v / lengths.v;
  HeightBounds b;
  b.max_abs = d.max_abs;
  b.max_gradient = std::hypot(pu * d.dx, pv * d.dy);
  // Frobenius norm of the Hessian bound, plus the curvature of the
  // parameterisation's u lines (1/radius on the cylinder and sphere) acting
  // on the slope.
  b.max_hessian = std::sqrt(std::pow(pu * pu * d.dxx, 2) + std::pow(pv * pv * d.dyy, 2) +
                            2.0 * std::pow(pu * pv * d.dxy, 2)) +
                  (shape.type == ShapeType::kPlane ? 0.0 : b.max_gradient / shape.radius);
  return b;
}

MapLengths mesh_map_lengths(const MeshSurface& mesh) {
  double area = 0.0, sum_u = 0.0, sum_v = 0.0;
  for (std::uint32_t t = 0; t < mesh.mesh.triangle_count(); ++t) {
    const MeshUv q = mesh_uv(mesh, t, 0.0, 0.0);
    const double gu = length(q.grad_u), gv = length(q.grad_v);
    if (!(gu > 0.0) || !(gv > 0.0)) continue;
    const unsigned* c = &mesh.mesh.triangles[3 * std::size_t(t)];
    const auto vertex = [&](int k) {
      const float* p = &mesh.mesh.positions[3 * std::size_t(c[k])];
      return Vec3{p[0], p[1], p[2]};
    };
    const double a = 0.5 * length(cross(vertex(1) - vertex(0), vertex(2) - vertex(0)));
    area += a;
    sum_u += a / gu;
    sum_v += a / gv;
  }
  return area > 0.0 ? MapLengths{sum_u / area, sum_v / area} : MapLengths{};
}

std::vector<HeightBounds> mesh_height_bounds(const SurfaceMap& map, const MeshSurface& mesh) {
  const TexelDifferences d = texel_differences(map);
  std::vector<HeightBounds> out(mesh.mesh.triangle_count());
  for (std::uint32_t t = 0; t < out.size(); ++t) {
    const MeshUv q = mesh_uv(mesh, t, 0.0, 0.0);
    // Texels per scene unit along u and v on this triangle.
    const double pu = map.width * map.tiles_u * length(q.grad_u);
    const double pv = map.height * map.tiles_v * length(q.grad_v);
    out[t].max_abs = d.max_abs;
    out[t].max_gradient = pu * d.dx + pv * d.dy;
    out[t].max_hessian = pu * pu * d.dxx + pv * pv * d.dyy + 2.0 * pu * pv * d.dxy;
  }
  return out;
}

std::string map_digest(const SurfaceMap& m) {
  const int header[4] = {static_cast<int>(m.kind), m.width, m.height, m.channels()};
  ContentDigest digest;
  digest.add(header, sizeof header);
  digest.add(m.texels.data(), m.texels.size() * sizeof(float));
  return digest.hex();
}

}  // namespace penumbra
