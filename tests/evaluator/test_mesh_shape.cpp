// Mesh shapes read from files (core/mesh_surface.h, scene/mesh_file.h):
// the truth's exact normal against finite differences, the subdivision's
// watertightness, a UV sphere read back from a file against the built-in
// tessellation it was written from, a plane mesh against the analytic
// plane, and the errors bad files get.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <sys/wait.h>

#include <nlohmann/json.hpp>

#include "analysis/metrics.h"
#include "core/mesh_surface.h"
#include "core/random.h"
#include "core/shadow_origin.h"
#include "core/surface_map.h"
#include "core/tessellation.h"
#include "evaluator/evaluator.h"
#include "image/bump_maps.h"
#include "image/image_io.h"
#include "mesh_files.h"
#include "scene/mesh_file.h"
#include "scene/scene_json.h"
#include "temp_dir_test.h"

namespace penumbra {
namespace {

using nlohmann::json;

// A unit sphere's octahedron, vertices shared, normals radial: closed.
TriangleMesh octahedron() {
  TriangleMesh m;
  const float v[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const auto& p : v)
    for (float x : p) {
      m.positions.push_back(x);
      m.normals.push_back(x);
    }
  m.triangles = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
  m.side_triangles = m.triangle_count();
  return m;
}

MeshSurface surface_of(TriangleMesh m) {
  MeshSurface s;
  s.mesh = std::move(m);
  return s;
}

HeightFunction test_height() {
  return make_weave(std::vector<Vec3>{{1, 0.3, 0}, {0, 0.2, 1}}, 3.0, HeightCombine::kProduct);
}

// P'(b) = P + A h(P) Ni, as subdivide_displaced places a lattice point.
Vec3 truth_point(const TriangleMesh& m, double b1, double b2, double amplitude) {
  const double b[3] = {1.0 - b1 - b2, b1, b2};
  const SurfaceGeometry g = mesh_surface_at(m, 1, b);
  return displaced_point(g, amplitude, evaluate_height(test_height(), g.p));
}

// The closed form against central differences of P'(b): the step 1e-5 in
// barycentrics leaves a truncation error of order 1e-10 and a rounding
// error of order 1e-16 / 1e-5 = 1e-11 in each derivative, so 1e-7 on the
// unit normal is far outside both and far inside any wrong term (the
// curvature term alone moves it by A h k, about 1e-2 here).
TEST(MeshSurface, TruthNormalIsTheNormalOfTheDisplacedSurface) {
  const TriangleMesh m = octahedron();
  const double amplitude = 0.05, step = 1e-5;
  Pcg32 rng(3);
  for (int i = 0; i < 200; ++i) {
    double b1 = rng.next_double(), b2 = rng.next_double();
    if (b1 + b2 > 1.0) b1 = 1.0 - b1, b2 = 1.0 - b2;
    b1 = std::clamp(b1, 2 * step, 1.0 - 4 * step),
    b2 = std::clamp(b2, 2 * step, 1.0 - b1 - 2 * step);
    const Vec3 d1 =
        (truth_point(m, b1 + step, b2, amplitude) - truth_point(m, b1 - step, b2, amplitude)) /
        (2 * step);
    const Vec3 d2 =
        (truth_point(m, b1, b2 + step, amplitude) - truth_point(m, b1, b2 - step, amplitude)) /
        (2 * step);
    Vec3 expected = normalize(cross(d1, d2));
    const double b[3] = {1.0 - b1 - b2, b1, b2};
    const SurfaceGeometry g = mesh_surface_at(m, 1, b);
    if (dot(expected, g.n) < 0.0) expected = -expected;
    const Vec3 ns = mesh_displaced_normal(m, 1, b, amplitude, evaluate_height(test_height(), g.p));
    EXPECT_LT(length(ns - expected), 1e-7) << "b = " << b1 << ", " << b2;
  }
}

// The bump of a mesh turns Ni by exactly the displacement's turn of the
// facet: where h = 0 and grad h = g, the truth P'(b) = P + A h(P) Ni(b) has
// tangents T_j = e_j + A <g, e_j> Ni, so T1 x T2 - e1 x e2 is linear in A
// (its A^2 term has Ni x Ni), and the bump's unnormalised normal
// Ni - A g' must equal Ni + (T1 x T2 - e1 x e2) / det, det =
// <e1 x e2, Ni> (either sign: the winding is the file's), for any A and
// any g, its component along Ng included (h lives on the triangle). T_j
// are central differences of P' with h linear (h = <g, P - P0>) at step
// 1e-5: truncation of order 1e-10 and rounding of order 1e-16 / 1e-5 on
// T_j, both divided by det (down to about 1e-2 on these random triangles),
// so 1e-8 on the unit normal; measured 1.4e-9 (1.7e-8 at step 1e-4, the
// truncation's step^2). Projecting g onto the plane normal to Ni, as the
// evaluator did before, misses by up to A |g| sin(delta) tan(delta): 2.7e-2
// here, which the test must see, or it could not catch the old formula.
TEST(MeshSurface, BumpTurnsNiAsTheDisplacementTurnsTheFacet) {
  Pcg32 rng(11);
  const auto random_vector = [&] {
    return Vec3{2 * rng.next_double() - 1, 2 * rng.next_double() - 1, 2 * rng.next_double() - 1};
  };
  double projection_miss = 0.0, largest_miss = 0.0;
  for (int i = 0; i < 200; ++i) {
    TriangleMesh m;
    const Vec3 ng_dir = normalize(Vec3{0.2, 0.3, 1.0});
    for (int k = 0; k < 3; ++k) {
      Vec3 p = random_vector();
      p = p - ng_dir * dot(p, ng_dir);  // a triangle in the plane normal to ng_dir
      const Vec3 n = normalize(ng_dir + random_vector() * 0.6);  // within about 50 degrees
      for (double x : {p.x, p.y, p.z}) m.positions.push_back(float(x));
      for (double x : {n.x, n.y, n.z}) m.normals.push_back(float(x));
    }
    m.triangles = {0, 1, 2};
    m.side_triangles = 1;
    const Vec3 v[3] = {{m.positions[0], m.positions[1], m.positions[2]},
                       {m.positions[3], m.positions[4], m.positions[5]},
                       {m.positions[6], m.positions[7], m.positions[8]}};
    const Vec3 e1 = v[1] - v[0], e2 = v[2] - v[0];
    Vec3 ng = normalize(cross(e1, e2));
    if (dot(ng, ng_dir) < 0.0) ng = -ng;
    const double b1 = 0.1 + 0.5 * rng.next_double(), b2 = 0.1 + 0.3 * rng.next_double();
    const double b[3] = {1.0 - b1 - b2, b1, b2};
    const SurfaceGeometry g = mesh_surface_at(m, 0, b);
    const Vec3 gradient = random_vector();
    const double amplitude = 0.05 * rng.next_double();
    const auto truth = [&](double c1, double c2) {
      const double bb[3] = {1.0 - c1 - c2, c1, c2};
      const SurfaceGeometry q = mesh_surface_at(m, 0, bb);
      return q.p + q.n * (amplitude * dot(gradient, q.p - g.p));
    };
    const double step = 1e-5;
    const Vec3 t1 = (truth(b1 + step, b2) - truth(b1 - step, b2)) / (2 * step);
    const Vec3 t2 = (truth(b1, b2 + step) - truth(b1, b2 - step)) / (2 * step);
    const Vec3 facet = cross(e1, e2);
    const double det = dot(facet, g.n);
    const Vec3 expected = normalize(g.n + (cross(t1, t2) - facet) / det);
    HeightSample h;
    h.gradient = facet_bump_gradient(gradient, ng, g.n);
    const double miss = length(displaced_normal(g, amplitude, h) - expected);
    largest_miss = std::max(largest_miss, miss);
    EXPECT_LT(miss, 1e-8) << "sample " << i;
    // The same with Ng on the other side: g' does not depend on it.
    h.gradient = facet_bump_gradient(gradient, -ng, g.n);
    EXPECT_LT(length(displaced_normal(g, amplitude, h) - expected), 1e-8) << "sample " << i;
    h.gradient = gradient - g.n * dot(gradient, g.n);
    projection_miss =
        std::max(projection_miss, length(displaced_normal(g, amplitude, h) - expected));
  }
  std::printf(
      "[ mesh     ] the bump misses the displacement's turn by up to %.3g; projecting g onto "
      "the plane normal to Ni, by up to %.3g\n",
      largest_miss, projection_miss);
  EXPECT_GT(projection_miss, 1e-4);
}

// The octahedron stretched along x, so its edges split into different
// counts and every triangle has edges of two levels.
TriangleMesh stretched_octahedron() {
  TriangleMesh m = octahedron();
  for (std::size_t v = 0; v < m.vertex_count(); ++v) m.positions[3 * v] *= 3.0f;
  return m;
}

// Every edge of a closed mesh's subdivision, squeezed triangles left out,
// is shared by exactly two triangles in opposite directions (no crack, no
// T-junction), and the sub-triangles tile each base triangle: their areas
// in barycentric space sum to its own.
TEST(MeshSurface, AdaptiveSubdivisionOfAClosedMeshIsClosed) {
  for (double edge : {10.0, 1.0, 0.37, 0.2}) {
    const TriangleMesh base = stretched_octahedron();
    const MeshSubdivision plan = plan_subdivision(base, edge);
    const TriangleMesh out = subdivide_displaced(surface_of(base), plan, {test_height()}, 0.05);
    ASSERT_EQ(out.triangle_count(), plan.triangle_count());
    std::map<std::pair<unsigned, unsigned>, int> directed;
    std::size_t squeezed = 0;
    for (std::size_t t = 0; t < out.triangle_count(); ++t) {
      const unsigned* c = &out.triangles[3 * t];
      if (c[0] == c[1] || c[1] == c[2] || c[2] == c[0]) {
        ++squeezed;
        continue;
      }
      for (int k = 0; k < 3; ++k) ++directed[{c[k], c[(k + 1) % 3]}];
    }
    for (const auto& [e, count] : directed) {
      EXPECT_EQ(count, 1) << "edge length " << edge;
      EXPECT_EQ(directed.count({e.second, e.first}), 1u)
          << "edge length " << edge << ": edge " << e.first << "-" << e.second << " is open";
    }
    // Euler: V - E + F = 2 for the sphere.
    const std::size_t edges = directed.size() / 2;
    EXPECT_EQ(long(out.vertex_count()) - long(edges) + long(out.triangle_count() - squeezed), 2)
        << "edge length " << edge;
    // Tiling: locate_in_base maps each sub-triangle's corners into its base
    // triangle; the signed areas add up to 1/2 per base triangle.
    std::vector<double> area(base.triangle_count(), 0.0);
    for (std::uint64_t prim = 0; prim < plan.triangle_count(); ++prim) {
      double corner[3][3];
      std::uint32_t t = 0;
      const double at[3][2] = {{0, 0}, {1, 0}, {0, 1}};
      for (int k = 0; k < 3; ++k) locate_in_base(plan, prim, at[k][0], at[k][1], &t, corner[k]);
      area[t] += 0.5 * ((corner[1][1] - corner[0][1]) * (corner[2][2] - corner[0][2]) -
                        (corner[1][2] - corner[0][2]) * (corner[2][1] - corner[0][1]));
    }
    for (double a : area) EXPECT_NEAR(a, 0.5, 1e-12) << "edge length " << edge;
  }
}

// The truth as another renderer gets it: the same surface (every vertex
// one of the shared subdivision's, bit for bit, and every edge, by its
// end points' bits, shared by two triangles in opposite directions), each
// vertex's normal the exact one of the base triangle it belongs to, and the
// base mesh's creases kept: a point on a base edge has a copy per side,
// whose normals differ by about the facets' own angle.
TEST(MeshSurface, ExportedTruthIsTheSameSurfaceWithItsCreases) {
  const TriangleMesh base = octahedron();
  const double amplitude = 0.005;
  const MeshSubdivision plan = plan_subdivision(base, 0.37);
  const HeightFunction height = test_height();
  const TriangleMesh shared = subdivide_displaced(surface_of(base), plan, {height}, amplitude);
  const TriangleMesh out = displaced_mesh_for_export(surface_of(base), plan, {height}, amplitude);
  ASSERT_EQ(out.normals.size(), out.positions.size());
  using Point = std::array<float, 3>;
  const auto point = [](const TriangleMesh& m, unsigned v) {
    return Point{m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]};
  };
  std::map<Point, int> shared_points;
  for (unsigned v = 0; v < shared.vertex_count(); ++v) shared_points[point(shared, v)] = 0;
  std::map<Point, std::vector<Vec3>> copies;
  for (unsigned v = 0; v < out.vertex_count(); ++v) {
    ASSERT_EQ(shared_points.count(point(out, v)), 1u) << "vertex " << v;
    const float* n = &out.normals[3 * v];
    copies[point(out, v)].push_back({n[0], n[1], n[2]});
  }
  EXPECT_EQ(copies.size(), shared.vertex_count());
  std::map<std::pair<Point, Point>, int> directed;
  for (std::size_t t = 0; t < out.triangle_count(); ++t)
    for (int k = 0; k < 3; ++k)
      ++directed[{point(out, out.triangles[3 * t + k]),
                  point(out, out.triangles[3 * t + (k + 1) % 3])}];
  for (const auto& [e, count] : directed) {
    EXPECT_EQ(count, 1);
    EXPECT_EQ(directed.count({e.second, e.first}), 1u) << "an open edge";
  }
  // The octahedron's facets meet at 109.5 degrees (normals 70.5 degrees
  // apart): a point inside an edge has one copy per side, whose normals
  // the displacement tilts by at most atan(A |grad h|) each.
  double largest_crease = 0.0, smallest_crease = 180.0;
  for (const auto& [p, normals] : copies) {
    if (normals.size() != 2) continue;
    const double angle = degrees(angle_between(normals[0], normals[1]));
    largest_crease = std::max(largest_crease, angle);
    smallest_crease = std::min(smallest_crease, angle);
  }
  const double tilt = degrees(std::atan(amplitude * max_gradient_norm(test_height())));
  std::printf("creases %.2f to %.2f degrees (facets 70.53, tilt up to %.2f)\n", smallest_crease,
              largest_crease, tilt);
  EXPECT_GT(smallest_crease, 70.53 - 2 * tilt);
  EXPECT_LT(largest_crease, 70.53 + 2 * tilt);
  std::size_t squeezed = 0;
  for (std::size_t t = 0; t < shared.triangle_count(); ++t) {
    const unsigned* c = &shared.triangles[3 * t];
    squeezed += c[0] == c[1] || c[1] == c[2] || c[2] == c[0];
  }
  EXPECT_EQ(out.triangle_count(), shared.triangle_count() - squeezed);
}

json small_scene() {
  return json::parse(R"({
    "version": 1,
    "camera": {"projection": "orthographic", "position": [0, 0, -5], "direction": [0, 0, 1],
               "right": [2.4, 0, 0], "up": [0, 2.4, 0], "width": 40, "height": 40, "spp": 4,
               "seed": 7},
    "light": {"type": "distant", "direction": [-1, 0.3, -0.2], "irradiance": 3.14159},
    "shape": {"type": "sphere", "center": [0, 0, 0], "axis": [0, 1, 0], "radius": 1,
              "tessellation": {"scheme": "uv", "segments": 12}},
    "material": {"albedo": 0.8},
    "representation": "smooth"
  })");
}

// The radiance and coverage channels (R, G, B, A) of two renders, bit for bit.
void expect_same_radiance(const Image& a, const Image& b, const std::string& what) {
  ASSERT_EQ(a.pixels.size(), b.pixels.size());
  const std::size_t channels = a.channels.size();
  std::size_t differ = 0;
  for (std::size_t p = 0; p < a.pixels.size(); p += channels)
    for (std::size_t c = 0; c < 4; ++c) differ += a.pixels[p + c] != b.pixels[p + c];
  EXPECT_EQ(differ, 0u) << what;
}

class MeshShapeTest : public TempDirTest {};

// The triangles, vertex normals and shadow-ray origins a mesh file gives
// are the tessellation's own when the file holds its bits: every offset
// method's smooth render is the same image. (Bump differs by design: the
// tessellation bumps the analytic sphere under the triangle, a file mesh
// its interpolated normal.)
TEST_F(MeshShapeTest, UvSphereFromAFileRendersLikeTheBuiltInTessellation) {
  const json built_in = small_scene();
  const Scene tessellated = scene_from_json(built_in, "built-in");
  write_ply(tessellate(tessellated.shape, *tessellated.tessellation), path("sphere.ply"));
  json from_file = built_in;
  from_file["shape"] = {{"type", "mesh"}, {"file", path("sphere.ply")}};
  for (const OffsetMethodInfo& offset : all_offset_methods()) {
    json a = built_in, b = from_file;
    a["offset"] = b["offset"] = {{"method", std::string(offset.id)}};
    expect_same_radiance(render(scene_from_json(a, "built-in")), render(scene_from_json(b, "file")),
                         std::string(offset.id));
  }
}

// A flat square as two triangles with the plane's normal at every vertex
// has Ni = N and no curvature, as the analytic plane: its bump render is the
// plane's up to where Embree's float hit lands against the analytic double
// one (1e-7 relative in the point, times the height's slope), and its truth
// differs from the plane's only in the facets the two subdivisions make.
TEST_F(MeshShapeTest, FlatSquareMatchesTheAnalyticPlane) {
  std::ofstream(path("square.obj")) << "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
                                       "vn 0 0 -1\nf 1//1 2//1 3//1\nf 1//1 3//1 4//1\n";
  json plane = small_scene();
  plane["shape"] = {
      {"type", "plane"}, {"center", {0, 0, 0}}, {"axis", {0, 0, -1}}, {"width", 2}, {"height", 2}};
  plane["light"]["direction"] = {-1, 0.3, -1.2};
  plane["height"] = {
      {"type", "grating"}, {"amplitude", 0.01}, {"frequency", 4}, {"direction", {1, 0.4, 0}}};
  plane["displacement"] = {{"edge_length", 0.01}};
  json mesh = plane;
  mesh["shape"] = {{"type", "mesh"}, {"file", path("square.obj")}};
  // The plane's default edge length is relative to its size: the same here.
  for (const char* representation : {"bump", "displacement"}) {
    plane["representation"] = mesh["representation"] = representation;
    const Image a = render(scene_from_json(plane, "plane"));
    const Image b = render(scene_from_json(mesh, "mesh"));
    double sum = 0.0, differ = 0.0, largest = 0.0;
    const std::size_t channels = a.channels.size();
    for (std::size_t p = 0; p < a.pixels.size(); p += channels) {
      sum += a.pixels[p];
      differ += std::abs(a.pixels[p] - b.pixels[p]);
      largest = std::max(largest, double(std::abs(a.pixels[p] - b.pixels[p])));
    }
    std::printf("%s: mean |difference| %.3g of the mean radiance, largest %.3g\n", representation,
                differ / sum, largest);
    EXPECT_LT(differ / sum, std::string(representation) == "bump" ? 1e-5 : 1e-3) << representation;
    // The pixel-centre angles are the plane's: the same ray meets the same
    // flat surface with the same normal, up to Embree's float hit.
    double theta_error = 0.0;
    const int theta = a.channel_index("analysis.theta");
    for (int y = 0; y < a.height; ++y)
      for (int x = 0; x < a.width; ++x)
        if (a.at(x, y, 3) == 1.0f && b.at(x, y, 3) == 1.0f)
          theta_error =
              std::max(theta_error, double(std::abs(a.at(x, y, theta) - b.at(x, y, theta))));
    EXPECT_LT(theta_error, 1e-3) << representation;
  }
}

// A mesh's analysis angles are its base mesh's at the pixel centre: the same
// bits in smooth, bump and truth renders at any samples, seed or edge
// length (they bin a profile's pixels, so a truth's convergence check would
// otherwise measure its binning), and those of a flat square are the
// analytic plane's.
TEST_F(MeshShapeTest, AnalysisAnglesAreThePixelCentresOfTheBaseMesh) {
  const Scene tessellated = scene_from_json(small_scene(), "built-in");
  write_ply(tessellate(tessellated.shape, *tessellated.tessellation), path("sphere.ply"));
  json doc = small_scene();
  doc["shape"] = {{"type", "mesh"}, {"file", path("sphere.ply")}};
  doc["height"] = {
      {"type", "grating"}, {"amplitude", 0.02}, {"frequency", 5}, {"direction", {1, 0.4, 0}}};
  doc["displacement"] = {{"edge_length", 0.05}};
  std::vector<Image> renders;
  for (const char* representation : {"smooth", "bump", "displacement"})
    for (const auto& [spp, seed, edge] :
         {std::tuple{4, 7, 0.05}, std::tuple{16, 8, 0.05}, std::tuple{4, 7, 0.025}}) {
      json d = doc;
      d["representation"] = representation;
      d["camera"]["spp"] = spp, d["camera"]["seed"] = seed, d["camera"]["jitter"] = true;
      d["displacement"]["edge_length"] = edge;
      renders.push_back(render(scene_from_json(d, representation)));
    }
  const Image& first = renders.front();
  const int theta = first.channel_index("analysis.theta"),
            view = first.channel_index("analysis.view");
  std::size_t compared = 0;
  for (int y = 0; y < first.height; ++y)
    for (int x = 0; x < first.width; ++x) {
      bool covered = true;
      for (const Image& r : renders) covered = covered && r.at(x, y, 3) == 1.0f;
      if (!covered) continue;
      ++compared;
      for (const Image& r : renders) {
        ASSERT_EQ(r.at(x, y, theta), first.at(x, y, theta)) << x << ", " << y;
        ASSERT_EQ(r.at(x, y, view), first.at(x, y, view)) << x << ", " << y;
      }
    }
  EXPECT_GT(compared, 600u);
  // Ni is not the sphere's normal: the angles are the mesh's, within the
  // facets' turn of the normal (12 segments: up to about 15 degrees) of the
  // built-in tessellation's analytic ones.
  const Image built_in = render(tessellated);
  double largest = 0.0;
  for (int y = 0; y < first.height; ++y)
    for (int x = 0; x < first.width; ++x)
      if (first.at(x, y, 3) == 1.0f && built_in.at(x, y, 3) == 1.0f)
        largest =
            std::max(largest, double(std::abs(first.at(x, y, theta) - built_in.at(x, y, theta))));
  std::printf("largest |theta(mesh) - theta(analytic sphere)| %.3f degrees\n", largest);
  EXPECT_GT(largest, 0.0);
  EXPECT_LT(largest, 15.0);
}

// The terminator profile bins a mesh's pixels by the angle of Ni at the
// pixel centre, so that on any triangulation of a sphere, however
// irregular, the smooth render's profile is the analytic sphere's,
// cos(theta), away from the terminator (where the flat triangles' shadow
// rays darken it: the artifact Penumbra measures). Checked on an icosphere
// and on a UV sphere whose vertices are moved at random along the surface,
// normals radial: per 1-degree bin over [0, 70) degrees, |profile -
// bin mean of cos(theta)|. The pixel footprint: Ni turns by about a pixel
// over the radius, 0.019 radians at 128 px, and a pixel's mean of cos over
// +-0.01 is cos (1 - 0.01^2 / 6), 2e-5 off; the samples: cos varies by
// +-0.01 over a pixel, so 64 jittered samples leave about 0.01 / 8 / sqrt(3)
// = 7e-4 per pixel, over the 10 or more pixels of a bin under 3e-4; a kink
// of Ni across a triangle's edge inside a pixel adds to both. Bound: 1e-3
// (measured 2.2e-4, icosphere, and 3.6e-4, jittered). Binning by the flat
// triangle's normal instead would be off by its tilt, up to 0.05 here.
TEST_F(MeshShapeTest, ProfileOfAnIrregularSphereMeshIsTheAnalyticSpheres) {
  json doc = small_scene();
  doc["camera"]["width"] = doc["camera"]["height"] = 128;
  doc["camera"]["spp"] = 64, doc["camera"]["jitter"] = true;
  doc["shape"]["tessellation"] = {{"scheme", "icosphere"}, {"frequency", 6}};
  const Scene ico = scene_from_json(doc, "icosphere");
  TriangleMesh jittered;
  {
    json uv = small_scene();
    uv["shape"]["tessellation"]["segments"] = 24;
    const Scene s = scene_from_json(uv, "uv");
    jittered = tessellate(s.shape, *s.tessellation);
    Pcg32 rng(11);
    for (std::size_t v = 0; v < jittered.vertex_count(); ++v) {
      float* p = &jittered.positions[3 * v];
      Vec3 q{p[0] + 0.08 * (rng.next_double() - 0.5), p[1] + 0.08 * (rng.next_double() - 0.5),
             p[2] + 0.08 * (rng.next_double() - 0.5)};
      q = normalize(q);
      for (int k = 0; k < 3; ++k)
        p[k] = jittered.normals[3 * v + k] = float(k == 0 ? q.x : k == 1 ? q.y : q.z);
    }
  }
  const std::pair<std::string, TriangleMesh> meshes[] = {
      {"icosphere", tessellate(ico.shape, *ico.tessellation)}, {"jittered uv sphere", jittered}};
  for (const auto& [name, mesh] : meshes) {
    write_ply(mesh, path("mesh.ply"));
    json d = doc;
    d["shape"] = {{"type", "mesh"}, {"file", path("mesh.ply")}};
    const Scene scene = scene_from_json(d, name);
    const Image image = render(scene);
    const double scale = radiance_scale(scene);
    const Profile profile = terminator_profile(image, scale);
    std::vector<double> cos_sum(profile.value.size(), 0.0);
    std::vector<int> count(profile.value.size(), 0);
    const int theta = image.channel_index("analysis.theta");
    for (int y = 0; y < image.height; ++y)
      for (int x = 0; x < image.width; ++x) {
        if (image.at(x, y, 3) < 0.999f) continue;
        const double t = image.at(x, y, theta);
        const auto bin = std::size_t(t / profile.bin_degrees);
        if (bin >= cos_sum.size()) continue;
        cos_sum[bin] += std::cos(radians(t));
        ++count[bin];
      }
    double largest = 0.0;
    std::size_t bins = 0;
    for (std::size_t b = 0; b < profile.value.size() && profile.centre(b) < 70.0; ++b) {
      if (profile.count[b] < 10) continue;
      ASSERT_EQ(std::uint64_t(count[b]), profile.count[b]) << name << " bin " << b;
      largest = std::max(largest, std::abs(profile.value[b] - cos_sum[b] / count[b]));
      ++bins;
    }
    std::printf("%s (%zu triangles): %zu bins, largest |profile - cos| %.2e\n", name.c_str(),
                mesh.triangle_count(), bins, largest);
    EXPECT_GT(bins, 40u) << name;
    EXPECT_LT(largest, 1e-3) << name;
  }
}

// One line naming the scene, /shape/file and what is wrong with the mesh.
TEST_F(MeshShapeTest, BadMeshFilesAreRefusedWithTheFileAndTheReason) {
  const std::vector<std::pair<std::string, std::string>> files = {
      {"missing.obj", ""},
      {"points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"},
      {"nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"},
      {"flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"},
      {"range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"},
      {"unended.ply", "ply\nformat ascii 1.0\nelement vertex 100000000\n"},
      {"huge.ply",
       "ply\nformat ascii 1.0\nelement vertex 100000000\nproperty float x\nend_header\n0\n"},
  };
  for (const auto& [name, text] : files) {
    if (!text.empty()) std::ofstream(path(name)) << text;
    json scene = small_scene();
    scene["shape"] = {{"type", "mesh"}, {"file", path(name)}};
    try {
      scene_from_json(scene, "scene.json");
      ADD_FAILURE() << name << " was accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), "scene.json") << name;
      EXPECT_EQ(e.pointer(), "/shape/file") << name;
      EXPECT_NE(e.reason().find(name), std::string::npos) << e.what();
      std::printf("%s: %s\n", name.c_str(), e.what());
    }
  }
}

// Writes `mesh` as OBJ text (vertices, normals, faces).
std::string obj_text(const TriangleMesh& mesh) {
  std::string text;
  char line[128];
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\nvn %.9g %.9g %.9g\n",
                  double(mesh.positions[3 * v]), double(mesh.positions[3 * v + 1]),
                  double(mesh.positions[3 * v + 2]), double(mesh.normals[3 * v]),
                  double(mesh.normals[3 * v + 1]), double(mesh.normals[3 * v + 2]));
    text += line;
  }
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const unsigned* c = &mesh.triangles[3 * t];
    std::snprintf(line, sizeof line, "f %u//%u %u//%u %u//%u\n", c[0] + 1, c[0] + 1, c[1] + 1,
                  c[1] + 1, c[2] + 1, c[2] + 1);
    text += line;
  }
  return text;
}

// The same with a planar UV per vertex (x and y mapped to [0, 1]).
std::string obj_text_with_uvs(const TriangleMesh& mesh) {
  std::string text;
  char line[160];
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    const double x = mesh.positions[3 * v], y = mesh.positions[3 * v + 1];
    std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\nvn %.9g %.9g %.9g\nvt %.9g %.9g\n", x, y,
                  double(mesh.positions[3 * v + 2]), double(mesh.normals[3 * v]),
                  double(mesh.normals[3 * v + 1]), double(mesh.normals[3 * v + 2]), 0.5 + 0.5 * x,
                  0.5 + 0.5 * y);
    text += line;
  }
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const unsigned* c = &mesh.triangles[3 * t];
    std::snprintf(line, sizeof line, "f %u/%u/%u %u/%u/%u %u/%u/%u\n", c[0] + 1, c[0] + 1, c[0] + 1,
                  c[1] + 1, c[1] + 1, c[1] + 1, c[2] + 1, c[2] + 1, c[2] + 1);
    text += line;
  }
  return text;
}

// An image map on a mesh is laid over its UVs: a mesh without them is
// refused at the map, and so is a filter (its footprints follow an analytic
// shape's parameterisation).
TEST_F(MeshShapeTest, ImageMapsOnAMeshNeedItsUvsAndNoFilter) {
  std::ofstream(path("tri.obj")) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  std::ofstream(path("tri-uv.obj")) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
                                       "f 1/1 2/2 3/3\n";
  const auto refusal = [&](const char* mesh, const json& height) {
    json scene = small_scene();
    scene["shape"] = {{"type", "mesh"}, {"file", path(mesh)}};
    scene["height"] = height;
    try {
      scene_from_json(scene, "scene.json");
    } catch (const InputError& e) {
      return e.pointer() + ": " + e.reason();
    }
    return std::string("accepted");
  };
  for (const char* family : {"height-map", "normal-map"}) {
    const std::string why =
        refusal("tri.obj", {{"type", family}, {"file", path("map.exr")}, {"amplitude", 0.01}});
    EXPECT_EQ(why.rfind("/height/type: ", 0), 0u) << why;
    EXPECT_NE(why.find("no texture coordinates"), std::string::npos) << why;
  }
  write_exr(bake_surface_map(scene_from_json(small_scene(), "s").shape,
                             make_grating({1, 0, 0}, 2.0, 0.0), 1.0, 8, 8, MapKind::kHeight),
            path("map.exr"));
  const std::string filtered = refusal("tri-uv.obj", {{"type", "height-map"},
                                                      {"file", path("map.exr")},
                                                      {"amplitude", 0.01},
                                                      {"filter", json::object()}});
  EXPECT_EQ(filtered.rfind("/height/filter: ", 0), 0u) << filtered;
}

// A flat square with the analytic plane's own (u, v) as its UVs carries an
// image map exactly as the plane does (its UVs are affine, as the plane's
// parameters are): the bump and normal-map renders are the plane's up to
// Embree's float hit (as FlatSquareMatchesTheAnalyticPlane), so the mesh's
// gradient through grad(u), grad(v) and its MikkTSpace frame (T along
// dP/du, sign (N x T) along dP/dv) are the plane's; the truth differs
// in the facets the two subdivisions make.
TEST_F(MeshShapeTest, FlatSquareWithImageMapsMatchesTheAnalyticPlane) {
  json plane = small_scene();
  plane["shape"] = {
      {"type", "plane"}, {"center", {0, 0, 0}}, {"axis", {0, 0, -1}}, {"width", 2}, {"height", 2}};
  plane["light"]["direction"] = {-1, 0.3, -1.2};
  plane["displacement"] = {{"edge_length", 0.01}};
  const Shape shape = scene_from_json(plane, "plane").shape;
  const HeightFunction grating = make_grating({1, 0.4, 0}, 4.0, 0.3);
  write_exr(bake_surface_map(shape, grating, 1.0, 96, 96, MapKind::kHeight), path("h.exr"));
  write_exr(bake_surface_map(shape, grating, 0.01, 96, 96, MapKind::kNormal), path("n.exr"));
  std::ofstream obj(path("square.obj"));
  obj.precision(17);
  const double corner[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  for (const auto& c : corner) obj << "v " << c[0] << " " << c[1] << " 0\n";
  for (const auto& c : corner) {
    const SurfaceParameters q = surface_parameters(shape, {c[0], c[1], 0.0});
    obj << "vt " << q.u << " " << q.v << "\n";
  }
  // Wound about -z, the normal's side, as a modelling tool writes it.
  obj << "vn 0 0 -1\nf 1/1/1 3/3/1 2/2/1\nf 1/1/1 4/4/1 3/3/1\n";
  obj.close();
  json mesh = plane;
  mesh["shape"] = {{"type", "mesh"}, {"file", path("square.obj")}};
  const json height_map{{"type", "height-map"}, {"file", path("h.exr")}, {"amplitude", 0.01}};
  const json normal_map{{"type", "normal-map"}, {"file", path("n.exr")}};
  for (const auto& [height, representation] :
       {std::pair{height_map, "bump"}, std::pair{height_map, "displacement"},
        std::pair{normal_map, "bump"}}) {
    plane["height"] = mesh["height"] = height;
    plane["representation"] = mesh["representation"] = representation;
    const Image a = render(scene_from_json(plane, "plane"));
    const Image b = render(scene_from_json(mesh, "mesh"));
    double sum = 0.0, differ = 0.0;
    const std::size_t channels = a.channels.size();
    for (std::size_t p = 0; p < a.pixels.size(); p += channels) {
      sum += a.pixels[p];
      differ += std::abs(a.pixels[p] - b.pixels[p]);
    }
    const std::string what = height["type"].get<std::string>() + " " + representation;
    std::printf("%s: mean |difference| %.3g of the mean radiance\n", what.c_str(), differ / sum);
    EXPECT_LT(differ / sum, std::string(representation) == "bump" ? 1e-5 : 1e-3) << what;
  }
}

// Mutated OBJ and PLY files (bytes flipped, inserted, cut, numbers made
// huge or NaN, counts changed) either load into a finite mesh that renders
// finite pixels, or are refused with /shape/file (or /height/type, where a
// mutant with UVs lost them); nothing crashes or hangs (the whole run takes
// well under a second of loading per mutant).
// A glTF 2.0 asset's UVs as the file holds them, decoded here from its JSON
// and binary buffer without Assimp: the reader gives each corner the file's
// TEXCOORD_0 with v turned up (1 - v: glTF puts v = 0 at the image's top,
// OBJ and Blender at its bottom, and Blender's glTF importer flips it the
// same way), at the position the node's matrix puts it. The same asset as
// .gltf with an external buffer, as .gltf with the buffer embedded and as
// .glb reads to the same bits. Floats: the file's UVs are float and 1 - v
// is exact for v in [0.5, 1] and within half an ulp of 1 elsewhere, so
// 1e-7 is rounding; a wrong flip or a swapped corner is off by up to 1.
TEST_F(MeshShapeTest, GltfUvsAreTheFilesWithVTurnedUp) {
  const std::string folder = "/usr/share/assimp/models/glTF2/";
  const std::string gltf = folder + "BoxTextured-glTF/BoxTextured.gltf";
  ASSERT_TRUE(std::filesystem::exists(gltf)) << "assimp-testmodels is not installed";
  const json doc = json::parse(std::ifstream(gltf));
  std::ifstream bin_in(folder + "BoxTextured-glTF/" + doc["buffers"][0]["uri"].get<std::string>(),
                       std::ios::binary);
  const std::string bin((std::istreambuf_iterator<char>(bin_in)), std::istreambuf_iterator<char>());
  // An accessor's element i, component c, as float (5126) or uint16 (5123).
  const auto element = [&](int accessor, std::size_t i, std::size_t c) {
    const json& a = doc["accessors"][accessor];
    const json& view = doc["bufferViews"][a["bufferView"].get<int>()];
    const std::size_t size = a["componentType"] == 5126 ? 4 : 2;
    const std::size_t width = a["type"] == "SCALAR" ? 1 : a["type"] == "VEC2" ? 2 : 3;
    const std::size_t stride = view.value("byteStride", std::size_t(size * width));
    const std::size_t at = view.value("byteOffset", std::size_t(0)) +
                           a.value("byteOffset", std::size_t(0)) + i * stride + c * size;
    if (size == 2) {
      std::uint16_t v = 0;
      std::memcpy(&v, bin.data() + at, 2);
      return double(v);
    }
    float v = 0;
    std::memcpy(&v, bin.data() + at, 4);
    return double(v);
  };
  const json& primitive = doc["meshes"][0]["primitives"][0];
  const int indices = primitive["indices"], positions = primitive["attributes"]["POSITION"],
            texcoords = primitive["attributes"]["TEXCOORD_0"];
  // The root node's column-major matrix (its child holds the mesh).
  const json& m = doc["nodes"][0]["matrix"];
  const auto placed = [&](std::size_t v) {
    const double x = element(positions, v, 0), y = element(positions, v, 1),
                 z = element(positions, v, 2);
    return Vec3{m[0].get<double>() * x + m[4].get<double>() * y + m[8].get<double>() * z,
                m[1].get<double>() * x + m[5].get<double>() * y + m[9].get<double>() * z,
                m[2].get<double>() * x + m[6].get<double>() * y + m[10].get<double>() * z};
  };
  const std::size_t corners = doc["accessors"][indices]["count"];
  const LoadedMesh loaded = load_mesh_file(gltf, MeshTransform{}, MeshNormals::kFile);
  const MeshSurface& surface = *loaded.surface;
  ASSERT_TRUE(surface.has_uvs());
  ASSERT_EQ(surface.mesh.triangles.size(), corners);
  // Corners in the file's order: the reader keeps triangles and their
  // corners as they come.
  double largest = 0.0;
  for (std::size_t c = 0; c < corners; ++c) {
    const std::size_t v = std::size_t(element(indices, c, 0));
    const std::size_t ours = surface.mesh.triangles[c];
    const Vec3 p{surface.mesh.positions[3 * ours], surface.mesh.positions[3 * ours + 1],
                 surface.mesh.positions[3 * ours + 2]};
    EXPECT_LT(length(p - placed(v)), 1e-7) << "corner " << c;
    largest =
        std::max({largest, std::abs(double(surface.uvs[2 * c]) - element(texcoords, v, 0)),
                  std::abs(double(surface.uvs[2 * c + 1]) - (1.0 - element(texcoords, v, 1)))});
  }
  EXPECT_LT(largest, 1e-7);
  for (const std::string other :
       {"BoxTextured-glTF-Embedded/BoxTextured.gltf", "BoxTextured-glTF-Binary/BoxTextured.glb"}) {
    const LoadedMesh same = load_mesh_file(folder + other, MeshTransform{}, MeshNormals::kFile);
    EXPECT_EQ(same.surface->uvs, surface.uvs) << other;
    EXPECT_EQ(same.surface->mesh.positions, surface.mesh.positions) << other;
  }
}

// A one-triangle glTF 2.0 file, its buffer embedded as base64: positions,
// then UVs, then the vertex normals where given, as floats; `uvs` may hold
// what OBJ's text cannot carry through Assimp (its `vt nan` reads as 0), a
// NaN.
json gltf_triangle_document(const std::array<float, 9>& positions, const std::array<float, 6>& uvs,
                            const std::array<float, 9>* normals = nullptr) {
  std::string bytes(sizeof positions + sizeof uvs + (normals ? sizeof *normals : 0), '\0');
  std::memcpy(bytes.data(), positions.data(), sizeof positions);
  std::memcpy(bytes.data() + sizeof positions, uvs.data(), sizeof uvs);
  if (normals)
    std::memcpy(bytes.data() + sizeof positions + sizeof uvs, normals->data(), sizeof *normals);
  static const char* digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string base64;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    std::uint32_t n = std::uint32_t(std::uint8_t(bytes[i])) << 16;
    if (i + 1 < bytes.size()) n |= std::uint32_t(std::uint8_t(bytes[i + 1])) << 8;
    if (i + 2 < bytes.size()) n |= std::uint8_t(bytes[i + 2]);
    for (std::size_t k = 0; k < 4; ++k)
      base64 += i + k <= bytes.size() ? digits[(n >> (18 - 6 * k)) & 63] : '=';
  }
  json doc = {
      {"asset", {{"version", "2.0"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"mesh", 0}}}},
      {"meshes",
       {{{"primitives", {{{"attributes", {{"POSITION", 0}, {"TEXCOORD_0", 1}}}, {"mode", 4}}}}}}},
      {"buffers",
       {{{"byteLength", bytes.size()}, {"uri", "data:application/octet-stream;base64," + base64}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", sizeof positions}},
        {{"buffer", 0}, {"byteOffset", sizeof positions}, {"byteLength", sizeof uvs}}}},
      {"accessors",
       {{{"bufferView", 0},
         {"componentType", 5126},
         {"count", 3},
         {"type", "VEC3"},
         {"min", {0, 0, 0}},
         {"max", {1, 1, 0}}},
        {{"bufferView", 1}, {"componentType", 5126}, {"count", 3}, {"type", "VEC2"}}}}};
  if (normals) {
    doc["bufferViews"].push_back({{"buffer", 0},
                                  {"byteOffset", sizeof positions + sizeof uvs},
                                  {"byteLength", sizeof *normals}});
    doc["accessors"].push_back(
        {{"bufferView", 2}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}});
    doc["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = 2;
  }
  return doc;
}
std::string gltf_triangle(const std::array<float, 9>& positions, const std::array<float, 6>& uvs) {
  return gltf_triangle_document(positions, uvs).dump();
}

// A node of a file is read where it sits in the whole file: a glTF
// triangle with tilted vertex normals under a child node (rotation and a
// non-uniform scale) of a parent (rotation and translation), read by its
// child's name, against the whole file read through Assimp's own
// aiProcess_PreTransformVertices (its positions within 1e-6 of the scene's
// size, its normals' directions within 1e-6: float matrices either way);
// the parent's name gives the same triangle; a name the file lacks is
// refused at /shape/node with the names it has, as an empty one is; and
// the glTF ClearCoat sample's row R3_BaseNormals is its three tiles, each
// vertex one of the whole file's.
TEST_F(MeshShapeTest, ANodeIsReadWhereItSitsInTheFile) {
  const std::array<float, 9> positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const float s = 1.0f / std::sqrt(1.09f);
  const std::array<float, 9> normals = {0.3f * s, 0, s, 0, 0.3f * s, s, -0.3f * s, 0, s};
  json doc = gltf_triangle_document(positions, {0, 0, 1, 0, 0, 1}, &normals);
  doc["nodes"] = {{{"name", "parent"},
                   {"children", {1}},
                   {"rotation", {0.0, 0.38268343, 0.0, 0.92387953}},  // 45 degrees about y
                   {"translation", {1.0, -2.0, 0.5}}},
                  {{"name", "child"},
                   {"mesh", 0},
                   {"rotation", {0.25881905, 0.0, 0.0, 0.96592583}},  // 30 degrees about x
                   {"scale", {2.0, 0.5, 1.0}}}};
  std::ofstream(path("nodes.gltf")) << doc.dump();
  const LoadedMesh whole = load_mesh_file(path("nodes.gltf"), MeshTransform{}, MeshNormals::kFile);
  for (const char* node : {"child", "parent"}) {
    const LoadedMesh part =
        load_mesh_file(path("nodes.gltf"), MeshTransform{}, MeshNormals::kFile, node);
    const TriangleMesh &a = part.surface->mesh, &b = whole.surface->mesh;
    ASSERT_EQ(a.triangles, b.triangles) << node;
    for (std::size_t v = 0; v < a.vertex_count(); ++v) {
      const auto at = [](const std::vector<float>& x, std::size_t i) {
        return Vec3{x[3 * i], x[3 * i + 1], x[3 * i + 2]};
      };
      EXPECT_LT(length(at(a.positions, v) - at(b.positions, v)), 1e-6 * 3.0) << node << " " << v;
      EXPECT_LT(length(normalize(at(a.normals, v)) - normalize(at(b.normals, v))), 1e-6)
          << node << " " << v;
    }
  }
  json scene = small_scene();
  for (const char* node : {"stranger", ""}) {
    scene["shape"] = {{"type", "mesh"}, {"file", path("nodes.gltf")}, {"node", node}};
    try {
      scene_from_json(scene, "scene.json");
      ADD_FAILURE() << "node \"" << node << "\" was read";
    } catch (const InputError& e) {
      EXPECT_EQ(e.pointer(), "/shape/node");
      if (*node) {
        EXPECT_NE(std::string(e.what()).find("\"parent\", \"child\""), std::string::npos)
            << e.what();
      }
    }
  }
  const std::string clear_coat = "/usr/share/assimp/models/glTF2/ClearCoat-glTF/ClearCoatTest.gltf";
  ASSERT_TRUE(std::filesystem::exists(clear_coat)) << "apt-get install assimp-testmodels";
  const TriangleMesh all = load_mesh_file(clear_coat, {}, MeshNormals::kFile).surface->mesh;
  const TriangleMesh row =
      load_mesh_file(clear_coat, {}, MeshNormals::kFile, "R3_BaseNormals").surface->mesh;
  std::size_t tiles = 0;
  for (const char* tile : {"R3_BaseLayerSample", "R3_ClearCoatSample", "R3_CoatOnlySample"})
    tiles +=
        load_mesh_file(clear_coat, {}, MeshNormals::kFile, tile).surface->mesh.triangle_count();
  EXPECT_EQ(row.triangle_count(), tiles);
  EXPECT_LT(row.triangle_count(), all.triangle_count());
  // Float matrices applied in float (Assimp) or double (the reader) may
  // part by an ulp: 1e-5 of these few units.
  std::size_t found = 0;
  for (std::size_t v = 0; v < row.vertex_count(); ++v)
    for (std::size_t w = 0; w < all.vertex_count(); ++w)
      if (std::abs(row.positions[3 * v] - all.positions[3 * w]) < 1e-5f &&
          std::abs(row.positions[3 * v + 1] - all.positions[3 * w + 1]) < 1e-5f &&
          std::abs(row.positions[3 * v + 2] - all.positions[3 * w + 2]) < 1e-5f) {
        ++found;
        break;
      }
  EXPECT_EQ(found, row.vertex_count());
}

// A mesh file's own normal texture is its normal map where /height/file is
// absent: the ClearCoat sample's tile R3_BaseLayerSample (RibsNormal.png)
// renders the bits of the same scene naming that file; the whole sample,
// whose tiles name two textures and some none, is refused at /height/file
// naming them, as a file whose materials name none is; and a file naming
// one is shaded with it by default (asset_scene_document).
TEST_F(MeshShapeTest, AMeshsOwnNormalTextureIsItsNormalMap) {
  const std::string folder = "/usr/share/assimp/models/glTF2/ClearCoat-glTF/";
  ASSERT_TRUE(std::filesystem::exists(folder + "ClearCoatTest.gltf"))
      << "apt-get install assimp-testmodels";
  json scene = small_scene();
  scene["shape"] = {
      {"type", "mesh"}, {"file", folder + "ClearCoatTest.gltf"}, {"node", "R3_BaseLayerSample"}};
  scene["representation"] = "bump";
  scene["height"] = {{"type", "normal-map"}};
  json named = scene;
  named["height"]["file"] = folder + "RibsNormal.png";
  const Image own = render(scene_from_json(scene, "own")),
              file = render(scene_from_json(named, "named"));
  EXPECT_EQ(own.pixels, file.pixels);
  json flat = scene;
  flat["height"] = {{"type", "none"}};
  EXPECT_NE(own.pixels, render(scene_from_json(flat, "no map")).pixels);
  const auto refused = [&](const json& doc, const std::string& reason) {
    try {
      scene_from_json(doc, "scene.json");
      ADD_FAILURE() << "read without a normal texture: " << reason;
    } catch (const InputError& e) {
      EXPECT_EQ(e.pointer(), "/height/file");
      EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
    }
  };
  json whole = scene;
  whole["shape"].erase("node");
  refused(whole, "2 normal textures (RibsNormal.png, PlasticWrap_normals.jpg) and some none");
  std::ofstream(path("plain.gltf"))
      << gltf_triangle({0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 0, 1, 0, 0, 1});
  json plain = scene;
  plain["shape"] = {{"type", "mesh"}, {"file", path("plain.gltf")}};
  refused(plain, "name no normal texture");
  EXPECT_FALSE(asset_scene_document(path("plain.gltf")).contains("height"));
  json textured = gltf_triangle_document({0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 0, 1, 0, 0, 1});
  textured["materials"] = {{{"normalTexture", {{"index", 0}}}}};
  textured["textures"] = {{{"source", 0}}};
  textured["images"] = {{{"uri", "ribs.png"}}};
  textured["meshes"][0]["primitives"][0]["material"] = 0;
  std::ofstream(path("textured.gltf")) << textured.dump();
  std::filesystem::copy_file(folder + "RibsNormal.png", path("ribs.png"));
  const json asset = asset_scene_document(path("textured.gltf"));
  EXPECT_EQ(asset.at("height"), json({{"type", "normal-map"}}));
  EXPECT_EQ(scene_from_json(asset, "asset").height.map->digest,
            scene_from_json(named, "named").height.map->digest);
}

// Texture coordinates that are not numbers are refused where the file is
// named, with the vertex; the same triangle with finite ones loads with
// them. (Assimp keeps a glTF buffer's floats as they are.)
TEST_F(MeshShapeTest, ATriangleWithANanUvIsRefusedWithTheVertex) {
  const std::array<float, 9> positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  std::ofstream(path("good.gltf")) << gltf_triangle(positions, {0, 0, 1, 0, 0, 1});
  const LoadedMesh good = load_mesh_file(path("good.gltf"), MeshTransform{}, MeshNormals::kSmooth);
  ASSERT_EQ(good.surface->uvs.size(), 6u);
  EXPECT_EQ(good.surface->uvs[2], 1.0f);
  EXPECT_EQ(good.surface->uvs[5], 0.0f);  // v = 1 in the file, turned up
  std::ofstream(path("nan.gltf")) << gltf_triangle(
      positions, {0, 0, 1, std::numeric_limits<float>::quiet_NaN(), 0, 1});
  json scene = small_scene();
  scene["shape"] = {{"type", "mesh"}, {"file", path("nan.gltf")}};
  try {
    scene_from_json(scene, "scene.json");
    ADD_FAILURE() << "a NaN texture coordinate was read";
  } catch (const InputError& e) {
    EXPECT_EQ(e.pointer(), "/shape/file");
    EXPECT_NE(std::string(e.what()).find("texture coordinates of vertex"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("nan.gltf"), std::string::npos) << e.what();
  }
}

TEST_F(MeshShapeTest, MutatedMeshFilesLoadOrAreRefused) {
  const Scene tessellated = scene_from_json(small_scene(), "built-in");
  const TriangleMesh sphere = tessellate(tessellated.shape, *tessellated.tessellation);
  write_ply(sphere, path("parent.ply"));
  std::ifstream ply_in(path("parent.ply"), std::ios::binary);
  const std::string ply((std::istreambuf_iterator<char>(ply_in)), std::istreambuf_iterator<char>());
  // The third and fourth parents carry UVs and are rendered with a normal
  // map or a height map over them (MikkTSpace on mutated UVs and
  // positions); the fourth is a real glTF 2.0 asset, its buffer embedded in
  // the JSON as base64, so that a mutation reaches the JSON and the data.
  std::ifstream gltf_in(
      "/usr/share/assimp/models/glTF2/BoxTextured-glTF-Embedded/BoxTextured.gltf");
  const std::string gltf((std::istreambuf_iterator<char>(gltf_in)),
                         std::istreambuf_iterator<char>());
  ASSERT_FALSE(gltf.empty()) << "assimp-testmodels is not installed";
  const std::string parents[4] = {obj_text(sphere), ply, obj_text_with_uvs(sphere), gltf};
  const char* extensions[4] = {".obj", ".ply", ".obj", ".gltf"};
  write_exr(bake_surface_map(tessellated.shape, make_grating({1, 0.4, 0}, 3.0, 0.0), 0.05, 16, 8,
                             MapKind::kNormal),
            path("normal.exr"));
  write_exr(bake_surface_map(tessellated.shape, make_grating({1, 0.4, 0}, 3.0, 0.0), 1.0, 16, 8,
                             MapKind::kHeight),
            path("height.exr"));
  const char* tokens[] = {"nan", "inf", "-1",    "1e300",           "99999999",
                          "\n",  " ",   "f 1 2", "element face 7\n"};
  Pcg32 rng(20261128);
  int loaded = 0, refused = 0, assimp_checks = 0;
  std::array<int, 4> loaded_of{};
  for (int m = 0; m < 800; ++m) {
    const int which = m % 4;
    std::string text = parents[which];
    const int edits = 1 + int(rng.next_double() * 4);
    for (int e = 0; e < edits && !text.empty(); ++e) {
      const std::size_t at = std::size_t(rng.next_double() * double(text.size()));
      const double kind = rng.next_double();
      if (kind < 0.3)
        text[at] = char(rng.next_double() * 256);
      else if (kind < 0.6)
        text.insert(at, tokens[std::size_t(rng.next_double() * std::size(tokens))]);
      else if (kind < 0.8)
        text.resize(at);
      else
        text.erase(
            at, std::min<std::size_t>(text.size() - at, 1 + std::size_t(rng.next_double() * 40)));
    }
    const std::string file = path(std::string("mutant") + extensions[which]);
    std::ofstream(file, std::ios::binary) << text;
    json scene = small_scene();
    scene["shape"] = {{"type", "mesh"}, {"file", file}};
    scene["camera"]["width"] = scene["camera"]["height"] = 8;
    if (which >= 2) {
      scene["representation"] = "bump";
      scene["height"] =
          m % 2 == 0
              ? json{{"type", "normal-map"}, {"file", path("normal.exr")}}
              : json{{"type", "height-map"}, {"file", path("height.exr")}, {"amplitude", 0.01}};
    }
    try {
      const Scene s = scene_from_json(scene, "scene.json");
      const Image image = render(s);
      EXPECT_TRUE(std::all_of(image.pixels.begin(), image.pixels.end(),
                              [](float v) { return std::isfinite(v); }))
          << "mutant " << m;
      ++loaded;
      ++loaded_of[std::size_t(which)];
    } catch (const InputError& e) {
      // A mutant that lost its UVs is refused at the map that needs them.
      EXPECT_TRUE(e.pointer() == "/shape/file" || (which >= 2 && e.pointer() == "/height/type"))
          << "mutant " << m << ": " << e.what();
      ++refused;
      // Assimp's failed assertions are refusals here, not aborts (mesh_file.cpp).
      if (std::string(e.what()).find("failed its own check") != std::string::npos) {
        if (assimp_checks++ == 0)
          std::filesystem::copy_file(file, path("assert" + std::string(extensions[which])));
      }
    }
  }
  std::printf(
      "mesh file mutants: %d loaded (OBJ %d, PLY %d, OBJ with UVs %d, glTF %d), %d refused (%d by "
      "a failed Assimp assertion)\n",
      loaded, loaded_of[0], loaded_of[1], loaded_of[2], loaded_of[3], refused, assimp_checks);
  EXPECT_GT(loaded, 30);
  EXPECT_GT(loaded_of[3], 0);  // some glTF mutants load, or the glTF side tests only refusals
  EXPECT_GT(refused, 30);
  // The installed binary refuses such a file too (exit 2), rather than abort.
  for (const char* extension : extensions) {
    const std::string file = path(std::string("assert") + extension);
    if (!std::filesystem::exists(file)) continue;
    json scene = small_scene();
    scene["shape"] = {{"type", "mesh"}, {"file", file}};
    std::ofstream(path("scene.json")) << scene.dump();
    const std::string command = std::string(PENUMBRA_BINARY) + " render " + path("scene.json") +
                                " -o " + path("out.exr") + " 2> " + path("err.txt");
    const int status = std::system(command.c_str());
    std::ifstream err_in(path("err.txt"));
    const std::string err((std::istreambuf_iterator<char>(err_in)),
                          std::istreambuf_iterator<char>());
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 2) << command << ": " << err;
    EXPECT_NE(err.find("/shape/file"), std::string::npos) << err;
  }
}

}  // namespace
}  // namespace penumbra
