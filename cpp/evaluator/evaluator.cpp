#include "evaluator/evaluator.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <type_traits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <fmt/format.h>

#include "core/light_sampling.h"
#include "core/mesh_surface.h"
#include "core/random.h"
#include "core/ray_packet.h"
#include "core/shading.h"
#include "evaluator/displaced_mesh.h"
#include "evaluator/lowpoly_mesh.h"

namespace penumbra {

const std::vector<std::string>& evaluator_channels() {
  static const std::vector<std::string> channels{
      "R", "G", "B", "A", "analysis.theta", "analysis.deviation", "analysis.G", "analysis.view"};
  return channels;
}

namespace {

using Clock = std::chrono::steady_clock;

struct LightSample {
  Vec3 wi;
  double irradiance = 0.0;  // W/m^2 on a plane facing the light
  double distance = 0.0;    // to the light; infinite for a distant light
};

// Where an area light is sampled for one camera sample, in [0,1)^2.
struct LightUniforms {
  double u1 = 0.5, u2 = 0.5;
};

// A direction from the light's own sampler: the point of an area light
// that `u` picks; delta lights ignore u.
LightDirectionSample light_direction(const Light& light, const Vec3& p, double u1, double u2,
                                     double* radiance) {
  switch (light.type) {
    case LightType::kEnvironment: {
      const LightDirectionSample s = light.environment->sample(u1, u2, radiance);
      *radiance *= light.scale;
      return s;
    }
    case LightType::kSphere:
      *radiance = light.radiance;
      return sample_sphere_light(light.position, light.radius, p, u1, u2);
    case LightType::kQuad:
      *radiance = light.radiance;
      return sample_rectangle_light(light.corner, light.edge_u, light.edge_v, p, u1, u2);
    case LightType::kDistant:
    case LightType::kPoint:
    case LightType::kGroup:  // sample_light draws a member
      break;
  }
  *radiance = 0.0;
  return {};
}

// The light's sampler's density at wi (another strategy drew it), with the
// distance to the emitter and its radiance there; pdf 0 where wi misses it.
LightDirectionSample light_density(const Light& light, const Vec3& p, const Vec3& wi,
                                   double* radiance) {
  *radiance = 0.0;
  switch (light.type) {
    case LightType::kEnvironment:
      *radiance = light.environment->radiance(wi) * light.scale;
      return {wi, light.environment->pdf(wi), std::numeric_limits<double>::infinity()};
    case LightType::kSphere:
      *radiance = light.radiance;
      return sphere_light_pdf(light.position, light.radius, p, wi);
    case LightType::kQuad:
      *radiance = light.radiance;
      return rectangle_light_pdf(light.corner, light.edge_u, light.edge_v, p, wi);
    case LightType::kDistant:
    case LightType::kPoint:
    case LightType::kGroup:  // sample_light draws a member
      break;
  }
  return {};
}

// The share of an area light's samples its own sampler draws under
// LightSampling::kMis; the rest are cosine-weighted about the normal.
constexpr double kMisLightShare = 0.5;

// `u` picks the point of an area light; delta lights ignore it. The
// sample's irradiance is radiance / pdf (core/light_sampling.h); a sample
// that reaches no emitter has irradiance 0. Under LightSampling::kMis the
// strategy is drawn per sample from u1 (the light's sampler below
// kMisLightShare, else cosine-weighted directions about n, the unit normal
// facing the viewer), and the sample's pdf is the two strategies' mixture:
// Veach's one-sample model with the balance heuristic (Veach 1997, section
// 9.2.4), the weighting that model is optimal with. Its sample costs one
// shadow ray, as a light sample does.
LightSample sample_light(const Light& light, const Vec3& p, const LightUniforms& u,
                         const Vec3& n = {}) {
  switch (light.type) {
    case LightType::kGroup: {
      // One light per sample: u1 picks it by member_cdf and is stretched
      // back over [0, 1) within its share, for the light's own sampling.
      const std::vector<double>& cdf = light.member_cdf;
      const std::size_t k =
          std::size_t(std::upper_bound(cdf.begin() + 1, cdf.end() - 1, u.u1) - (cdf.begin() + 1));
      const double share = cdf[k + 1] - cdf[k];
      const LightUniforms within{std::clamp((u.u1 - cdf[k]) / share, 0.0, std::nextafter(1.0, 0.0)),
                                 u.u2};
      LightSample s = sample_light(light.members[k], p, within, n);
      s.irradiance /= share;
      return s;
    }
    case LightType::kDistant:
      return {light.direction, light.irradiance, std::numeric_limits<double>::infinity()};
    case LightType::kPoint: {
      const Vec3 to_light = light.position - p;
      const double d2 = length_squared(to_light);
      const double d = std::sqrt(d2);
      return {to_light / d, light.intensity / d2, d};
    }
    case LightType::kEnvironment:
    case LightType::kSphere:
    case LightType::kQuad:
      break;
  }
  double radiance = 0.0;
  if (light.sampling == LightSampling::kLight) {
    const LightDirectionSample s = light_direction(light, p, u.u1, u.u2, &radiance);
    if (!(s.pdf > 0.0)) return {Vec3{0, 0, 1}, 0.0, 0.0};
    return {s.wi, radiance / s.pdf, s.distance};
  }
  constexpr double c = kMisLightShare;
  LightDirectionSample s;
  double pdf_cosine = 0.0;
  if (u.u1 < c) {
    s = light_direction(light, p, u.u1 / c, u.u2, &radiance);
    if (!(s.pdf > 0.0)) return {Vec3{0, 0, 1}, 0.0, 0.0};
    pdf_cosine = cosine_direction_pdf(n, s.wi);
  } else {
    const Vec3 wi = sample_cosine_direction(n, (u.u1 - c) / (1.0 - c), u.u2);
    pdf_cosine = cosine_direction_pdf(n, wi);
    s = light_density(light, p, wi, &radiance);
    if (!(s.pdf > 0.0) || !(pdf_cosine > 0.0)) return {Vec3{0, 0, 1}, 0.0, 0.0};
  }
  return {s.wi, radiance / (c * s.pdf + (1.0 - c) * pdf_cosine), s.distance};
}

// Whether the scene's samples nest (core/sample_pattern.h): a jittered
// camera's displacement truths, which a check at 4^k times the samples
// extends (RenderOptions::resume). Other renders keep the plain grid at
// every count: nothing extends them, and the nested order cost a 256-sample
// bump render 1.7x its time (SIMD packets of scattered samples).
bool nested_samples(const Scene& scene) {
  return scene.camera.jitter && scene.representation == Representation::kDisplacement;
}

// The area-light point of sample s of a pixel: the pixel's samples fall in
// the same nx x ny strata as its camera samples, shuffled (permute_index)
// so that a sample's light stratum does not follow its camera stratum, and
// jittered within, counter-based from the pixel's key like the camera's;
// nested where the camera's are (nested_samples).
LightUniforms light_uniforms(const Scene& scene, std::uint64_t pixel_key, int s, int nx, int ny) {
  if (!is_area_light(scene.light)) return {};
  constexpr std::uint64_t kLightStream = 0x6c69676874ull;  // "light"
  const std::uint64_t key = mix64(pixel_key ^ kLightStream);
  const StratumPoint p =
      stratum_point(s, scene.camera.spp,
                    {key, true, static_cast<std::uint32_t>(key >> 32u), nested_samples(scene)});
  return {(p.sx + p.x) / nx, (p.sy + p.y) / ny};
}

// The cosine of analysis.theta at base point p of normal n: of the sampled
// direction wi for a delta light (the one direction there is), of the light
// vector (scene.h, light_vector) for an area light, so that a pixel's
// angle says where the light comes from on balance rather than where its
// samples happened to land; 0 (90 degrees) where that vector vanishes.
double cos_light_angle(const Light& light, const Vec3& n, const Vec3& p, const Vec3& wi) {
  if (!is_area_light(light)) return dot(n, wi);
  const Vec3 v = light_vector(light, p);
  const double norm = length(v);
  return norm > 0.0 ? std::clamp(dot(n, v) / norm, -1.0, 1.0) : 0.0;
}

// What a camera ray sees: the surface point to shade and how to leave it.
struct SurfaceHit {
  double t = 0.0;
  SurfaceGeometry geometry;  // base surface (under the hit, for displacement and meshes)
  Vec3 shading_point;        // where light is evaluated and shadow rays start
  // The true normal and the interpolated one, as the surface stores them
  // (not yet turned towards the viewer). Analytic shapes: both geometry.n.
  Vec3 ng, ni;
  LowPolyHit triangle;  // low-poly meshes only
  bool on_prop = false;
  // A mesh shape's truth: the exact normal of its displaced surface, which
  // the tracer knows from the base triangle (mesh_displaced_normal).
  bool has_exact_ns = false;
  Vec3 exact_ns;
};

// Where a shadow ray starts, and which mesh triangle it ignores.
struct ShadowRay {
  Vec3 origin;
  std::uint32_t skip = kNoTriangle;
};

// The normals at a hit after turning them towards the viewer.
struct FacingNormals {
  Vec3 ng, ns;
  bool backfacing = false;
};

// Smooth and bump: the analytic base shape is both what the camera sees and
// what casts shadows (that is what makes the bump terminator hard).
class BaseTracer {
 public:
  explicit BaseTracer(const Scene& scene)
      : shape_(scene.shape), t_min_(1e-7 * scene.shape.radius) {}

  bool primary(const Ray& ray, SurfaceHit* out) const {
    Hit hit;
    if (!penumbra::intersect(shape_, ray, 0.0, std::numeric_limits<double>::infinity(), &hit))
      return false;
    out->t = hit.t;
    out->geometry = hit.geometry;
    out->shading_point = hit.geometry.p;
    out->ng = out->ni = hit.geometry.n;
    return true;
  }
  ShadowRay shadow_ray(const SurfaceHit& hit, const FacingNormals&, const Vec3&) const {
    return {hit.shading_point};
  }
  // The origin lies on the analytic surface, so the root at t = 0 is skipped
  // by a relative epsilon rather than by moving the origin.
  bool occluded(const ShadowRay& ray, const Vec3& wi, double distance) const {
    return penumbra::occluded(shape_, {ray.origin, wi}, t_min_, distance);
  }
  double shadow_t_min() const { return t_min_; }

 private:
  const Shape& shape_;
  double t_min_;
};

// Displacement: the displaced surface, tessellated, is what the camera sees
// and what casts shadows. Shading happens at the exact displaced point with
// the exact normal; shadow rays leave it lifted off the facets.
class MeshTracer {
 public:
  MeshTracer(const Scene& scene, const DisplacedMesh& mesh)
      : mesh_(mesh),
        amplitude_(scene.height.amplitude),
        height_(scene.height.function),
        map_(scene.height.height_map()),
        shape_(scene.shape) {}

  bool primary(const Ray& ray, SurfaceHit* out) const {
    const auto hit = mesh_.intersect(ray);
    if (!hit) return false;
    set_hit(*hit, out);
    return true;
  }
  // primary() of n <= kPacketRays rays at once: one Embree packet, which
  // traverses the BVH faster than n single rays when they are coherent.
  static constexpr std::size_t kPacketRays = DisplacedMesh::kPacketRays;
  void primary_packet(const Ray* rays, std::size_t n, SurfaceHit* out, bool* found) const {
    MeshHit hits[kPacketRays];
    mesh_.intersect_packet(rays, n, hits, found);
    for (std::size_t k = 0; k < n; ++k)
      if (found[k]) set_hit(hits[k], &out[k]);
  }
  ShadowRay shadow_ray(const SurfaceHit& hit, const FacingNormals& n, const Vec3&) const {
    return {hit.shading_point + n.ns * mesh_.shadow_offset(hit.triangle.triangle)};
  }
  bool occluded(const ShadowRay& ray, const Vec3& wi, double distance) const {
    return mesh_.occluded({ray.origin, wi}, distance);
  }
  // occluded() of n <= kPacketRays shadow rays at once.
  void occluded_packet(const Ray* rays, const double* distance, std::size_t n,
                       bool* blocked) const {
    mesh_.occluded_packet(rays, distance, n, blocked);
  }

 private:
  void set_hit(const MeshHit& hit, SurfaceHit* out) const {
    out->t = hit.t;
    out->geometry = hit.geometry;
    out->ng = out->ni = hit.geometry.n;
    if (hit.on_mesh) {
      const HeightSample h = height_at(height_, map_, shape_, hit.geometry);
      out->shading_point = displaced_point(hit.geometry, amplitude_, h);
      out->exact_ns =
          mesh_displaced_normal(shape_.mesh->mesh, hit.base_triangle, hit.base_b, amplitude_, h);
      out->has_exact_ns = true;
      out->triangle.triangle = hit.base_triangle;
    } else if (hit.geometry.displaceable)
      out->shading_point =
          displaced_point(hit.geometry, amplitude_, height_at(height_, map_, shape_, hit.geometry));
    else
      out->shading_point = hit.geometry.p;
  }

  const DisplacedMesh& mesh_;
  double amplitude_;
  const HeightFunction& height_;
  const SurfaceMap* map_;
  const Shape& shape_;
};

// A low-poly tessellation: the camera and the shadow rays see flat
// triangles, shading uses the interpolated normal, and the scene's offset
// method decides where shadow rays leave the triangle.
class LowPolyTracer {
 public:
  LowPolyTracer(const Scene& scene, const LowPolyMesh& mesh)
      : mesh_(mesh), offset_(scene.offset), t_min_(1e-6 * scene.shape.radius) {}

  bool primary(const Ray& ray, SurfaceHit* out) const {
    const auto hit = mesh_.intersect(ray);
    if (!hit) return false;
    out->t = hit->t;
    out->geometry = hit->base;
    out->shading_point = hit->p;
    out->ng = hit->ng;
    out->ni = hit->ni;
    out->triangle = *hit;
    return true;
  }
  ShadowRay shadow_ray(const SurfaceHit& hit, const FacingNormals& n, const Vec3& wi) const {
    ShadowQuery q;
    q.triangle = mesh_.shading_triangle(hit.triangle, n.backfacing);
    q.p = hit.shading_point;
    q.ng = n.ng;
    q.ns = n.ns;
    q.wi = wi;
    q.backfacing = n.backfacing;
    const ShadowOrigin o = shadow_ray_origin(offset_, q);
    return {o.origin, o.skip_self ? hit.triangle.triangle : kNoTriangle};
  }
  bool occluded(const ShadowRay& ray, const Vec3& wi, double distance) const {
    return mesh_.occluded({ray.origin, wi}, t_min_, distance, ray.skip);
  }

 private:
  const LowPolyMesh& mesh_;
  const OffsetSettings& offset_;
  double t_min_;
};

// The scene's props: analytic spheres that every tracer's rays also meet.
class Props {
 public:
  explicit Props(const Scene& scene) : props_(scene.props) {}

  bool empty() const { return props_.empty(); }
  // Replaces *out when a prop is nearer than out->t (or when `found` is false).
  bool nearer(const Ray& ray, bool found, SurfaceHit* out) const {
    bool replaced = false;
    for (const Shape& prop : props_) {
      Hit hit;
      const double t_max = found || replaced ? out->t : std::numeric_limits<double>::infinity();
      if (!penumbra::intersect(prop, ray, 0.0, t_max, &hit)) continue;
      *out = SurfaceHit{};
      out->t = hit.t;
      out->geometry = hit.geometry;
      out->geometry.displaceable = false;
      out->shading_point = hit.geometry.p;
      out->ng = out->ni = hit.geometry.n;
      out->on_prop = true;
      replaced = true;
    }
    return replaced;
  }
  bool occluded(const Vec3& origin, const Vec3& wi, double distance) const {
    for (const Shape& prop : props_)
      if (penumbra::occluded(prop, {origin, wi}, 1e-7 * prop.radius, distance)) return true;
    return false;
  }

 private:
  const std::vector<Shape>& props_;
};

// How the surface point under a camera sample moves per pixel step, on the
// tangent plane at the hit (ray differentials, Igehy 1999), scaled by
// max(1/8, 1/sqrt(spp)) as pbrt-v4 scales camera differentials
// (CameraBase::Approximate_dp_dxy): the samples of a pixel share its
// footprint, so each filters only its share.
struct PixelDifferentials {
  Vec3 dpdx, dpdy;
};

PixelDifferentials pixel_differentials(const Camera& c, const Ray& ray, double t, const Vec3& n) {
  const double scale = std::max(0.125, 1.0 / std::sqrt(double(c.spp)));
  const Vec3 step_x = c.right / double(c.width), step_y = c.up / double(c.height);
  double cos_n = dot(ray.direction, n);
  if (std::abs(cos_n) < 1e-9) cos_n = std::copysign(1e-9, cos_n);
  const auto on_plane = [&](const Vec3& step) {
    Vec3 moved = step;  // orthographic: the origin moves, the direction does not
    if (c.projection == Projection::kPerspective) {
      // The unnormalised direction D = direction + x0 right + y0 up has
      // |D| = |direction|^2 / <d, direction> when right and up are
      // orthogonal to direction; the unit direction turns by
      // (step - d <d, step>) / |D|, and the point at distance t with it.
      const double length_d = length_squared(c.direction) / dot(ray.direction, c.direction);
      moved = (step - ray.direction * dot(ray.direction, step)) * (t / length_d);
    }
    return (moved - ray.direction * (dot(moved, n) / cos_n)) * scale;
  };
  return {on_plane(step_x), on_plane(step_y)};
}

// The bump normal of a sample: the analytic or image height's exact
// normal, a normal map's, or a filtered map's mean normal, which also sets
// the sample's filtered specular lobe in *material. On a mesh shape h is
// differentiated over the flat triangle of normal `ng` (facet_bump_gradient).
struct BumpNormals {
  const Scene& scene;
  const SurfaceMap* height_map;
  const SurfaceMap* normal_map;
  const FilteredMap* filtered;

  Vec3 at(const SurfaceGeometry& g, const Vec3& ng, const Ray& ray, double t,
          Material* material) const {
    if (filtered) {
      const PixelDifferentials d = pixel_differentials(scene.camera, ray, t, g.n);
      const FilteredSample f =
          filtered_sample(*filtered, scene.shape, g, d.dpdx, d.dpdy, material->specular_roughness);
      material->filtered = {true, f.lobe.distribution, f.lobe.alpha2, f.tangent};
      return f.ns;
    }
    if (normal_map) return normal_map_normal(*normal_map, scene.shape, g);
    HeightSample h = height_at(scene.height.function, height_map, scene.shape, g);
    if (scene.shape.type == ShapeType::kMesh) h.gradient = facet_bump_gradient(h.gradient, ng, g.n);
    return displaced_normal(g, scene.height.amplitude, h);
  }
};

// A worker's packet: rays and what they hit (about 60 KiB, so on the heap).
struct PacketBuffers {
  SamplePacket samples;
  RayPacket rays;
  HitPacket hits;
};

// What every packet of a render shares: the camera and the light.
struct PacketSetup {
  PacketCamera camera;
  int nx = 1;  // strata across a pixel
  PacketLighting lighting;
};

struct PixelSums {
  double radiance = 0.0, hits = 0.0, theta = 0.0, deviation = 0.0, g = 0.0, g_count = 0.0,
         view = 0.0;
};

// A pass the light reaches at a sample, and the radiance it adds unless the
// shadow ray is blocked.
struct LitPass {
  std::size_t pass = 0;
  double radiance = 0.0;
};

// A sample's shadow ray waiting to be traced with others (shade_deferred):
// its passes' contributions are lit[first, last).
struct PendingShadow {
  ShadowRay ray;
  Vec3 wi;
  double distance = 0.0;
  std::size_t first = 0, last = 0;
};

// Where a render of one raw-bump pass puts each of its samples as well
// (render_tallied; the user methods' passes): add() is called once per
// sample that hits, `lit` when the light reaches it unblocked and raw bump
// gives it radiance `value`; `column`: the sample's pixel in its row.
class SampleSink {
 public:
  virtual ~SampleSink() = default;
  virtual void add(const Material& m, const ShadingPoint& p, double irradiance, double value,
                   bool lit, int column) const = 0;
  // Whether a sample of pixel `column` of the row should carry the height
  // field's visibility though no pass reads it.
  virtual bool wants_visibility(int /*column*/) const { return false; }
};

// Where a tallied render (render_tallied) puts one pixel's unblocked light:
// the part a factor scales, split over the factor grid's nodes by each
// sample's interpolation weights; and, with probes, the pixel's light under
// each probe's factors, every value's after the other.
class TallySink final : public SampleSink {
 public:
  TallySink(const FactorGrid* grid, Lobes lobes, std::vector<std::pair<int, double>>* scaled,
            double* rest, const std::vector<FactorProbe>* probes, std::vector<double>* probe_sums)
      : grid_(grid),
        lobes_(lobes),
        scaled_(scaled),
        rest_(rest),
        probes_(probes),
        probe_sums_(probe_sums) {
    if (probes_)
      for (const FactorProbe& p : *probes_) visibility_ = visibility_ || p.needs_visibility;
  }
  void add(const Material& m, const ShadingPoint& p, double irradiance, double value, bool lit,
           int /*column*/) const override {
    if (!lit) return;
    NodeWeights nodes;
    const int n = grid_->nodes(factor_inputs(p.ng, p.ns, p.wi, p.wo), &nodes);
    const double light = n ? factor_scaled_value(m, p.ns, p.wi, p.wo, lobes_) * irradiance : 0.0;
    if (light > 0.0)
      for (int k = 0; k < n; ++k)
        scaled_->emplace_back(nodes[std::size_t(k)].first, light * nodes[std::size_t(k)].second);
    *rest_ += value - light;
    if (probing_) add_probes(m, p, irradiance, value);
  }
  bool wants_visibility(int /*column*/) const override { return probing_ && visibility_; }
  // Whether the probes are tried on the pixel whose samples come next.
  void probe_pixel(bool probe) { probing_ = probes_ && probe; }
  bool probes_visibility() const { return visibility_; }

 private:
  // A factor method's sample is raw bump's with the light of its lobes
  // scaled (shading.cpp, shade): the same shadow ray and light sample.
  void add_probes(const Material& m, const ShadingPoint& p, double irradiance, double value) const {
    double scaled_by_lobes[2] = {-1.0, -1.0};  // Lobes::kDiffuse, kAll; computed when needed
    double* sums = probe_sums_->data();
    for (const FactorProbe& probe : *probes_) {
      double& scaled = scaled_by_lobes[probe.lobes == Lobes::kAll ? 1 : 0];
      if (scaled < 0.0) scaled = factor_scaled_value(m, p.ns, p.wi, p.wo, probe.lobes) * irradiance;
      factors_.resize(probe.values);
      probe.factors(p, factors_.data());
      for (std::size_t k = 0; k < probe.values; ++k)
        sums[k] += (value - scaled) + scaled * factors_[k];
      sums += probe.values;
    }
  }

  const FactorGrid* grid_;
  Lobes lobes_;
  std::vector<std::pair<int, double>>* scaled_;  // (cell, light), unsorted
  double* rest_;                                 // light no cell's G scales
  const std::vector<FactorProbe>* probes_;       // null: none
  std::vector<double>* probe_sums_;              // the pixel's, per probe and value
  mutable std::vector<double> factors_;          // one probe's at a sample
  bool visibility_ = false;                      // a probe reads it
  bool probing_ = false;                         // on the current pixel
};

// The samples of a user method's pass (core/user_method.h) in the order
// they are shaded (a row's pixels in turn): the factor's inputs and the
// light the factor scales (0 where the light does not reach the sample
// unblocked).
struct SampleRecords {
  std::vector<double> cos_light, cos_deviation, cos_shading, cos_view, light;
  std::vector<Vec3> ng, ns, wi, wo;  // only for a method that wants the vectors
  // The sample's pixel: in its row as recorded, in the block once appended.
  std::vector<std::uint32_t> column;
  std::vector<double> rest;  // one per pixel of the rows: the light no factor scales

  // `o`'s samples after these, its pixels after these.
  void append(const SampleRecords& o) {
    auto cat = [](auto& a, const auto& b) { a.insert(a.end(), b.begin(), b.end()); };
    const auto offset = static_cast<std::uint32_t>(rest.size());
    cat(cos_light, o.cos_light), cat(cos_deviation, o.cos_deviation);
    cat(cos_shading, o.cos_shading), cat(cos_view, o.cos_view), cat(light, o.light);
    cat(ng, o.ng), cat(ns, o.ns), cat(wi, o.wi), cat(wo, o.wo), cat(rest, o.rest);
    for (const std::uint32_t c : o.column) column.push_back(offset + c);
  }
  FactorBatch batch() const {
    return {cos_light, cos_deviation, cos_shading, cos_view, ng, ns, wi, wo};
  }
};

// Records a user method's samples: the raw-bump pass it renders is the
// user's scene with the method `none`, so it sees the same normals.
class RecordSink final : public SampleSink {
 public:
  // `out`: one row's records, its `rest` one entry per pixel of the row.
  RecordSink(const TerminatorSettings& t, bool vectors, SampleRecords* out)
      : use_ni_(t.reference_normal == ReferenceNormal::kInterpolated),
        lobes_(t.lobes),
        vectors_(vectors),
        out_(out) {}
  void add(const Material& m, const ShadingPoint& p, double irradiance, double value, bool lit,
           int column) const override {
    const Vec3& ng = use_ni_ ? p.ni : p.ng;
    out_->cos_light.push_back(dot(ng, p.wi));
    out_->cos_deviation.push_back(dot(ng, p.ns));
    out_->cos_shading.push_back(dot(p.ns, p.wi));
    out_->cos_view.push_back(dot(ng, p.wo));
    if (vectors_) {
      out_->ng.push_back(ng), out_->ns.push_back(p.ns);
      out_->wi.push_back(p.wi), out_->wo.push_back(p.wo);
    }
    const double light = lit ? factor_scaled_value(m, p.ns, p.wi, p.wo, lobes_) * irradiance : 0.0;
    out_->light.push_back(light);
    out_->column.push_back(static_cast<std::uint32_t>(column));
    if (lit) out_->rest[std::size_t(column)] += value - light;
  }

 private:
  bool use_ni_;
  Lobes lobes_;
  bool vectors_;
  SampleRecords* out_;
};

// The parts of a sample every method sees alike, in the channels' units.
struct SampleAngles {
  double theta = 0.0, deviation = 0.0, view = 0.0;  // degrees
};

// The sums a resumed render starts from (RenderOptions::resume) and where
// a render leaves its own (RenderOptions::sums), pixel by pixel from any
// thread: each pixel's slots are its own.
class PixelSumsIo {
 public:
  PixelSumsIo(const Camera& camera, const RenderOptions& options, std::size_t images)
      : camera_(camera), resume_(options.resume), out_(options.sums) {
    const std::size_t values =
        std::size_t(camera.width) * std::size_t(camera.height) * kSampleSumChannels;
    if (resume_) {
      if (resume_->size() != images)
        throw std::invalid_argument("render: resume needs the sums of every image");
      for (const SampleSums& r : *resume_)
        if (r.width != camera.width || r.height != camera.height || r.values.size() != values ||
            r.spp != resume_->front().spp || !camera.jitter || !nests(r.spp, camera.spp))
          throw std::invalid_argument(fmt::format(
              "render: sums of {} samples at {}x{} cannot be extended to {} jittered samples at "
              "{}x{} (core/sample_pattern.h, nests)",
              r.spp, r.width, r.height, camera.spp, camera.width, camera.height));
      first_sample_ = resume_->front().spp;
    }
    if (out_) {
      out_->assign(images, SampleSums{camera.spp, camera.width, camera.height, {}});
      for (SampleSums& o : *out_) o.values.assign(values, 0.0);
    }
  }
  int first_sample() const { return first_sample_; }
  // The samples this render draws, of each pixel.
  int drawn() const { return camera_.spp - first_sample_; }
  void start(std::size_t pixel, PixelSums* sums, std::size_t images) const {
    for (std::size_t k = 0; k < images; ++k) {
      sums[k] = {};
      if (!resume_) continue;
      const double* v = &(*resume_)[k].values[pixel * kSampleSumChannels];
      sums[k] = {v[0], v[1], v[2], v[3], v[4], v[5], v[6]};
    }
  }
  void finish(std::size_t pixel, const PixelSums* sums, std::size_t images) const {
    if (!out_) return;
    for (std::size_t k = 0; k < images; ++k) {
      double* v = &(*out_)[k].values[pixel * kSampleSumChannels];
      const PixelSums& p = sums[k];
      v[0] = p.radiance, v[1] = p.hits, v[2] = p.theta, v[3] = p.deviation, v[4] = p.g,
      v[5] = p.g_count, v[6] = p.view;
    }
  }

 private:
  const Camera& camera_;
  const std::vector<SampleSums>* resume_;
  std::vector<SampleSums>* out_;
  int first_sample_ = 0;
};
static_assert(sizeof(PixelSums) == kSampleSumChannels * sizeof(double));

void write_pixel(const PixelSums& sums, double inv_spp, float* out) {
  const float radiance = static_cast<float>(sums.radiance * inv_spp);
  out[0] = out[1] = out[2] = radiance;
  out[3] = static_cast<float>(sums.hits * inv_spp);
  if (sums.hits > 0.0) {
    out[4] = static_cast<float>(sums.theta / sums.hits);
    out[5] = static_cast<float>(sums.deviation / sums.hits);
    // 0 where no sample had a factor: a method that is not a plain
    // factor, wherever raw bump receives no light (README, channels).
    out[6] = sums.g_count > 0.0 ? static_cast<float>(sums.g / sums.g_count) : 0.0f;
    out[7] = static_cast<float>(sums.view / sums.hits);
  }
}

// The jitter of sample k of a pixel within its stratum, x then y, from
// the pixel's key: counter-based, so that where a sample lies depends on
// nothing drawn before it (a method's random numbers while shading draw
// from the pixel's Pcg32 stream instead), and a packet can draw its
// samples' jitter without a chain through a generator's state.
struct Jitter {
  double x = 0.5, y = 0.5;  // stratum centres without jitter
};

// Camera sample s of a pixel: its stratum and its jitter within it, from
// the pattern of the scene's samples (core/sample_pattern.h, nested where
// nested_samples says); a camera that does not jitter takes the plain
// grid's centres.
StratumPoint camera_stratum(const Scene& scene, std::uint64_t pixel_key, int s, int nx) {
  const Camera& camera = scene.camera;
  if (!camera.jitter) return {s % nx, s / nx, 0.5, 0.5};
  return stratum_point(s, camera.spp, {pixel_key, false, 0, nested_samples(scene)});
}

// The camera ray of sample (sx, sy) of pixel (i, j), at `jitter` within
// its stratum; `orthographic_direction` is the camera's direction,
// normalised.
Ray camera_ray(const Camera& camera, const Vec3& orthographic_direction, int i, int j, int sx,
               int sy, int nx, int ny, const Jitter& jitter) {
  const double a = (sx + jitter.x) / nx;
  const double b = (sy + jitter.y) / ny;
  const double x0 = (i + a) / camera.width - 0.5;
  const double y0 = 0.5 - (j + b) / camera.height;
  if (camera.projection == Projection::kPerspective)
    return {camera.position, normalize(camera.direction + camera.right * x0 + camera.up * y0)};
  return {camera.position + camera.right * x0 + camera.up * y0, orthographic_direction};
}

// Shades one camera sample's hit with every pass, into one PixelSums each:
// what every tracer and both the scalar and the packet path share.
template <typename Tracer>
class SampleShader {
 public:
  SampleShader(const Scene& scene, const Tracer& tracer, const Props& props,
               const std::vector<TerminatorSettings>& passes)
      : scene_(scene),
        tracer_(tracer),
        props_(props),
        passes_(passes),
        displaced_shading_(scene.representation != Representation::kSmooth),
        is_ground_truth_(scene.representation == Representation::kDisplacement),
        // A filter shades bump samples only: the truth is the unfiltered surface.
        bump_{
            scene, scene.height.height_map(), scene.height.normal_map(),
            scene.representation == Representation::kBump ? scene.height.filtered.get() : nullptr},
        perturbed_(scene.height.amplitude != 0.0 || bump_.normal_map) {
    // The same visibility serves every method that reads it.
    for (const TerminatorSettings& t : passes)
      needs_visibility_ =
          needs_visibility_ || (!is_ground_truth_ && method_info(t.method.method).needs_visibility);
  }

  const BumpNormals& bump() const { return bump_; }
  // Whether a hit's shading normal is the bump normal (BumpNormals::at).
  bool bumps() const { return displaced_shading_ && perturbed_; }

  // `sink`: where the one pass's samples go as well (SampleSink).
  void shade(const Ray& ray, const SurfaceHit& hit, const LightUniforms& u, Material* material,
             Pcg32* rng, PixelSums* sums, std::uint64_t* shadow_rays,
             const SampleSink* sink = nullptr, int column = 0) const;
  // shade() but for the radiance of the passes the light reaches, which
  // waits for the shadow ray's verdict: its contributions are appended to
  // *lit, and the ray to trace is returned (nullopt: no pass needs it).
  // Adding them later, in the order of the samples, gives shade()'s sums.
  std::optional<PendingShadow> shade_deferred(const Ray& ray, const SurfaceHit& hit,
                                              const LightUniforms& u, Material* material,
                                              Pcg32* rng, PixelSums* sums,
                                              std::vector<LitPass>* lit) const;
  // Lane k of a packet on the analytic base (BaseTracer, no props): what
  // shade() does with the packet's values, read straight from its arrays.
  // Copying them through a SurfaceHit first cost a tenth of the render:
  // wider loads of a Vec3 just stored narrower wait for the store.
  void shade_packed(const HitPacket& hits, const RayPacket& rays, std::size_t k,
                    const Material& material, PixelSums* sums, std::uint64_t* shadow_rays,
                    const SampleSink* sink, int column) const;
  // Every pass on one shading point, into sums, but for the radiance of
  // the passes the light reaches: lit(pass, radiance) decides on those.
  template <typename Lit>
  void shade_passes(const Material& material, const ShadingPoint& point, const LightSample& light,
                    const SampleAngles& angles, Pcg32* rng, PixelSums* sums, Lit&& lit) const;

 private:
  // What shade() computes before the passes.
  struct Prepared {
    FacingNormals facing;
    LightSample light;
    ShadingPoint point;
    SampleAngles angles;
  };
  Prepared prepare(const Ray& ray, const SurfaceHit& hit, const LightUniforms& u,
                   Material* material) const;
  // The height field's ambient visibility at a hit seen as `facing` says
  // (1 where there is none to shadow it: the truth, a flat surface).
  double visibility(const SurfaceHit& hit, const FacingNormals& facing) const {
    const SurfaceGeometry& g = hit.geometry;
    const double amplitude = scene_.height.amplitude;
    if (is_ground_truth_ || !displaced_shading_ || !g.displaceable || amplitude == 0.0) return 1.0;
    // Seen from inside (an open cylinder), the height field is inverted.
    return facing.backfacing
               ? height_field_visibility(scene_.height.function, -amplitude, g.p, -g.n)
               : height_field_visibility(scene_.height.function, amplitude, g.p, g.n);
  }
  ShadowRay shadow_ray(const SurfaceHit& hit, const Prepared& p) const {
    return hit.on_prop ? ShadowRay{hit.shading_point}
                       : tracer_.shadow_ray(hit, p.facing, p.light.wi);
  }

  const Scene& scene_;
  const Tracer& tracer_;
  const Props& props_;
  const std::vector<TerminatorSettings>& passes_;
  bool displaced_shading_, is_ground_truth_;
  BumpNormals bump_;
  bool perturbed_;
  bool needs_visibility_ = false;
};

template <typename Tracer>
typename SampleShader<Tracer>::Prepared SampleShader<Tracer>::prepare(const Ray& ray,
                                                                      const SurfaceHit& hit,
                                                                      const LightUniforms& u,
                                                                      Material* material) const {
  const SurfaceGeometry& g = hit.geometry;
  const Vec3 wo = -ray.direction;
  Vec3 n = g.n;
  FacingNormals facing{hit.ng, hit.ni, false};
  Vec3 ni = hit.ni;
  if (bumps() && g.displaceable) {
    // The bump perturbs the analytic normal; on a mesh it is carried
    // over to Ni, so that Ns relates to Ni as it would to N.
    const Vec3 b = hit.has_exact_ns ? hit.exact_ns : bump_.at(g, hit.ng, ray, hit.t, material);
    facing.ns = hit.ni == g.n ? b : normalize(rotate_between(g.n, hit.ni, b));
  }
  // Two-sided: the inside of an open cylinder is seen from inside.
  if (dot(facing.ng, wo) < 0.0) {
    n = -n;
    ni = -ni;
    facing.ng = -facing.ng;
    facing.ns = -facing.ns;
    facing.backfacing = true;
  }
  const Vec3& ns = facing.ns;
  const LightSample light = sample_light(scene_.light, hit.shading_point, u, facing.ng);
  // On the displaced surface the true normal is Ns itself; on the
  // analytic base Ng and Ni coincide with the base normal.
  ShadingPoint point = is_ground_truth_ && !hit.on_prop
                           ? ShadingPoint{ns, ns, ns, light.wi, wo}
                           : ShadingPoint{facing.ng, ni, ns, light.wi, wo};
  if (needs_visibility_) point.visibility = visibility(hit, facing);
  // Within 1.2e-6 degrees: below what the float channels resolve.
  const SampleAngles angles{degrees(acos_approx(cos_light_angle(scene_.light, n, g.p, light.wi))),
                            degrees(acos_approx(dot(ns, n))), degrees(acos_approx(dot(n, wo)))};
  return {facing, light, point, angles};
}

template <typename Tracer>
void SampleShader<Tracer>::shade(const Ray& ray, const SurfaceHit& hit, const LightUniforms& u,
                                 Material* material, Pcg32* rng, PixelSums* sums,
                                 std::uint64_t* shadow_rays, const SampleSink* sink,
                                 int column) const {
  const Prepared p = prepare(ray, hit, u, material);
  int is_blocked = -1;     // the shadow ray, traced for the first pass that needs it
  double lit_value = 0.0;  // the one pass's, where the light reaches it (sink)
  shade_passes(*material, p.point, p.light, p.angles, rng, sums, [&](std::size_t k, double value) {
    if (is_blocked < 0) {
      ++*shadow_rays;
      const ShadowRay shadow = shadow_ray(hit, p);
      is_blocked = tracer_.occluded(shadow, p.light.wi, p.light.distance) ||
                   props_.occluded(shadow.origin, p.light.wi, p.light.distance);
    }
    if (is_blocked != 0) return;
    sums[k].radiance += value;
    lit_value = value;
  });
  if (!sink) return;
  // A sink's probes read the visibility only where the light arrives.
  if (!needs_visibility_ && lit_value > 0.0 && sink->wants_visibility(column)) {
    ShadingPoint point = p.point;
    point.visibility = visibility(hit, p.facing);
    sink->add(*material, point, p.light.irradiance, lit_value, true, column);
    return;
  }
  sink->add(*material, p.point, p.light.irradiance, lit_value, lit_value > 0.0, column);
}

template <typename Tracer>
std::optional<PendingShadow> SampleShader<Tracer>::shade_deferred(
    const Ray& ray, const SurfaceHit& hit, const LightUniforms& u, Material* material, Pcg32* rng,
    PixelSums* sums, std::vector<LitPass>* lit) const {
  const Prepared p = prepare(ray, hit, u, material);
  const std::size_t first = lit->size();
  shade_passes(*material, p.point, p.light, p.angles, rng, sums, [&](std::size_t k, double value) {
    lit->push_back({k, value});
  });
  if (lit->size() == first) return std::nullopt;
  return PendingShadow{shadow_ray(hit, p), p.light.wi, p.light.distance, first, lit->size()};
}

template <typename Tracer>
template <typename Lit>
void SampleShader<Tracer>::shade_passes(const Material& material, const ShadingPoint& point,
                                        const LightSample& light, const SampleAngles& angles,
                                        Pcg32* rng, PixelSums* sums, Lit&& lit) const {
  for (std::size_t k = 0; k < passes_.size(); ++k) {
    const Shaded shaded = penumbra::shade(passes_[k], material, point, rng);
    PixelSums& s = sums[k];
    s.hits += 1.0;
    s.theta += angles.theta;
    s.deviation += angles.deviation;
    if (shaded.factor_defined) {
      s.g += shaded.factor;
      s.g_count += 1.0;
    }
    s.view += angles.view;
    if (!(shaded.value > 0.0) || light.irradiance == 0.0) continue;
    lit(k, shaded.value * light.irradiance);
  }
}

template <typename Tracer>
void SampleShader<Tracer>::shade_packed(const HitPacket& hits, const RayPacket& rays, std::size_t k,
                                        const Material& material, PixelSums* sums,
                                        std::uint64_t* shadow_rays, const SampleSink* sink,
                                        int column) const {
  // As shade() for a BaseTracer hit: Ng = Ni = the base normal, Ns the
  // packet's (the base normal where nothing bumps it), both turned towards
  // the viewer.
  const Vec3 wo{-rays.dx[k], -rays.dy[k], -rays.dz[k]};
  Vec3 n{hits.nx[k], hits.ny[k], hits.nz[k]};
  Vec3 ns{hits.nsx[k], hits.nsy[k], hits.nsz[k]};
  const bool backfacing = dot(n, wo) < 0.0;
  if (backfacing) n = -n, ns = -ns;
  const Vec3 p{hits.px[k], hits.py[k], hits.pz[k]};
  const LightSample light = sample_light(scene_.light, p, {});  // a delta light (traces_packets)
  ShadingPoint point{n, n, ns, light.wi, wo};
  const double amplitude = scene_.height.amplitude;
  // As visibility() for the hit (n is already turned, as -g.n there).
  const auto field_visibility = [&] {
    return displaced_shading_ && amplitude != 0.0
               ? height_field_visibility(scene_.height.function,
                                         backfacing ? -amplitude : amplitude, p, n)
               : 1.0;
  };
  if (needs_visibility_) point.visibility = field_visibility();
  const SampleAngles angles{hits.theta[k], hits.deviation[k], hits.view[k]};
  bool counted = false;  // the packet traced the shadow ray; count it once, as shade() does
  double lit_value = 0.0;
  shade_passes(material, point, light, angles, nullptr, sums, [&](std::size_t pass, double value) {
    if (!counted) ++*shadow_rays, counted = true;
    if (hits.blocked[k] == 0.0) sums[pass].radiance += value, lit_value = value;
  });
  if (!sink) return;
  // As shade(): a sink's probes read the visibility only where the light arrives.
  if (!needs_visibility_ && lit_value > 0.0 && sink->wants_visibility(column)) {
    ShadingPoint probed = point;
    probed.visibility = field_visibility();
    sink->add(material, probed, light.irradiance, lit_value, true, column);
    return;
  }
  sink->add(material, point, light.irradiance, lit_value, lit_value > 0.0, column);
}

// Whether render_image traces its camera rays in packets (core/ray_packet.h):
// on the analytic base shape (BaseTracer) with no props, no image map and no
// filter, the packet computes what the tracer and the analytic bump do, to
// the bit; a packet's samples are shaded without the pixel's random stream,
// so no method may draw random numbers.
template <typename Tracer>
bool traces_packets(const Scene& scene, const SampleShader<Tracer>& shader,
                    const std::vector<TerminatorSettings>& passes, const RenderOptions& options) {
  if (!std::is_same_v<Tracer, BaseTracer> || !options.packets || !scene.props.empty() ||
      is_area_light(scene.light) || !packet_supports(scene.shape))
    return false;
  const BumpNormals& bump = shader.bump();
  if (bump.filtered || bump.normal_map || bump.height_map) return false;
  return std::all_of(passes.begin(), passes.end(), shares_samples);
}

// The key of pixel (i, j): its jitter and its random stream derive from it.
std::uint64_t pixel_key(const Camera& camera, int i, int j) {
  return mix64(camera.seed ^ mix64(std::uint64_t(j) * camera.width + i));
}

// One pixel to render: where it is, its key (its jitter and its random
// stream derive from it) and where its samples go.
struct PixelTask {
  int i = 0, j = 0;
  std::uint64_t key = 0;
  Pcg32* rng = nullptr;       // for the methods that draw random numbers while shading
  PixelSums* sums = nullptr;  // one per pass
  std::uint64_t* shadow_rays = nullptr;
  const SampleSink* sink = nullptr;  // one pass's samples (scalar path only)
  int first_sample = 0;              // a resumed render's: the samples its sums hold
};

// The rows of a render through packets: rays, hits, bump normals, shadow
// rays and angles a packet at a time, then each hit shaded. A packet runs
// on across pixels (at 16 spp it holds 16 of them), and a pixel is written
// once its last sample is shaded; each pixel's samples are shaded in the
// order of the scalar path, so its sums are the same.
class PacketRows {
 public:
  PacketRows(const Scene& scene, const PacketSetup& setup, const SampleShader<BaseTracer>& shader,
             std::size_t pass_count, std::vector<Image>* images)
      : scene_(scene),
        setup_(setup),
        shader_(shader),
        pass_count_(pass_count),
        images_(images),
        buffers_(std::make_unique<PacketBuffers>()),
        sums_(kSlots * pass_count) {}

  // `sink`: where the one pass's samples go as well (a user method's).
  void render_row(int j, std::uint64_t* shadow_rays, const SampleSink* sink = nullptr);

 private:
  // Pixels with samples in flight: at most a packet's worth of pixels whose
  // samples are all in, and the one whose samples are still coming.
  static constexpr std::size_t kSlots = kPacketSize + 1;

  void flush(std::uint64_t* shadow_rays);

  const Scene& scene_;
  const PacketSetup& setup_;
  const SampleShader<BaseTracer>& shader_;
  std::size_t pass_count_;
  std::vector<Image>* images_;
  std::unique_ptr<PacketBuffers> buffers_;
  std::vector<PixelSums> sums_;  // pass_count_ per slot; pixel i in slot i % kSlots
  std::size_t lane_slot_[kPacketSize]{};
  std::vector<int> complete_;  // pixels of row j_ whose samples are all in the packets
  int j_ = 0;
  const SampleSink* sink_ = nullptr;
};

void PacketRows::render_row(int j, std::uint64_t* shadow_rays, const SampleSink* sink) {
  sink_ = sink;
  const Camera& camera = scene_.camera;
  SamplePacket& samples = buffers_->samples;
  RayPacket& rays = buffers_->rays;
  j_ = j;
  rays.count = 0;
  for (int i = 0; i < camera.width; ++i) {
    const std::uint64_t key = pixel_key(camera, i, j);
    const std::size_t slot = std::size_t(i) % kSlots;
    std::fill_n(sums_.begin() + std::ptrdiff_t(slot * pass_count_), pass_count_, PixelSums{});
    // Strata in the order of the scalar path's loops, y outer.
    for (int sample = 0; sample < camera.spp; ++sample) {
      const std::size_t k = rays.count++;
      samples.i[k] = i, samples.j[k] = j;
      const StratumPoint p = camera_stratum(scene_, key, sample, setup_.nx);
      samples.sx[k] = p.sx, samples.sy[k] = p.sy;
      samples.jx[k] = p.x, samples.jy[k] = p.y;
      lane_slot_[k] = slot;
      if (rays.count == kPacketSize) flush(shadow_rays);
    }
    complete_.push_back(i);
  }
  flush(shadow_rays);
}

void PacketRows::flush(std::uint64_t* shadow_rays) {
  RayPacket& rays = buffers_->rays;
  HitPacket& hits = buffers_->hits;
  if (rays.count > 0) {
    camera_rays(setup_.camera, buffers_->samples, &rays);
    trace_packet(scene_.shape, scene_.height.function, scene_.height.amplitude, shader_.bumps(),
                 setup_.lighting, rays, &hits);
  }
  // No pass draws random numbers here (traces_packets): no stream.
  for (std::size_t k = 0; k < rays.count; ++k)
    if (hits.found[k] != 0.0)
      shader_.shade_packed(hits, rays, k, scene_.material, &sums_[lane_slot_[k] * pass_count_],
                           shadow_rays, sink_, static_cast<int>(buffers_->samples.i[k]));
  rays.count = 0;
  const Camera& camera = scene_.camera;
  const std::size_t channel_count = evaluator_channels().size();
  for (const int i : complete_) {
    const std::size_t pixel = std::size_t(j_) * camera.width + i;
    const PixelSums* sums = &sums_[(std::size_t(i) % kSlots) * pass_count_];
    for (std::size_t k = 0; k < pass_count_; ++k)
      write_pixel(sums[k], 1.0 / camera.spp, &(*images_)[k].pixels[pixel * channel_count]);
  }
  complete_.clear();
}

// The scene's camera and light for packets, and where the tracer's shadow
// rays start counting hits.
template <typename Tracer>
PacketSetup packet_setup(const Scene& scene, const Tracer& tracer) {
  PacketSetup setup;
  const Camera& c = scene.camera;
  int ny;
  strata(c.spp, &setup.nx, &ny);
  setup.camera = {c.projection == Projection::kPerspective,
                  c.position,
                  c.projection == Projection::kPerspective ? c.direction : normalize(c.direction),
                  c.right,
                  c.up,
                  double(c.width),
                  double(c.height),
                  double(setup.nx),
                  double(ny)};
  PacketLighting& lighting = setup.lighting;
  // Only delta lights reach packets (traces_packets).
  lighting.distant = scene.light.type == LightType::kDistant;
  lighting.light = lighting.distant ? scene.light.direction : scene.light.position;
  if constexpr (std::is_same_v<Tracer, BaseTracer>) lighting.shadow_t_min = tracer.shadow_t_min();
  return setup;
}

// A block of at most kRays of one pixel's samples on their way through a
// tracer's packets: their camera rays and hits, and the shadow rays that
// wait for a verdict with the radiance each would add (lit).
template <std::size_t kRays>
struct SampleBlock {
  Ray rays[kRays], shadow_rays[kRays];
  SurfaceHit hits[kRays];
  PendingShadow pending[kRays];
  double distances[kRays];
  bool found[kRays], blocked[kRays];
  std::size_t waiting = 0;

  // Camera rays of samples [first, first + n) of pixel (i, j).
  void camera_rays(const Scene& scene, const Vec3& orthographic_direction, int i, int j,
                   std::uint64_t key, int first, std::size_t n, int nx, int ny) {
    const Camera& camera = scene.camera;
    for (std::size_t k = 0; k < n; ++k) {
      const StratumPoint p = camera_stratum(scene, key, first + int(k), nx);
      rays[k] = camera_ray(camera, orthographic_direction, i, j, p.sx, p.sy, nx, ny, {p.x, p.y});
    }
  }
  void wait(const PendingShadow& p) {
    shadow_rays[waiting] = {p.ray.origin, p.wi};
    distances[waiting] = p.distance;
    pending[waiting++] = p;
  }
  // Traces the waiting shadow rays (in one packet, or the one ray alone
  // without `packets`) and adds the radiance of those the light reaches,
  // in the samples' order.
  template <typename Tracer>
  void settle(const Tracer& tracer, const Props& props, const std::vector<LitPass>& lit,
              bool packets, PixelSums* sums, std::uint64_t* shadow_ray_count) {
    if (waiting > 0 && packets) tracer.occluded_packet(shadow_rays, distances, waiting, blocked);
    if (waiting > 0 && !packets)
      blocked[0] = tracer.occluded(pending[0].ray, pending[0].wi, pending[0].distance);
    for (std::size_t k = 0; k < waiting; ++k) {
      const PendingShadow& p = pending[k];
      ++*shadow_ray_count;
      if (blocked[k] || props.occluded(p.ray.origin, p.wi, p.distance)) continue;
      for (std::size_t c = p.first; c < p.last; ++c) sums[lit[c].pass].radiance += lit[c].radiance;
    }
    waiting = 0;
  }
};

// One pixel's samples kPacketRays at a time, camera rays and then shadow
// rays in packets of the tracer's: the samples are shaded in the order of
// the strata, and the radiance the shadow rays let through is added in that
// order too, so the sums are shade_pixel's one sample at a time.
template <typename Tracer>
void shade_pixel_packets(const Scene& scene, const Tracer& tracer, const Props& props,
                         const SampleShader<Tracer>& shader, const PixelTask& pixel, int nx,
                         int ny) {
  constexpr std::size_t kRays = Tracer::kPacketRays;
  const Camera& camera = scene.camera;
  const Vec3 orthographic_direction = normalize(camera.direction);
  Material material = scene.material;
  SampleBlock<kRays> b;
  // Kept per thread: one allocation per pixel was 2 % of a 16-spp truth.
  thread_local std::vector<LitPass> lit;
  const int count = nx * ny;
  for (int first = pixel.first_sample; first < count; first += int(kRays)) {
    const std::size_t n = std::min<std::size_t>(kRays, count - first);
    b.camera_rays(scene, orthographic_direction, pixel.i, pixel.j, pixel.key, first, n, nx, ny);
    tracer.primary_packet(b.rays, n, b.hits, b.found);
    lit.clear();
    for (std::size_t k = 0; k < n; ++k) {
      b.hits[k].on_prop = false;
      material.filtered.active = false;
      if (!(props.nearer(b.rays[k], b.found[k], &b.hits[k]) || b.found[k])) continue;
      const LightUniforms u = light_uniforms(scene, pixel.key, first + int(k), nx, ny);
      if (const auto p = shader.shade_deferred(b.rays[k], b.hits[k], u, &material, pixel.rng,
                                               pixel.sums, &lit))
        b.wait(*p);
    }
    b.settle(tracer, props, lit, true, pixel.sums, pixel.shadow_rays);
  }
}

// One pixel's samples one at a time, in the order of the strata; through
// the tracer's packets (shade_pixel_packets) where it has them and `packets`.
template <typename Tracer>
void shade_pixel(const Scene& scene, const Tracer& tracer, const Props& props,
                 const SampleShader<Tracer>& shader, const PixelTask& pixel, bool packets) {
  const Camera& camera = scene.camera;
  int nx, ny;
  strata(camera.spp, &nx, &ny);
  if constexpr (requires { Tracer::kPacketRays; }) {
    if (packets) return shade_pixel_packets(scene, tracer, props, shader, pixel, nx, ny);
  }
  const Vec3 orthographic_direction = normalize(camera.direction);
  // One per pixel, not per sample: value-initialising it (a mesh hit
  // included) took 9% of a bump render. Every tracer sets all the
  // fields it uses; `on_prop` is the one field only props set.
  SurfaceHit hit;
  Material material = scene.material;  // a filtered map sets its lobe per sample
  for (int s = pixel.first_sample; s < camera.spp; ++s) {
    const StratumPoint p = camera_stratum(scene, pixel.key, s, nx);
    const Ray ray = camera_ray(camera, orthographic_direction, pixel.i, pixel.j, p.sx, p.sy, nx, ny,
                               {p.x, p.y});
    hit.on_prop = false;
    material.filtered.active = false;
    const bool found = tracer.primary(ray, &hit);
    if (!(props.nearer(ray, found, &hit) || found)) continue;
    shader.shade(ray, hit, light_uniforms(scene, pixel.key, s, nx, ny), &material, pixel.rng,
                 pixel.sums, pixel.shadow_rays, pixel.sink, pixel.i);
  }
}

// render_tallied's tally while it renders: per pixel, (cell, light) sorted
// by cell with each cell once, and the rest, both divided by the samples.
struct TallyRequest {
  const FactorGrid* grid = nullptr;
  Lobes lobes = Lobes::kDiffuse;
  std::vector<std::vector<std::pair<int, double>>> scaled;
  std::vector<double> rest;
  TallyProbes* probes = nullptr;  // null: none

  const std::vector<FactorProbe>* probe_list() const {
    return probes && !probes->probes.empty() ? &probes->probes : nullptr;
  }
  std::size_t probe_values() const {
    std::size_t n = 0;
    if (probes)
      for (const FactorProbe& p : probes->probes) n += p.values;
    return n;
  }
  bool probes_pixel(std::uint64_t pixel) const {
    return probes && (probes->pixels.empty() || probes->pixels[pixel]);
  }

  void store(std::uint64_t pixel, std::vector<std::pair<int, double>>& entries, double rest_sum,
             const std::vector<double>& probe_sums, double inv_spp) {
    if (probes) {
      const double* sums = probe_sums.data();
      for (std::size_t f = 0; f < probes->probes.size(); ++f) {
        const std::size_t values = probes->probes[f].values;
        double* out = probes->radiance[f].data() + pixel * values;
        for (std::size_t k = 0; k < values; ++k) out[k] = sums[k] * inv_spp;
        sums += values;
      }
    }
    std::sort(entries.begin(), entries.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<std::pair<int, double>>& out = scaled[pixel];
    for (const auto& [cell, light] : entries) {
      if (out.empty() || out.back().first != cell) out.emplace_back(cell, 0.0);
      out.back().second += light;
    }
    for (auto& entry : out) entry.second *= inv_spp;
    rest[pixel] = rest_sum * inv_spp;
  }
};

// The tally of one row rendered through packets (PacketRows). Its pixels'
// samples arrive one pixel after the other, each pixel's in the scalar
// path's order, so a pixel is stored when a later pixel's first sample
// arrives (or the row ends): the same sums as the scalar path's.
class RowTallySink final : public SampleSink {
 public:
  struct Buffers {  // a thread's: the current pixel's tally
    std::vector<std::pair<int, double>>* entries;
    double* rest;
    std::vector<double>* probe_sums;
  };
  RowTallySink(TallySink* sink, TallyRequest* tally, Buffers buffers, std::uint64_t first_pixel,
               int width, double inv_spp)
      : sink_(sink),
        tally_(tally),
        buffers_(buffers),
        first_pixel_(first_pixel),
        width_(width),
        inv_spp_(inv_spp) {}
  void add(const Material& m, const ShadingPoint& p, double irradiance, double value, bool lit,
           int column) const override {
    advance(column);
    sink_->add(m, p, irradiance, value, lit, column);
  }
  bool wants_visibility(int column) const override {
    return sink_->probes_visibility() && tally_->probes_pixel(first_pixel_ + std::uint64_t(column));
  }
  // Stores the pixels that are left (after the row's last sample).
  void finish() const { advance(width_); }

 private:
  // Stores pixels [column_, column) and starts pixel `column`.
  void advance(int column) const {
    while (column_ < column) {
      if (column_ >= 0)
        tally_->store(first_pixel_ + std::uint64_t(column_), *buffers_.entries, *buffers_.rest,
                      *buffers_.probe_sums, inv_spp_);
      if (++column_ == width_) break;
      buffers_.entries->clear();
      *buffers_.rest = 0.0;
      std::fill(buffers_.probe_sums->begin(), buffers_.probe_sums->end(), 0.0);
      sink_->probe_pixel(tally_->probes_pixel(first_pixel_ + std::uint64_t(column_)));
    }
  }

  TallySink* sink_;
  TallyRequest* tally_;
  Buffers buffers_;
  std::uint64_t first_pixel_;
  int width_;
  double inv_spp_;
  mutable int column_ = -1;  // the pixel whose samples come in; -1: none yet
};

// A user method's pass while it renders (render_user_passes): the samples
// of rows [first_row, first_row + rows.size()), a SampleRecords per row.
struct RecordRequest {
  const TerminatorSettings* pass = nullptr;  // the raw-bump pass that is rendered
  bool vectors = false;                      // record the vectors too
  int first_row = 0;
  std::vector<SampleRecords> rows;
};

// Renders rows [first_row, end_row) of the image with each of `passes` (one
// per image); see render_methods. With `tally` or `record` (one pass), on
// the scalar path, tallying or recording its samples as it goes.
struct ImageRequest {
  TallyRequest* tally = nullptr;
  RecordRequest* record = nullptr;
  int first_row = 0;
  int end_row = -1;  // -1: the last row
};

template <typename Tracer>
void render_image(const Scene& scene, const Tracer& tracer, const RenderOptions& options,
                  const std::vector<TerminatorSettings>& passes, std::vector<Image>* images,
                  RenderStats* stats, const ImageRequest& request = {}) {
  const Camera& camera = scene.camera;
  const int width = camera.width, height = camera.height;
  const int first_row = request.first_row;
  const int end_row = request.end_row < 0 ? height : request.end_row;
  const std::size_t channel_count = evaluator_channels().size();
  const std::size_t pass_count = passes.size();
  const double inv_spp = 1.0 / camera.spp;
  const Props props(scene);
  const SampleShader<Tracer> shader(scene, tracer, props, passes);
  TallyRequest* const tally = request.tally;
  RecordRequest* const record = request.record;
  const bool sinks = tally || record;
  if ((options.resume || options.sums) && (sinks || !std::is_same_v<Tracer, MeshTracer>))
    throw std::invalid_argument("render: only displacement truths resume or keep their sums");
  const PixelSumsIo sums_io(camera, options, pass_count);
  // A user method's recording and a tally go through packets too
  // (PacketRows): their samples come in the scalar path's order.
  const bool packets = traces_packets(scene, shader, passes, options);
  const PacketSetup setup = packet_setup(scene, tracer);

  std::atomic<int> rows_done{0};
  std::atomic<std::uint64_t> shadow_rays{0};
  std::mutex progress_mutex;
  auto last_report = Clock::now();

  tbb::parallel_for(
      tbb::blocked_range<int>(first_row, end_row), [&](const tbb::blocked_range<int>& rows) {
        std::uint64_t local_shadow_rays = 0;
        std::vector<PixelSums> sums(pass_count);
        std::vector<std::pair<int, double>> entries;  // a tallied pixel's samples
        double rest = 0.0;
        std::vector<double> probe_sums(tally ? tally->probe_values() : 0);
        std::optional<TallySink> tally_sink;
        if (tally)
          tally_sink.emplace(tally->grid, tally->lobes, &entries, &rest, tally->probe_list(),
                             &probe_sums);
        std::optional<PacketRows> packet_rows;
        if constexpr (std::is_same_v<Tracer, BaseTracer>)
          if (packets) packet_rows.emplace(scene, setup, shader, pass_count, images);
        for (int j = rows.begin(); j != rows.end(); ++j) {
          std::optional<RecordSink> record_sink;
          if (record) {
            SampleRecords* recorded = &record->rows[std::size_t(j - record->first_row)];
            recorded->rest.assign(std::size_t(width), 0.0);
            record_sink.emplace(*record->pass, record->vectors, recorded);
          }
          if (packet_rows && tally_sink) {
            const RowTallySink row(&*tally_sink, tally, {&entries, &rest, &probe_sums},
                                   std::uint64_t(j) * width, width, inv_spp);
            packet_rows->render_row(j, &local_shadow_rays, &row);
            row.finish();
          } else if (packet_rows) {
            packet_rows->render_row(j, &local_shadow_rays, record_sink ? &*record_sink : nullptr);
          } else {
            const SampleSink* sink = tally_sink    ? static_cast<const SampleSink*>(&*tally_sink)
                                     : record_sink ? &*record_sink
                                                   : nullptr;
            for (int i = 0; i < width; ++i) {
              const std::uint64_t pixel = std::uint64_t(j) * width + i;
              const std::uint64_t key = pixel_key(camera, i, j);
              Pcg32 rng(key);
              sums_io.start(pixel, sums.data(), pass_count);
              entries.clear();
              rest = 0.0;
              std::fill(probe_sums.begin(), probe_sums.end(), 0.0);
              if (tally_sink) tally_sink->probe_pixel(tally->probes_pixel(pixel));
              shade_pixel(
                  scene, tracer, props, shader,
                  {i, j, key, &rng, sums.data(), &local_shadow_rays, sink, sums_io.first_sample()},
                  options.packets && !sinks);
              sums_io.finish(pixel, sums.data(), pass_count);
              if (tally) tally->store(pixel, entries, rest, probe_sums, inv_spp);
              for (std::size_t k = 0; k < pass_count; ++k)
                write_pixel(sums[k], inv_spp, &(*images)[k].pixels[pixel * channel_count]);
            }
          }
          const int done = ++rows_done;
          if (options.progress) {
            std::lock_guard<std::mutex> lock(progress_mutex);
            const auto now = Clock::now();
            if (done == end_row - first_row || now - last_report > std::chrono::milliseconds(250)) {
              last_report = now;
              options.progress(static_cast<double>(first_row + done) / height);
            }
          }
        }
        shadow_rays += local_shadow_rays;
      });
  if (stats) {
    stats->camera_samples = std::uint64_t(width) * height * std::uint64_t(sums_io.drawn());
    stats->resumed_spp = sums_io.first_sample();
    stats->shadow_rays += shadow_rays;
    stats->packets = stats->packets || packets ||
                     (requires { Tracer::kPacketRays; } && options.packets && !sinks);
    // (PacketRows records; a tracer's own packets, shade_pixel_packets, do not.)
  }
}

// Samples per recorded block of a user method's pass: about 20 MiB of
// records (60 more with the vectors), and a few blocks per image, so that
// each call of the user's function covers thousands of samples.
constexpr std::size_t kRecordedSamples = std::size_t(1) << 19;

// A user method's image for the pixels of `r` (from pixel `first_pixel`
// on): the raw-bump pass's channels, but for the
// radiance, the light no factor scales plus each sample's g times the light
// it scales, in the order of the samples, and analysis.G, the mean of g
// over the samples that hit.
void write_user_pixels(const SampleRecords& r, std::span<const double> g, const Image& raw,
                       std::size_t first_pixel, double inv_spp, Image* out) {
  const std::size_t c = evaluator_channels().size();
  const std::size_t pixels = r.rest.size();
  std::vector<double> radiance(r.rest), g_sum(pixels, 0.0), hits(pixels, 0.0);
  for (std::size_t k = 0; k < g.size(); ++k) {
    const std::size_t q = r.column[k];
    radiance[q] += g[k] * r.light[k];
    g_sum[q] += g[k];
    hits[q] += 1.0;
  }
  for (std::size_t q = 0; q < pixels; ++q) {
    const std::size_t at = (first_pixel + q) * c;
    std::copy_n(&raw.pixels[at], c, &out->pixels[at]);
    out->pixels[at] = out->pixels[at + 1] = out->pixels[at + 2] =
        static_cast<float>(radiance[q] * inv_spp);
    if (hits[q] > 0.0) out->pixels[at + 6] = static_cast<float>(g_sum[q] / hits[q]);
  }
}

Image blank_image(const Scene& scene) {
  Image image;
  image.width = scene.camera.width;
  image.height = scene.camera.height;
  image.channels = evaluator_channels();
  image.pixels.assign(std::size_t(image.width) * image.height * image.channels.size(), 0.0f);
  return image;
}

// The images of user methods' passes (core/user_method.h), all with the
// lobes and reference normal of users[0], from one raw-bump render whose
// samples are recorded a block of rows at a time: after each block, every
// user's function is called once on the block's samples, on this thread.
template <typename Tracer>
void render_user_passes(const Scene& scene, const Tracer& tracer, const RenderOptions& options,
                        const std::vector<const TerminatorSettings*>& users,
                        const std::vector<Image*>& out, RenderStats* stats) {
  TerminatorSettings raw = *users.front();
  raw.method = MethodSettings{};
  const bool vectors = std::any_of(users.begin(), users.end(), [](const TerminatorSettings* t) {
    return t->method.user->wants_vectors;
  });
  const Camera& camera = scene.camera;
  const std::size_t row_samples = std::size_t(camera.width) * camera.spp;
  const int block = static_cast<int>(std::max<std::size_t>(1, kRecordedSamples / row_samples));
  std::vector<Image> raw_image{blank_image(scene)};
  std::vector<double> g;
  for (int first = 0; first < camera.height; first += block) {
    const int end = std::min(camera.height, first + block);
    RecordRequest record{&raw, vectors, first,
                         std::vector<SampleRecords>(std::size_t(end - first))};
    render_image(scene, tracer, options, {raw}, &raw_image, stats,
                 {.record = &record, .first_row = first, .end_row = end});
    SampleRecords all = std::move(record.rows.front());
    for (std::size_t row = 1; row < record.rows.size(); ++row) all.append(record.rows[row]);
    g.assign(all.light.size(), 0.0);
    for (std::size_t k = 0; k < users.size(); ++k) {
      const MethodSettings& m = users[k]->method;
      if (!g.empty()) evaluate_user_method(*m.user, all.batch(), m.user_values, g);
      write_user_pixels(all, g, raw_image.front(), std::size_t(first) * camera.width,
                        1.0 / camera.spp, out[k]);
    }
  }
}

bool is_user_pass(const TerminatorSettings& t) {
  return t.method.method == TerminatorMethod::kPython;
}

// Every pass of render_methods on one tracer: the built-in methods in one
// pass, the user methods through recorded raw-bump passes, one per
// distinct (lobes, reference normal).
template <typename Tracer>
void render_passes(const Scene& scene, const Tracer& tracer, const RenderOptions& options,
                   const std::vector<TerminatorSettings>& methods, std::vector<Image>* images,
                   RenderStats* stats) {
  std::vector<TerminatorSettings> built_in;
  std::vector<std::size_t> built_in_at, users_at;
  for (std::size_t k = 0; k < methods.size(); ++k) {
    if (is_user_pass(methods[k])) {
      users_at.push_back(k);
    } else {
      built_in.push_back(methods[k]);
      built_in_at.push_back(k);
    }
  }
  if (users_at.empty()) return render_image(scene, tracer, options, methods, images, stats);
  if (!built_in.empty()) {
    std::vector<Image> rendered(built_in.size(), blank_image(scene));
    render_image(scene, tracer, options, built_in, &rendered, stats);
    for (std::size_t k = 0; k < built_in.size(); ++k)
      (*images)[built_in_at[k]] = std::move(rendered[k]);
  }
  while (!users_at.empty()) {
    const TerminatorSettings& first = methods[users_at.front()];
    std::vector<const TerminatorSettings*> group;
    std::vector<Image*> out;
    std::vector<std::size_t> rest;
    for (const std::size_t k : users_at) {
      const TerminatorSettings& t = methods[k];
      if (t.lobes == first.lobes && t.reference_normal == first.reference_normal) {
        group.push_back(&t);
        out.push_back(&(*images)[k]);
      } else {
        rest.push_back(k);
      }
    }
    render_user_passes(scene, tracer, options, group, out, stats);
    users_at = std::move(rest);
  }
}

// analysis.theta and analysis.view of every pixel whose centre ray meets the
// base shape before anything else: the light and view angles at that base
// point, one point per pixel instead of the mean over its samples at the base
// points under their hits. A pixel's bin in the profile and the viewer
// metric then depends on the camera and the base shape alone: not on the
// samples per pixel, the edge length or the representation. With the means,
// a pixel near a bin edge hopped bins between a ground truth and its check
// (4x the samples, or half the edge length), and under a glossy lobe, whose
// pixels within one bin differ a lot, each hop moved a bin by 0.006 of
// albedo*E/pi: six truths of the default study never converged. The
// displaced truth's pixels are binned like every method's, by the base
// point under the pixel: the profile compares the same pixels, and the
// parallax of displacement, which no bump method reproduces, counts in every
// method's error alike. Pixels whose centre ray misses the base shape
// (silhouettes, a displaced surface beyond it) or meets a prop first keep
// the mean.
// The base surface under the pixel-centre ray: the analytic shape's (a
// tessellation's too), or a mesh shape's flat triangle with Ni as its
// normal, so that a mesh's angles do not depend on the samples either.
std::optional<Hit> centre_hit(const Scene& scene, const LowPolyMesh* mesh, const Ray& ray) {
  Hit hit;
  if (scene.shape.type != ShapeType::kMesh)
    return penumbra::intersect(scene.shape, ray, 0.0, std::numeric_limits<double>::infinity(), &hit)
               ? std::optional<Hit>(hit)
               : std::nullopt;
  const std::optional<LowPolyHit> h = mesh->intersect(ray);
  if (!h) return std::nullopt;
  hit.t = h->t;
  hit.geometry = h->base;
  return hit;
}

// `mesh`: a mesh shape's base triangles where the caller has them (built
// here otherwise).
void centre_angles(const Scene& scene, std::vector<Image>* images,
                   const LowPolyMesh* mesh = nullptr) {
  std::unique_ptr<const LowPolyMesh> own;
  if (scene.shape.type == ShapeType::kMesh && !mesh) {
    own = std::make_unique<const LowPolyMesh>(scene.shape);
    mesh = own.get();
  }
  const Camera& camera = scene.camera;
  const Props props(scene);
  const Vec3 orthographic_direction = normalize(camera.direction);
  const std::size_t channels = evaluator_channels().size();
  tbb::parallel_for(
      tbb::blocked_range<int>(0, camera.height), [&](const tbb::blocked_range<int>& rows) {
        for (int j = rows.begin(); j != rows.end(); ++j)
          for (int i = 0; i < camera.width; ++i) {
            const Ray ray = camera_ray(camera, orthographic_direction, i, j, 0, 0, 1, 1, Jitter{});
            const std::optional<Hit> hit = centre_hit(scene, mesh, ray);
            if (!hit) continue;
            if (!props.empty() && props.occluded(ray.origin, ray.direction, hit->t)) continue;
            const SurfaceGeometry& g = hit->geometry;
            const Vec3 wo = -ray.direction;
            const Vec3 n =
                dot(g.n, wo) < 0.0 ? -g.n : g.n;  // seen from inside, as prepare() turns it
            const Vec3 wi =
                is_area_light(scene.light) ? Vec3{} : sample_light(scene.light, g.p, {}).wi;
            const auto theta =
                static_cast<float>(degrees(acos_approx(cos_light_angle(scene.light, n, g.p, wi))));
            const auto view = static_cast<float>(degrees(acos_approx(dot(n, wo))));
            const std::size_t pixel = std::size_t(j) * std::size_t(camera.width) + std::size_t(i);
            for (Image& image : *images) {
              float* out = &image.pixels[pixel * channels];
              if (!(out[3] > 0.0f)) continue;  // no sample hit: the channels stay empty
              out[4] = theta;
              out[7] = view;
            }
          }
      });
}

// The triangles a bump or smooth render traces: a tessellation's or a mesh
// shape's; null for an analytic shape.
std::unique_ptr<const LowPolyMesh> low_poly_mesh(const Scene& scene) {
  if (scene.tessellation)
    return std::make_unique<const LowPolyMesh>(scene.shape, *scene.tessellation);
  if (scene.shape.type == ShapeType::kMesh) return std::make_unique<const LowPolyMesh>(scene.shape);
  return nullptr;
}

}  // namespace

bool shares_samples(const TerminatorSettings& terminator) {
  return !method_info(terminator.method.method).draws_random;
}

std::vector<Image> render_methods(const Scene& scene,
                                  const std::vector<TerminatorSettings>& methods,
                                  const RenderOptions& options, RenderStats* stats) {
  if (methods.empty()) throw std::invalid_argument("render_methods: no method");
  if (methods.size() > 1)
    for (const TerminatorSettings& t : methods)
      if (!shares_samples(t))
        throw std::invalid_argument(
            fmt::format("render_methods: {} draws random numbers while shading; render it alone",
                        method_info(t.method.method).id));
  for (const TerminatorSettings& t : methods)
    if (is_user_pass(t) &&
        (!t.method.user || scene.representation == Representation::kDisplacement ||
         effective_adjustment(t) != NormalAdjustment::kNone))
      throw std::invalid_argument(
          "render_methods: a user method is a plain factor on a bump or smooth render, with its "
          "function registered and no normal adjustment");
  const auto start = Clock::now();
  RenderStats local;
  std::vector<Image> images(methods.size(), blank_image(scene));
  if (scene.representation == Representation::kDisplacement) {
    const std::shared_ptr<const DisplacedMesh> mesh =
        options.share_meshes ? shared_displaced_mesh(scene, &local.mesh_reused)
                             : std::make_shared<const DisplacedMesh>(scene);
    local.triangles = mesh->triangle_count();
    local.build_seconds = std::chrono::duration<double>(Clock::now() - start).count();
    const MeshTracer tracer(scene, *mesh);
    render_image(scene, tracer, options, methods, &images, &local);
    centre_angles(scene, &images);
  } else if (const auto mesh = low_poly_mesh(scene)) {
    local.triangles = mesh->triangle_count();
    local.build_seconds = std::chrono::duration<double>(Clock::now() - start).count();
    const LowPolyTracer tracer(scene, *mesh);
    render_passes(scene, tracer, options, methods, &images, &local);
    centre_angles(scene, &images, mesh.get());
  } else {
    const BaseTracer tracer(scene);
    render_passes(scene, tracer, options, methods, &images, &local);
    centre_angles(scene, &images);
  }
  local.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  if (stats) *stats = local;
  return images;
}

Image render(const Scene& scene, const RenderOptions& options, RenderStats* stats) {
  return std::move(render_methods(scene, {scene.terminator}, options, stats).front());
}

namespace {

// One lighting of a shared truth pass (render_lightings): its scene, the
// one pass it renders (its terminator) and the shader that shades it.
struct Lighting {
  const Scene* scene = nullptr;
  std::vector<TerminatorSettings> passes;
  std::unique_ptr<const SampleShader<MeshTracer>> shader;
};

// One pixel of every lighting: each block of camera rays and their hits
// once, then each lighting's shading and shadow rays as shade_pixel_packets
// (or, without packets, shade_pixel) does them for that lighting alone: its
// sums receive the same values in the same order, so they are the same bits.
struct LightingPixel {
  int i = 0, j = 0;
  std::uint64_t key = 0;
  std::vector<Pcg32>* rngs = nullptr;      // one per lighting
  std::vector<PixelSums>* sums = nullptr;  // one per lighting
  std::uint64_t* shadow_rays = nullptr;
  int first_sample = 0;  // a resumed render's: the samples its sums hold
};

void shade_pixel_lightings(const Scene& first, const MeshTracer& tracer, const Props& props,
                           const std::vector<Lighting>& lightings, const LightingPixel& pixel,
                           bool packets) {
  constexpr std::size_t kRays = MeshTracer::kPacketRays;
  const Camera& camera = first.camera;
  int nx, ny;
  strata(camera.spp, &nx, &ny);
  const Vec3 orthographic_direction = normalize(camera.direction);
  const std::size_t block = packets ? kRays : 1;
  SampleBlock<kRays> b;
  thread_local std::vector<LitPass> lit;
  std::vector<Material> materials;
  for (const Lighting& l : lightings) materials.push_back(l.scene->material);
  const int count = nx * ny;
  for (int start = pixel.first_sample; start < count; start += int(block)) {
    const std::size_t n = std::min<std::size_t>(block, std::size_t(count - start));
    b.camera_rays(first, orthographic_direction, pixel.i, pixel.j, pixel.key, start, n, nx, ny);
    if (packets) {
      tracer.primary_packet(b.rays, n, b.hits, b.found);
    } else {
      b.found[0] = tracer.primary(b.rays[0], &b.hits[0]);
    }
    for (std::size_t k = 0; k < n; ++k) {
      b.hits[k].on_prop = false;
      b.found[k] = props.nearer(b.rays[k], b.found[k], &b.hits[k]) || b.found[k];
    }
    for (std::size_t l = 0; l < lightings.size(); ++l) {
      const Lighting& lighting = lightings[l];
      Material& material = materials[l];
      PixelSums* sums = &(*pixel.sums)[l];
      lit.clear();
      for (std::size_t k = 0; k < n; ++k) {
        if (!b.found[k]) continue;
        material.filtered.active = false;
        const LightUniforms u = light_uniforms(*lighting.scene, pixel.key, start + int(k), nx, ny);
        if (const auto p = lighting.shader->shade_deferred(b.rays[k], b.hits[k], u, &material,
                                                           &(*pixel.rngs)[l], sums, &lit))
          b.wait(*p);
      }
      b.settle(tracer, props, lit, packets, sums, pixel.shadow_rays);
    }
  }
}

// The rows of every lighting's image (render_lightings).
void render_lighting_images(const Scene& first, const MeshTracer& tracer, const Props& props,
                            const std::vector<Lighting>& lightings, const RenderOptions& options,
                            std::vector<Image>* images, RenderStats* stats) {
  const Camera& camera = first.camera;
  const std::size_t channel_count = evaluator_channels().size();
  const double inv_spp = 1.0 / camera.spp;
  const PixelSumsIo sums_io(camera, options, lightings.size());
  std::atomic<int> rows_done{0};
  std::atomic<std::uint64_t> shadow_rays{0};
  std::mutex progress_mutex;
  auto last_report = Clock::now();
  tbb::parallel_for(
      tbb::blocked_range<int>(0, camera.height), [&](const tbb::blocked_range<int>& rows) {
        std::uint64_t local_shadow_rays = 0;
        std::vector<PixelSums> sums(lightings.size());
        std::vector<Pcg32> rngs;
        for (int j = rows.begin(); j != rows.end(); ++j) {
          for (int i = 0; i < camera.width; ++i) {
            const std::uint64_t key = pixel_key(camera, i, j);
            const std::size_t pixel = std::size_t(j) * std::size_t(camera.width) + std::size_t(i);
            rngs.assign(lightings.size(), Pcg32(key));
            sums_io.start(pixel, sums.data(), sums.size());
            shade_pixel_lightings(
                first, tracer, props, lightings,
                {i, j, key, &rngs, &sums, &local_shadow_rays, sums_io.first_sample()},
                options.packets);
            sums_io.finish(pixel, sums.data(), sums.size());
            for (std::size_t l = 0; l < lightings.size(); ++l)
              write_pixel(sums[l], inv_spp, &(*images)[l].pixels[pixel * channel_count]);
          }
          const int done = ++rows_done;
          if (options.progress) {
            std::lock_guard<std::mutex> lock(progress_mutex);
            const auto now = Clock::now();
            if (done == camera.height || now - last_report > std::chrono::milliseconds(250)) {
              last_report = now;
              options.progress(static_cast<double>(done) / camera.height);
            }
          }
        }
        shadow_rays += local_shadow_rays;
      });
  stats->camera_samples =
      std::uint64_t(camera.width) * std::uint64_t(camera.height) * std::uint64_t(sums_io.drawn());
  stats->resumed_spp = sums_io.first_sample();
  stats->shadow_rays = shadow_rays;
  stats->packets = options.packets;
}

}  // namespace

std::vector<Image> render_lightings(const std::vector<Scene>& scenes, const RenderOptions& options,
                                    RenderStats* stats) {
  if (scenes.empty()) throw std::invalid_argument("render_lightings: no scene");
  for (const Scene& s : scenes)
    if (s.representation != Representation::kDisplacement || !shares_samples(s.terminator))
      throw std::invalid_argument(
          "render_lightings: renders displacement truths whose method draws no random numbers");
  const auto start = Clock::now();
  RenderStats local;
  const Scene& first = scenes.front();
  const std::shared_ptr<const DisplacedMesh> mesh =
      options.share_meshes ? shared_displaced_mesh(first, &local.mesh_reused)
                           : std::make_shared<const DisplacedMesh>(first);
  local.triangles = mesh->triangle_count();
  local.build_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  const MeshTracer tracer(first, *mesh);
  const Props props(first);
  std::vector<Lighting> lightings(scenes.size());
  for (std::size_t l = 0; l < scenes.size(); ++l) {
    lightings[l].scene = &scenes[l];
    lightings[l].passes = {scenes[l].terminator};
    lightings[l].shader = std::make_unique<const SampleShader<MeshTracer>>(scenes[l], tracer, props,
                                                                           lightings[l].passes);
  }
  std::vector<Image> images(scenes.size(), blank_image(first));
  render_lighting_images(first, tracer, props, lightings, options, &images, &local);
  for (std::size_t l = 0; l < scenes.size(); ++l) {
    std::vector<Image> one{std::move(images[l])};
    centre_angles(scenes[l], &one);
    images[l] = std::move(one.front());
  }
  local.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  if (stats) *stats = local;
  return images;
}

namespace {

PixelTally flatten(const TallyRequest& request, int width, int height) {
  PixelTally tally;
  tally.width = width;
  tally.height = height;
  tally.rest = request.rest;
  tally.offsets.reserve(request.scaled.size() + 1);
  tally.offsets.push_back(0);
  for (const auto& pixel : request.scaled) {
    for (const auto& [cell, light] : pixel) {
      tally.cells.push_back(cell);
      tally.light.push_back(light);
    }
    tally.offsets.push_back(static_cast<std::uint32_t>(tally.cells.size()));
  }
  return tally;
}

}  // namespace

Image render_tallied(const Scene& scene, const FactorGrid& grid, PixelTally* tally,
                     const RenderOptions& options, RenderStats* stats, TallyProbes* probes) {
  const TerminatorSettings& t = scene.terminator;
  if (scene.representation == Representation::kDisplacement ||
      t.method.method != TerminatorMethod::kNone ||
      effective_adjustment(t) != NormalAdjustment::kNone)
    throw std::invalid_argument(
        "render_tallied: tallies raw bump only (method none, no normal adjustment, not displaced)");
  const auto start = Clock::now();
  RenderStats local;
  std::vector<Image> images(1);
  Image& image = images.front();
  image.width = scene.camera.width;
  image.height = scene.camera.height;
  image.channels = evaluator_channels();
  image.pixels.assign(std::size_t(image.width) * image.height * image.channels.size(), 0.0f);
  const std::size_t pixels = std::size_t(image.width) * image.height;
  TallyRequest request{&grid, t.lobes, std::vector<std::vector<std::pair<int, double>>>(pixels),
                       std::vector<double>(pixels, 0.0), probes};
  if (probes && !probes->pixels.empty() && probes->pixels.size() != pixels)
    throw std::invalid_argument("render_tallied: the probes' pixels are not the image's");
  if (probes) {
    probes->radiance.clear();
    for (const FactorProbe& p : probes->probes)
      probes->radiance.emplace_back(pixels * p.values, 0.0);
  }
  if (const auto mesh = low_poly_mesh(scene)) {
    local.triangles = mesh->triangle_count();
    local.build_seconds = std::chrono::duration<double>(Clock::now() - start).count();
    const LowPolyTracer tracer(scene, *mesh);
    render_image(scene, tracer, options, {t}, &images, &local, {.tally = &request});
    centre_angles(scene, &images, mesh.get());
  } else {
    const BaseTracer tracer(scene);
    render_image(scene, tracer, options, {t}, &images, &local, {.tally = &request});
    centre_angles(scene, &images);
  }
  *tally = flatten(request, image.width, image.height);
  local.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  if (stats) *stats = local;
  return std::move(image);
}

}  // namespace penumbra
