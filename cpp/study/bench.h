// The measurements behind `penumbra bench`: the evaluator's throughput on
// the bench scene of the evaluator issue (a bump cylinder with a grating,
// A = 0.01), per method and in the one pass a study renders a variant's
// methods in, and the CPU time of one render against an external renderer's.
#pragma once

#include <atomic>
#include <string>

#include <nlohmann/json.hpp>

#include "core/terminator.h"
#include "renderers/registry.h"

namespace penumbra {

// The bench scene, size x size pixels at `spp` samples per pixel.
nlohmann::json bench_scene(int size, int spp);

// One render (or pass) of the bench scene.
struct BenchTiming {
  std::string label;    // the method, or "N methods, one pass"
  bool packets = true;  // whether the evaluator traced packets (core/ray_packet.h)
  double wall_seconds = 0.0, cpu_seconds = 0.0;
  double msamples = 0.0;  // camera samples, millions, once per method
};

// One method's render, through the packets where they apply (`packets`) or
// the scalar path.
BenchTiming bench_method(const MethodInfo& method, int size, int spp, bool packets);

// Every method that shares its samples, rendered in one pass
// (render_methods), as a study renders the methods of a variant.
BenchTiming bench_shared_pass(int size, int spp, bool packets);

// The bench scene as a displaced mesh: its build and render.
struct DisplacementTiming {
  double edge_length = 0.0;
  std::size_t triangles = 0;
  double build_seconds = 0.0, seconds = 0.0;
  double msamples_per_second = 0.0;
  double peak_rss_mib = 0.0, peak_rss_mib_before = 0.0;
};
DisplacementTiming bench_displacement(int size, int spp);

// The bench scene's displacement truth under three light directions and
// two materials (Lambert, and GGX of weight 0.4): six renders, then the
// same six in one pass (render_lightings), the mesh from the process's
// cache in both.
struct SharedTruthTiming {
  std::size_t lightings = 0;
  double alone_seconds = 0.0, alone_cpu_seconds = 0.0;
  double pass_seconds = 0.0, pass_cpu_seconds = 0.0;
};
SharedTruthTiming bench_shared_truths(int size, int spp);

// The displacement truth at four times the bench's samples, as a study's
// convergence check renders it: from scratch, and extending the sums of
// the bench's samples (RenderOptions::resume; the same bits), CPU seconds
// with the mesh cached. `nested` false: 4 x spp does not nest spp
// (core/sample_pattern.h), and nothing was timed.
struct ExtendedTruthTiming {
  int spp = 0, extended_spp = 0;
  bool nested = false;
  double scratch_cpu_seconds = 0.0, extended_cpu_seconds = 0.0;
};
ExtendedTruthTiming bench_extended_truth(int size, int spp);

// A mesh file of about a million triangles, the unit sphere's 1024-segment
// UV tessellation written as binary PLY into `folder`: reading it
// (load_mesh_file: Assimp, welding, bounds) and a bump render of it under
// the bench scene's light and height (Embree's build, then the render).
struct MeshFileTiming {
  std::size_t triangles = 0;
  double file_mib = 0.0;
  double read_seconds = 0.0;
  double rss_mib_before = 0.0, rss_mib_read = 0.0;  // resident set before and after reading
  double build_seconds = 0.0, seconds = 0.0, msamples_per_second = 0.0;
  double peak_rss_mib = 0.0;  // the process's high-water mark after the render
};
MeshFileTiming bench_mesh_file(int size, int spp, const std::string& folder);

// One render of `document` as `penumbra render` makes it (render_with, then
// the EXR with the scene in its header) into `folder`: the CPU seconds it
// took, an external renderer's own processes included; an external renderer
// gets `threads` threads. Throws RenderCancelled once `interrupted` is set.
double render_cpu_seconds(RendererKind renderer, const nlohmann::json& document,
                          const std::string& folder, int threads,
                          const std::atomic<bool>& interrupted);

}  // namespace penumbra
