// Typed scene description. Every field documents its unit and domain; the
// JSON reader (scene_json.h) enforces them. Coordinates follow POV-Ray's
// convention (left-handed, y up, the camera's `direction` into the screen),
// so the POV-Ray export copies numbers unchanged.
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/bsdf.h"
#include "core/enum_names.h"
#include "core/environment.h"
#include "core/filtered_map.h"
#include "core/height.h"
#include "core/sample_pattern.h"
#include "core/shading.h"
#include "core/shadow_origin.h"
#include "core/shape.h"
#include "core/surface_map.h"
#include "core/terminator.h"
#include "core/tessellation.h"
#include "core/vec.h"
#include "util/version.h"

namespace penumbra {

inline constexpr int kSceneFormatVersion = 1;
inline constexpr int kMaxImageSize = 16384;
// Input domains that keep every quantity finite in float (Embree, images):
// coordinates and lengths within +-1e6 scene units (shapes are meant to be
// near unit size), lengths at least 1e-6, frequencies at most 1e6 cycles per
// unit, irradiance and intensity at most 1e9 W/m^2 or W/sr.
inline constexpr double kMaxCoordinate = 1e6;
inline constexpr double kMinLength = 1e-6;
inline constexpr double kMaxFrequency = 1e6;
inline constexpr double kMaxRadiant = 1e9;

enum class Projection { kOrthographic, kPerspective };
inline constexpr EnumName<Projection> kProjectionNames[] = {
    {"orthographic", Projection::kOrthographic}, {"perspective", Projection::kPerspective}};

// Pixel (i, j), j = 0 at the top, sample offset (a, b) in [0,1)^2:
//   x0 = (i + a)/width - 1/2,   y0 = 1/2 - (j + b)/height
//   orthographic: origin = position + x0 right + y0 up, direction = direction
//   perspective:  origin = position, direction = direction + x0 right + y0 up
// (reference sheet, section 6). Directions are normalised for tracing only.
struct Camera {
  Projection projection = Projection::kOrthographic;
  Vec3 position{0, 0, -5};
  Vec3 direction{0, 0, 1};
  Vec3 right{2.5, 0, 0};  // full image width in scene units (orthographic)
  Vec3 up{0, 2.5, 0};     // full image height in scene units (orthographic)
  int width = 256;        // pixels, [1, 16384]
  int height = 256;       // pixels, [1, 16384]
  int spp = 16;           // samples per pixel, [1, 65536], stratified
  std::uint64_t seed = 0;
  bool jitter = true;  // false: stratum centres (deterministic pixel grid)
};

// Stratification of spp samples: strata() in core/sample_pattern.h. Samples
// sit at stratum centres when the camera does not jitter; POV-Ray renders
// exactly those.

// Delta lights (distant, point), area lights (sphere, quad) of uniform
// radiance and a captured environment at infinity, which the evaluator
// samples per camera sample (core/light_sampling.h, core/environment.h);
// the camera sees none of them (the background stays black). A group is
// several of them in one scene, one drawn per camera sample.
enum class LightType { kDistant, kPoint, kSphere, kQuad, kEnvironment, kGroup };
inline constexpr EnumName<LightType> kLightTypeNames[] = {
    {"distant", LightType::kDistant},         {"point", LightType::kPoint},
    {"sphere", LightType::kSphere},           {"quad", LightType::kQuad},
    {"environment", LightType::kEnvironment}, {"group", LightType::kGroup}};

// How an area light's directions are drawn per camera sample: by the
// light's own sampler alone, or by one-sample multiple importance sampling
// that also draws cosine-weighted directions about the surface normal
// (evaluator.md, "Area and environment lights", says where each lowers the
// variance and which is the default).
enum class LightSampling { kLight, kMis };
inline constexpr EnumName<LightSampling> kLightSamplingNames[] = {{"light", LightSampling::kLight},
                                                                  {"mis", LightSampling::kMis}};

struct Light {
  LightType type = LightType::kDistant;
  Vec3 direction{-1, 0, 0};  // distant: unit vector towards the light
  double irradiance = kPi;   // distant: W/m^2 on a plane facing the light, >= 0
  Vec3 position;             // point: scene units; sphere: its centre
  double intensity = 0.0;    // point: W/sr, >= 0
  double radius = 0.0;       // sphere: scene units, > 0
  // quad: the parallelogram corner + a edge_u + b edge_v, (a, b) in [0,1]^2,
  // emitting on the side edge_u x edge_v points to (scene units).
  Vec3 corner, edge_u, edge_v;
  // sphere and quad: emitted radiance, W/(m^2 sr), >= 0. A power P (W) in
  // the JSON becomes P / (4 pi^2 radius^2) for a sphere (pi L times its
  // area) and P / (pi area) for a one-sided quad.
  double radiance = 0.0;
  // environment: the map's radiance (the Rec. 709 luminance of its R, G, B;
  // W/(m^2 sr) per unit of the file's values) times `scale` (>= 0), the
  // lookup direction turned by `rotation_deg` about the up axis
  // (core/environment.h). `map_digest` is its texels' content digest (what
  // the cache key holds).
  std::shared_ptr<const EnvironmentMap> environment;
  std::string map_digest;
  double rotation_deg = 0.0;
  double scale = 1.0;
  // sphere, quad and environment (the delta lights have one direction).
  LightSampling sampling = LightSampling::kLight;
  // group: its lights (2 to 8, none a group, at most one environment), and
  // the cumulative probabilities a camera sample draws each with
  // (member_cdf[i + 1] - member_cdf[i]: mostly in proportion to the
  // irradiance each gives the shape's centre; set_member_weights).
  std::vector<Light> members;
  std::vector<double> member_cdf;
};

// Lights sampled per camera sample (all but the delta lights; a group
// draws one of its lights per sample).
inline bool is_area_light(const Light& light) {
  return light.type == LightType::kSphere || light.type == LightType::kQuad ||
         light.type == LightType::kEnvironment || light.type == LightType::kGroup;
}

inline Vec3 light_vector(const Light& light, const Vec3& at);

// Where the light is seen from `at`, for the angles a study states per
// variant: towards a distant light, or towards a point light's position, a
// sphere's centre or a quad's centre; an environment's radiance-weighted
// mean direction.
inline Vec3 light_axis(const Light& light, const Vec3& at) {
  switch (light.type) {
    case LightType::kDistant:
      return light.direction;
    case LightType::kPoint:
    case LightType::kSphere:
      return light.position - at;
    case LightType::kQuad:
      return light.corner + (light.edge_u + light.edge_v) * 0.5 - at;
    case LightType::kEnvironment:
      return light.environment ? light.environment->mean_direction() : Vec3{0, 1, 0};
    case LightType::kGroup:
      break;
  }
  // A group: where its light comes from on balance, its light vector.
  Vec3 sum;
  for (const Light& m : light.members) sum += light_vector(m, at);
  return length_squared(sum) > 0.0 ? sum : Vec3{0, 1, 0};
}

// Gershun's light vector at `at` (W/m^2): the integral of L w dw over the
// directions w the light is seen in from `at`, shadows aside. n . it is the
// irradiance on a plane of normal n that has the whole light in front of
// it, and its direction is where the light comes from on balance: a
// distant or point light's own direction, a sphere's centre, the middle of
// a quad's solid angle, an environment's radiance-weighted mean. The
// terminator metric bins by the angle between it and the base normal
// (analysis.theta), which is the light angle itself for a distant light.
// Zero inside a sphere light, on or behind a quad's plane, and for an
// environment whose light cancels out (a uniform one).
inline Vec3 light_vector(const Light& light, const Vec3& at) {
  switch (light.type) {
    case LightType::kDistant:
      return light.direction * light.irradiance;
    case LightType::kPoint: {
      const Vec3 d = light.position - at;
      const double d2 = length_squared(d);
      return d2 > 0.0 ? d * (light.intensity / (d2 * std::sqrt(d2))) : Vec3{};
    }
    case LightType::kSphere: {
      // The cone of half-angle theta_max: pi L sin^2 theta_max along its axis.
      const Vec3 d = light.position - at;
      const double d2 = length_squared(d), r2 = light.radius * light.radius;
      if (!(d2 > r2)) return {};
      return d * (kPi * light.radiance * r2 / (d2 * std::sqrt(d2)));
    }
    case LightType::kQuad: {
      const Vec3 v[4] = {light.corner, light.corner + light.edge_u,
                         light.corner + light.edge_u + light.edge_v, light.corner + light.edge_v};
      if (!(dot(cross(light.edge_u, light.edge_v), at - light.corner) > 0.0)) return {};
      return polygon_light_vector(v, 4, at, light.radiance);
    }
    case LightType::kEnvironment:
      return light.environment ? light.environment->light_vector() * light.scale : Vec3{};
    case LightType::kGroup: {
      Vec3 sum;
      for (const Light& m : light.members) sum += light_vector(m, at);
      return sum;
    }
  }
  return {};
}

// What a group weighs its lights by: the irradiance each gives a plane at
// `at` facing it (shadows aside), W/m^2; an environment's on its mean
// direction (a uniform map's light vector is zero, its irradiance is not).
inline double light_strength(const Light& light, const Vec3& at) {
  if (light.type == LightType::kEnvironment)
    return light.environment
               ? light.scale * light.environment->irradiance(light.environment->mean_direction())
               : 0.0;
  return length(light_vector(light, at));
}

// A group's member_cdf from its lights' strengths at `at` (the shape's
// centre); equal where none has any.
inline void set_member_weights(Light* group, const Vec3& at) {
  // A tenth of the samples spread evenly: a light dim at the centre (a quad
  // whose plane it lies behind) may still light the shape elsewhere, and
  // a light never drawn would be a bias, not noise.
  constexpr double kEven = 0.1;
  std::vector<double> w;
  double total = 0.0;
  for (const Light& m : group->members) total += w.emplace_back(light_strength(m, at));
  const double n = double(w.size());
  group->member_cdf.assign(1, 0.0);
  for (const double wi : w)
    group->member_cdf.push_back(group->member_cdf.back() +
                                (total > 0.0 ? (1.0 - kEven) * wi / total + kEven / n : 1.0 / n));
  group->member_cdf.back() = 1.0;
}

enum class Representation {
  kSmooth,        // base geometry, Ns = base normal
  kBump,          // base geometry, Ns = exact normal of the displaced surface
  kDisplacement,  // the displaced surface itself (ground truth)
};
inline constexpr EnumName<Representation> kRepresentationNames[] = {
    {"smooth", Representation::kSmooth},
    {"bump", Representation::kBump},
    {"displacement", Representation::kDisplacement}};

// The analytic families, and image maps over the shape's (u, v)
// (core/surface_map.h): a height map (bump and displacement) or a
// tangent-space normal map (bump only: it has no surface to displace).
enum class HeightFamily { kNone, kGrating, kWeave, kNoise, kHeightMap, kNormalMap };
inline constexpr EnumName<HeightFamily> kHeightFamilyNames[] = {
    {"none", HeightFamily::kNone},
    {"grating", HeightFamily::kGrating},
    {"weave", HeightFamily::kWeave},
    {"noise", HeightFamily::kNoise},
    {"height-map", HeightFamily::kHeightMap},
    {"normal-map", HeightFamily::kNormalMap}};

struct HeightSpec {
  HeightFamily family = HeightFamily::kNone;
  // A, scene units, >= 0, A max|h| < radius. A height map's texel values are
  // h; a normal map has no amplitude (0 here).
  double amplitude = 0.0;
  HeightFunction function;  // analytic families; no terms for image maps
  // Image maps: the texels read from /height/file (shared between the copies
  // of a scene a study makes).
  std::shared_ptr<const SurfaceMap> map;
  // /height/filter: the map's pyramids and the roughness filter that shade
  // each bump sample for its footprint (absent: the map unfiltered).
  std::shared_ptr<const FilteredMap> filtered;

  const SurfaceMap* height_map() const {
    return map && map->kind == MapKind::kHeight ? map.get() : nullptr;
  }
  const SurfaceMap* normal_map() const {
    return map && map->kind == MapKind::kNormal ? map.get() : nullptr;
  }
};

struct DisplacementSettings {
  double edge_length = 0.0;  // scene units, > 0; tessellation of the ground truth
};

struct Scene {
  std::string name;
  Camera camera;
  Light light;
  Shape shape;
  // JSON /shape/tessellation. Absent: the analytic shape. Present: the shape
  // as a triangle mesh (smooth and bump representations only), which is
  // what makes the smooth-shading terminator and what `offset` acts on.
  std::optional<Tessellation> tessellation;
  // Where shadow rays leave a mesh triangle; anything but `none` needs a
  // tessellation.
  OffsetSettings offset;
  // Extra analytic spheres (smooth, same material, no height): they cast and
  // receive shadows, for side-effect scenes such as a small ball resting on a
  // large low-poly surface. Evaluator only.
  std::vector<Shape> props;
  Material material;
  HeightSpec height;
  Representation representation = Representation::kBump;
  TerminatorSettings terminator;
  DisplacementSettings displacement;
};

}  // namespace penumbra
