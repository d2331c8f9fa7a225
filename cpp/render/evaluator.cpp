#include "render/evaluator.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <mutex>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/random.h"
#include "render/displaced_mesh.h"

namespace penumbra {

const std::vector<std::string>& evaluator_channels() {
  static const std::vector<std::string> channels{
      "R", "G", "B", "A", "analysis.theta", "analysis.deviation", "analysis.G"};
  return channels;
}

int Image::channel_index(const std::string& name) const {
  for (std::size_t i = 0; i < channels.size(); ++i)
    if (channels[i] == name) return static_cast<int>(i);
  return -1;
}

namespace {

using Clock = std::chrono::steady_clock;

struct LightSample {
  Vec3 wi;
  double irradiance = 0.0;  // W/m^2 on a plane facing the light
  double distance = 0.0;    // to the light; infinite for a distant light
};

LightSample sample_light(const Light& light, const Vec3& p) {
  if (light.type == LightType::kDistant)
    return {light.direction, light.irradiance, std::numeric_limits<double>::infinity()};
  const Vec3 to_light = light.position - p;
  const double d2 = length_squared(to_light);
  const double d = std::sqrt(d2);
  return {to_light / d, light.intensity / d2, d};
}

// What a camera ray sees: the surface point to shade and how to leave it.
struct SurfaceHit {
  SurfaceGeometry geometry;  // base surface (under the hit, for displacement)
  Vec3 shading_point;        // where light is evaluated and shadow rays start
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
    out->geometry = hit.geometry;
    out->shading_point = hit.geometry.p;
    return true;
  }
  // The origin lies on the analytic surface, so the root at t = 0 is skipped
  // by a relative epsilon rather than by moving the origin.
  bool occluded(const Vec3& origin, const Vec3& /*ns*/, const Vec3& wi, double distance) const {
    return penumbra::occluded(shape_, {origin, wi}, t_min_, distance);
  }

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
      : mesh_(mesh), amplitude_(scene.height.amplitude), height_(scene.height.function) {}

  bool primary(const Ray& ray, SurfaceHit* out) const {
    const auto hit = mesh_.intersect(ray);
    if (!hit) return false;
    out->geometry = hit->geometry;
    if (hit->geometry.displaceable)
      out->shading_point =
          displaced_point(hit->geometry, amplitude_, evaluate_height(height_, hit->geometry.p));
    else
      out->shading_point = hit->geometry.p;
    return true;
  }
  bool occluded(const Vec3& origin, const Vec3& ns, const Vec3& wi, double distance) const {
    const Vec3 lifted = origin + ns * mesh_.shadow_offset();
    return mesh_.occluded({lifted, wi}, distance);
  }

 private:
  const DisplacedMesh& mesh_;
  double amplitude_;
  const HeightFunction& height_;
};

struct PixelSums {
  double radiance = 0.0, hits = 0.0, theta = 0.0, deviation = 0.0, g = 0.0;
};

template <typename Tracer>
void render_image(const Scene& scene, const Tracer& tracer, const RenderOptions& options,
                  Image* image, RenderStats* stats) {
  const Camera& camera = scene.camera;
  const int width = camera.width, height = camera.height;
  const std::size_t channel_count = image->channels.size();
  int nx, ny;
  strata(camera.spp, &nx, &ny);
  const double inv_spp = 1.0 / camera.spp;
  const bool perspective = camera.projection == Projection::kPerspective;
  const Vec3 orthographic_direction = normalize(camera.direction);
  const bool displaced_shading = scene.representation != Representation::kSmooth;
  const bool is_ground_truth = scene.representation == Representation::kDisplacement;
  const double amplitude = scene.height.amplitude;
  const HeightFunction& height_function = scene.height.function;
  const TerminatorSettings& terminator = scene.terminator;

  std::atomic<int> rows_done{0};
  std::atomic<std::uint64_t> shadow_rays{0};
  std::mutex progress_mutex;
  auto last_report = Clock::now();

  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
    std::uint64_t local_shadow_rays = 0;
    for (int j = rows.begin(); j != rows.end(); ++j) {
      for (int i = 0; i < width; ++i) {
        const std::uint64_t pixel = std::uint64_t(j) * width + i;
        Pcg32 rng(mix64(camera.seed ^ mix64(pixel)));
        PixelSums sums;
        for (int sy = 0; sy < ny; ++sy) {
          for (int sx = 0; sx < nx; ++sx) {
            const double a = (sx + (camera.jitter ? rng.next_double() : 0.5)) / nx;
            const double b = (sy + (camera.jitter ? rng.next_double() : 0.5)) / ny;
            const double x0 = (i + a) / width - 0.5;
            const double y0 = 0.5 - (j + b) / height;
            Ray ray;
            if (perspective) {
              ray = {camera.position,
                     normalize(camera.direction + camera.right * x0 + camera.up * y0)};
            } else {
              ray = {camera.position + camera.right * x0 + camera.up * y0, orthographic_direction};
            }
            SurfaceHit hit;
            if (!tracer.primary(ray, &hit)) continue;
            const SurfaceGeometry& g = hit.geometry;
            const Vec3 wo = -ray.direction;
            Vec3 n = g.n;
            Vec3 ns = n;
            if (displaced_shading && g.displaceable && amplitude != 0.0)
              ns = displaced_normal(g, amplitude, evaluate_height(height_function, g.p));
            // Two-sided: the inside of an open cylinder is seen from inside.
            if (dot(n, wo) < 0.0) {
              n = -n;
              ns = -ns;
            }
            // On the displaced surface the true normal is Ns itself; on the
            // analytic base Ng and Ni coincide with the base normal.
            const Vec3 ng_ref = is_ground_truth ? ns : n;
            const LightSample light = sample_light(scene.light, hit.shading_point);
            const double factor = terminator_factor(terminator.method, {ng_ref, ns, light.wi, wo});
            sums.hits += 1.0;
            // Within 1.2e-6 degrees: below what the float channels resolve.
            sums.theta += degrees(acos_approx(dot(n, light.wi)));
            sums.deviation += degrees(acos_approx(dot(ns, n)));
            sums.g += factor;
            const double cos_theta_s = dot(ns, light.wi);
            if (!(cos_theta_s > 0.0) || light.irradiance == 0.0) continue;
            const LobeValues lobes = evaluate_lobes(scene.material, ns, light.wi, wo);
            const double f = lobes.diffuse * factor +
                             lobes.specular * (terminator.lobes == Lobes::kAll ? factor : 1.0);
            if (!(f > 0.0)) continue;
            ++local_shadow_rays;
            if (tracer.occluded(hit.shading_point, ns, light.wi, light.distance)) continue;
            sums.radiance += f * cos_theta_s * light.irradiance;
          }
        }
        float* out = &image->pixels[pixel * channel_count];
        const float radiance = static_cast<float>(sums.radiance * inv_spp);
        out[0] = out[1] = out[2] = radiance;
        out[3] = static_cast<float>(sums.hits * inv_spp);
        if (sums.hits > 0.0) {
          out[4] = static_cast<float>(sums.theta / sums.hits);
          out[5] = static_cast<float>(sums.deviation / sums.hits);
          out[6] = static_cast<float>(sums.g / sums.hits);
        }
      }
      const int done = ++rows_done;
      if (options.progress) {
        std::lock_guard<std::mutex> lock(progress_mutex);
        const auto now = Clock::now();
        if (done == height || now - last_report > std::chrono::milliseconds(250)) {
          last_report = now;
          options.progress(static_cast<double>(done) / height);
        }
      }
    }
    shadow_rays += local_shadow_rays;
  });
  if (stats) {
    stats->camera_samples = std::uint64_t(width) * height * camera.spp;
    stats->shadow_rays = shadow_rays;
  }
}

}  // namespace

Image render(const Scene& scene, const RenderOptions& options, RenderStats* stats) {
  const auto start = Clock::now();
  RenderStats local;
  Image image;
  image.width = scene.camera.width;
  image.height = scene.camera.height;
  image.channels = evaluator_channels();
  image.pixels.assign(std::size_t(image.width) * image.height * image.channels.size(), 0.0f);
  if (scene.representation == Representation::kDisplacement) {
    const DisplacedMesh mesh(scene);
    local.triangles = mesh.triangle_count();
    local.build_seconds = std::chrono::duration<double>(Clock::now() - start).count();
    render_image(scene, MeshTracer(scene, mesh), options, &image, &local);
  } else {
    render_image(scene, BaseTracer(scene), options, &image, &local);
  }
  local.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  if (stats) *stats = local;
  return image;
}

}  // namespace penumbra
