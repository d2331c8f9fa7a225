// Cost of the shadow-ray origin methods (core/shadow_origin.h) on low-poly,
// smooth-shaded spheres:
//   origin/METHOD             ns per shadow_ray_origin call, 16-segment UV sphere
//   shadow_ray/SIZE/METHOD    ns per complete shadow ray (origin + occlusion with
//                             skip-self) on a ~1k and a ~1M triangle UV sphere
//   render/SIZE/METHOD        penumbra::render of the sphere scene (256x256, 4 spp,
//                             all cores): camera samples per wall second (mesh and
//                             BVH build excluded) and build time
// Queries are hits near the terminator (0 < dot(Ni, wi) <= 0.25) from a fixed
// seed, so every run sees the same pool. Scenes go through scene_from_json,
// validated like user scenes. Timings only: nothing here asserts on them.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/random.h"
#include "core/shadow_origin.h"
#include "evaluator/evaluator.h"
#include "evaluator/lowpoly_mesh.h"
#include "scene/scene_json.h"

namespace {

using nlohmann::json;
using penumbra::LowPolyMesh;
using penumbra::OffsetMethod;
using penumbra::OffsetSettings;
using penumbra::Scene;
using penumbra::ShadowQuery;
using penumbra::Vec3;

constexpr std::size_t kPoolSize = 4096;  // power of two: the index wraps with a mask
constexpr std::uint64_t kSeed = 20240611;

// scenes/lowpoly/sphere.json, with the tessellation, offset and image size as
// parameters.
Scene lowpoly_sphere(unsigned segments, unsigned rings, std::string_view offset, int size,
                     int spp) {
  json document = json::parse(R"({
    "version": 1,
    "name": "bench-lowpoly-sphere",
    "camera": {
      "projection": "orthographic",
      "position": [0, 0, -5],
      "direction": [0, 0, 1],
      "right": [2.5, 0, 0],
      "up": [0, 2.5, 0],
      "width": 256,
      "height": 256,
      "spp": 4,
      "seed": 1
    },
    "light": {"type": "distant", "direction": [-1, 0.3, -0.2], "irradiance": 3.141592653589793},
    "shape": {
      "type": "sphere",
      "center": [0, 0, 0],
      "axis": [0, 1, 0],
      "radius": 1.0,
      "tessellation": {"scheme": "uv", "segments": 16, "shading": "smooth"}
    },
    "material": {"albedo": 0.8},
    "representation": "smooth",
    "offset": {"method": "none"}
  })");
  document["camera"]["width"] = size;
  document["camera"]["height"] = size;
  document["camera"]["spp"] = spp;
  document["shape"]["tessellation"]["segments"] = segments;
  if (rings != 0) document["shape"]["tessellation"]["rings"] = rings;
  document["offset"]["method"] = offset;
  return penumbra::scene_from_json(document, "<bench_offsets>");
}

// A mesh and a pool of shadow queries on it, as LowPolyTracer::shadow_ray
// builds them for a front-facing hit.
struct Fixture {
  Scene scene;
  std::unique_ptr<LowPolyMesh> mesh;
  std::vector<ShadowQuery> queries;
  std::vector<std::uint32_t> triangles;  // the triangle each query was hit on
};

Vec3 uniform_sphere(penumbra::Pcg32& rng) {
  const double z = 1.0 - 2.0 * rng.next_double();
  const double phi = 2.0 * penumbra::kPi * rng.next_double();
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  return {r * std::cos(phi), r * std::sin(phi), z};
}

// Rays from all around the sphere towards its centre; hits whose Ni sees the
// light at a grazing angle are kept (the terminator band).
std::unique_ptr<Fixture> make_fixture(unsigned segments, unsigned rings) {
  auto f = std::make_unique<Fixture>();
  f->scene = lowpoly_sphere(segments, rings, "none", 256, 4);
  f->mesh = std::make_unique<LowPolyMesh>(f->scene.shape, *f->scene.tessellation);
  const Vec3 wi = f->scene.light.direction;
  const double reach = 3.0 * f->scene.shape.radius;
  penumbra::Pcg32 rng(kSeed);
  for (int attempt = 0; f->queries.size() < kPoolSize; ++attempt) {
    if (attempt > 1000 * int(kPoolSize)) throw std::runtime_error("query pool: too few hits");
    const Vec3 d = uniform_sphere(rng);
    const auto hit = f->mesh->intersect({f->scene.shape.center + d * reach, -d});
    if (!hit) continue;
    const double cos_s = dot(hit->ni, wi);
    if (!(cos_s > 0.0 && cos_s <= 0.25)) continue;
    ShadowQuery q;
    q.triangle = f->mesh->shading_triangle(*hit, false);
    q.p = hit->p;
    q.ng = hit->ng;
    q.ns = hit->ni;
    q.wi = wi;
    q.backfacing = false;
    f->queries.push_back(q);
    f->triangles.push_back(hit->triangle);
  }
  return f;
}

const Fixture& fixture(unsigned segments, unsigned rings) {
  static std::map<std::pair<unsigned, unsigned>, std::unique_ptr<Fixture>> cache;
  auto& slot = cache[{segments, rings}];
  if (!slot) slot = make_fixture(segments, rings);
  return *slot;
}

OffsetSettings settings_for(OffsetMethod method) {
  OffsetSettings s;  // defaults: epsilon 0.01, cutoff 0.1 (as the scene reader's)
  s.method = method;
  return s;
}

// 16-segment UV sphere (rings default to 8: 224 triangles).
void bm_origin(benchmark::State& state, OffsetMethod method) {
  const Fixture& f = fixture(16, 0);
  const OffsetSettings settings = settings_for(method);
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(penumbra::shadow_ray_origin(settings, f.queries[i]));
    i = (i + 1) & (kPoolSize - 1);
  }
  state.counters["triangles"] = double(f.mesh->triangle_count());
}

struct MeshSize {
  const char* name;
  unsigned segments, rings;
};
constexpr MeshSize kMeshSizes[] = {{"1k", 32, 16}, {"1M", 1024, 512}};

void bm_shadow_ray(benchmark::State& state, MeshSize size, OffsetMethod method) {
  const Fixture& f = fixture(size.segments, size.rings);
  const OffsetSettings settings = settings_for(method);
  const double t_min = 1e-6 * f.scene.shape.radius;  // as LowPolyTracer
  const double t_max = std::numeric_limits<double>::infinity();
  std::size_t i = 0;
  std::uint64_t blocked = 0;
  for (auto _ : state) {
    const ShadowQuery& q = f.queries[i];
    const penumbra::ShadowOrigin o = penumbra::shadow_ray_origin(settings, q);
    const bool hit = f.mesh->occluded({o.origin, q.wi}, t_min, t_max,
                                      o.skip_self ? f.triangles[i] : penumbra::kNoTriangle);
    blocked += hit ? 1 : 0;
    i = (i + 1) & (kPoolSize - 1);
  }
  state.counters["triangles"] = double(f.mesh->triangle_count());
  // Share of the pool's lit-side rays that came back shadowed (self-shadowing).
  state.counters["occluded"] =
      state.iterations() > 0 ? double(blocked) / double(state.iterations()) : 0.0;
}

void bm_render(benchmark::State& state, MeshSize size, std::string_view offset) {
  const Scene scene = lowpoly_sphere(size.segments, size.rings, offset, 256, 4);
  double render_seconds = 0.0, build_seconds = 0.0;
  std::uint64_t samples = 0;
  std::size_t triangles = 0;
  for (auto _ : state) {
    penumbra::RenderStats stats;
    benchmark::DoNotOptimize(penumbra::render(scene, {}, &stats));
    render_seconds += stats.seconds - stats.build_seconds;
    build_seconds += stats.build_seconds;
    samples += stats.camera_samples;
    triangles = stats.triangles;
  }
  const double n = double(std::max<benchmark::IterationCount>(state.iterations(), 1));
  state.counters["triangles"] = double(triangles);
  // Camera samples per second of the render proper (mesh and BVH build excluded).
  state.counters["Msamples_per_s"] =
      render_seconds > 0.0 ? double(samples) / render_seconds / 1e6 : 0.0;
  state.counters["build_s"] = build_seconds / n;
}

const int registered = [] {
  for (const auto& info : penumbra::all_offset_methods())
    benchmark::RegisterBenchmark(("origin/" + std::string(info.id)).c_str(), bm_origin,
                                 info.method);
  for (const MeshSize& size : kMeshSizes)
    for (const auto& info : penumbra::all_offset_methods())
      benchmark::RegisterBenchmark(
          ("shadow_ray/" + std::string(size.name) + "/" + std::string(info.id)).c_str(),
          bm_shadow_ray, size, info.method);
  for (const MeshSize& size : kMeshSizes)
    for (const std::string_view offset : {"hanika2021", "none"})
      benchmark::RegisterBenchmark(
          ("render/" + std::string(size.name) + "/" + std::string(offset)).c_str(), bm_render, size,
          offset)
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime()
          ->MeasureProcessCPUTime();  // CPU column: all threads (2 x Time when none waits)
  return 0;
}();

}  // namespace

BENCHMARK_MAIN();
