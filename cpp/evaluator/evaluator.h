// The reference evaluator: direct light only, black background, real shadow
// rays. Deterministic for a given scene (seed included) whatever the thread
// count: every pixel draws from its own random stream and sums in a fixed order.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/factor_table.h"
#include "core/shading.h"
#include "image/image.h"
#include "scene/scene.h"

namespace penumbra {

// Channels of every evaluator render, in this order:
//   R, G, B      radiance (W m^-2 sr^-1), box-filtered over the pixel
//   A            coverage: fraction of the pixel's samples that hit the object
//   analysis.theta      degrees between the light and the base-surface normal at
//                       the base point (for displacement: the base point under
//                       the hit): the light's direction wi for a distant or
//                       point light, its light vector (scene.h, light_vector)
//                       for an area light or an environment, the same angle
//                       for a light that shrinks to a point
//   analysis.deviation  degrees between Ns and that base normal
//   analysis.G          the terminator factor at the sample (1 for `none`)
//   analysis.view       degrees between wo and the base-surface normal (the
//                       view angle: 90 at the silhouette)
// The analysis channels are means over the samples that hit (0 where none did).
// They live in the EXR layer "analysis" because "G" alone is the green channel.
const std::vector<std::string>& evaluator_channels();

struct RenderStats {
  std::uint64_t camera_samples = 0;
  std::uint64_t shadow_rays = 0;
  double seconds = 0.0;        // wall time, preparation included
  double build_seconds = 0.0;  // displacement and low-poly meshes: mesh + BVH build
  std::size_t triangles = 0;   // displacement and low-poly meshes: mesh size
  bool mesh_reused = false;    // displacement: the mesh came from this process's cache
  bool packets = false;        // camera rays were traced in SIMD packets (RenderOptions)
  int resumed_spp = 0;         // samples per pixel taken from RenderOptions::resume
};

// A render's per-pixel sums over its samples, in double precision, as it
// adds them before dividing: radiance, coverage, then the analysis
// channels' sums (theta, deviation, G with its count, view),
// kSampleSumChannels per pixel, row-major. What a render at 4^k times the
// samples extends instead of drawing these samples again (issue 45).
constexpr std::size_t kSampleSumChannels = 7;
struct SampleSums {
  int spp = 0, width = 0, height = 0;
  std::vector<double> values;
};

struct RenderOptions {
  // Called with the fraction done, at most a few times per second, from
  // whichever worker thread finished a row; must be thread-safe.
  std::function<void(double)> progress;
  // Displacement: take the mesh from this process's cache of recent meshes
  // (evaluator/displaced_mesh.h, shared_displaced_mesh) rather than build it.
  bool share_meshes = true;
  // Trace camera rays in SIMD packets where the packet path applies (an
  // analytic shape without props, image maps or filtering; core/ray_packet.h).
  // It gives the same bits as the scalar path, which false forces.
  bool packets = true;
  // Displacement truths (render, render_lightings): per image, the sums of
  // the same scene rendered with fewer samples, a nested prefix of the
  // camera's (core/sample_pattern.h, nests): the render draws only the
  // samples after them, and its images have the bits of renders from
  // scratch (tested). std::invalid_argument when they do not fit.
  const std::vector<SampleSums>* resume = nullptr;
  // Where to put each image's sums, for a later render to extend.
  std::vector<SampleSums>* sums = nullptr;
};

Image render(const Scene& scene, const RenderOptions& options = {}, RenderStats* stats = nullptr);

// Whether a method's render can share its samples with other methods' in
// render_methods: it draws no random numbers while shading (MethodInfo::
// draws_random; the draws come from the pixel's stream, in an order another
// such method's draws would change).
bool shares_samples(const TerminatorSettings& terminator);

// `scene` rendered with each of `methods` in place of scene.terminator, in
// one pass: image k has the bits that render() gives for methods[k]. Camera
// rays, hits, bump normals, the height field's visibility and shadow rays
// are traced once per sample for all of them, so a study's 20 methods of one
// variant cost a few renders rather than 20. std::invalid_argument when a
// method does not share its samples (shares_samples) or `methods` is empty.
// stats->shadow_rays counts each shared shadow ray once.
// A user method (`python`, core/user_method.h) renders apart from the
// built-in methods: one raw-bump pass, its samples recorded a block of
// rows at a time (their cosines and the light the factor scales), the
// user's function called once per block on this thread, and each pixel
// summed from them; std::invalid_argument for a user method on a
// displacement render or with a normal adjustment. The function's
// failures propagate as UserMethodError.
std::vector<Image> render_methods(const Scene& scene,
                                  const std::vector<TerminatorSettings>& methods,
                                  const RenderOptions& options = {}, RenderStats* stats = nullptr);

// Displacement truths of `scenes`, which must differ only in their light,
// material and terminator (the caller checks: renderers.h,
// render_evaluator_lightings), in
// one pass: image k has the bits render() gives for scenes[k]. The displaced
// mesh is built (or taken from the process's cache) once, and each camera
// ray and its hit are traced once for all of them; each scene's light
// sample, shading and shadow ray are its own (issue 45: the truths of a
// study's light directions and materials on one geometry).
// std::invalid_argument when `scenes` is empty, a scene is not a
// displacement render, or its method draws random numbers while shading.
std::vector<Image> render_lightings(const std::vector<Scene>& scenes,
                                    const RenderOptions& options = {},
                                    RenderStats* stats = nullptr);

// Raw bump rendered as render() renders it, to the bit, with its light
// tallied per pixel by the cell of `grid` each sample's angles fall in
// (core/factor_table.h, PixelTally): what any factor table on that grid
// would make of each pixel, for the achievable floor (analysis/
// achievable.h). Traces in packets where render() would (options.packets
// false forces the scalar path); both give the same image and tally to the
// bit. std::invalid_argument unless scene.terminator is `none` with no
// normal adjustment on a bump or smooth render.
//
// With `probes`, each of its families of factors is also tried on every
// sample as it is tallied (FactorProbe): what a factor method would render
// at each of its parameter values, without rendering it.
struct FactorProbe {
  Lobes lobes = Lobes::kDiffuse;  // the lobes the factor scales
  bool needs_visibility = false;  // reads ShadingPoint::visibility
  std::size_t values = 0;         // parameter values tried
  // The factor at one shading point for every value, into out[0, values).
  std::function<void(const ShadingPoint& point, double* out)> factors;
};
struct TallyProbes {
  std::vector<FactorProbe> probes;
  // The pixels (row-major) to try them on: empty, all of them. The others'
  // radiance under the probes is left 0 (a fit reads only its terminator's).
  std::vector<char> pixels;
  // Filled by render_tallied, per probe: each pixel's radiance with the
  // factor at each value (W m^-2 sr^-1), at [pixel * values + value]; as a
  // render of that factor method would give it, to rounding.
  std::vector<std::vector<double>> radiance;
};
Image render_tallied(const Scene& scene, const FactorGrid& grid, PixelTally* tally,
                     const RenderOptions& options = {}, RenderStats* stats = nullptr,
                     TallyProbes* probes = nullptr);

}  // namespace penumbra
