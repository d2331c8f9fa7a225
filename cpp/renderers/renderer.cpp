#include "renderers/renderer.h"

#include <algorithm>
#include <filesystem>

#include <fmt/format.h>

#include "core/grid_mesh.h"
#include "core/mesh_surface.h"
#include "core/surface_map.h"
#include "core/tessellation.h"
#include "image/image_io.h"
#include "util/strict_json.h"

namespace penumbra {

std::vector<TerminatorMethod> methods_offered(const RendererInfo& info,
                                              Representation representation) {
  if (!info.all_methods)
    return representation == Representation::kBump ? info.bump_methods : info.other_methods;
  std::vector<TerminatorMethod> all;
  for (const MethodInfo& m : all_methods()) all.push_back(m.method);
  return all;
}

std::vector<OffsetMethod> offsets_offered(const RendererInfo& info) {
  if (!info.all_offsets) return info.offsets;
  std::vector<OffsetMethod> all;
  for (const OffsetMethodInfo& m : all_offset_methods()) all.push_back(m.method);
  return all;
}

bool offers(const RendererInfo& info, Representation representation, TerminatorMethod method) {
  const auto list = methods_offered(info, representation);
  return std::find(list.begin(), list.end(), method) != list.end();
}

bool offers(const RendererInfo& info, OffsetMethod offset) {
  const auto list = offsets_offered(info);
  return std::find(list.begin(), list.end(), offset) != list.end();
}

std::string mesh_method_why_not(const RendererInfo& info, TerminatorMethod method,
                                ReferenceNormal reference) {
  const auto& ni = info.reference_ni_methods;
  if (reference == ReferenceNormal::kInterpolated ||
      std::find(ni.begin(), ni.end(), method) == ni.end())
    return "";
  return fmt::format(
      "{} takes the reference normal of `{}` as the interpolated normal Ni; on a mesh shape the "
      "evaluator's takes /terminator/reference_normal, \"Ng\" here (set it to \"Ni\" to "
      "compare them)",
      info.name, method_info(method).id);
}

void refuse_unoffered(const Scene& scene, const RendererInfo& info, const char* name) {
  if (scene.height.height_map() && !info.height_maps)
    throw ExportError(std::string(name) + " export: " + info.height_maps_why_not);
  if (scene.height.normal_map() && !info.normal_maps)
    throw ExportError(std::string(name) + " export: " + info.normal_maps_why_not);
  if (scene.shape.type == ShapeType::kPlane && !info.plane)
    throw ExportError(std::string(name) + " export: " + info.plane_why_not);
  if (scene.tessellation && scene.tessellation->shading == NormalShading::kConsistent &&
      !info.consistent_normals)
    throw ExportError(std::string(name) + " export: " + info.consistent_normals_why_not);
  const bool bumps_by_height = scene.representation == Representation::kBump &&
                               scene.height.amplitude > 0.0 &&
                               (scene.height.height_map() || !scene.height.function.terms.empty());
  if (scene.shape.type == ShapeType::kMesh && bumps_by_height && !info.mesh_bump)
    throw ExportError(std::string(name) + " export: " + info.mesh_bump_why_not);
  const bool bumps = bumps_by_height ||
                     (scene.representation == Representation::kBump && scene.height.normal_map());
  if (const std::string why = mesh_method_why_not(info, scene.terminator.method.method,
                                                  scene.terminator.reference_normal);
      scene.shape.type == ShapeType::kMesh && bumps && !why.empty())
    throw ExportError(std::string(name) + " export: " + why);
}

namespace {

// Bytes per pixel of an evaluator image (7 float channels) held while it is
// rendered, written as EXR and previewed: image, OpenImageIO's write buffer,
// the preview's copies.
constexpr double kBytesPerPixel = 7 * 4 * 4;
// Bytes per triangle of a mesh with its Embree BVH (measured: about 100).
constexpr double kBytesPerTriangle = 120.0;

// In the unit that shows the size: a small run's 80 KiB is not "0.00 GiB".
std::string gib(double bytes) {
  if (bytes >= kGiB) return fmt::format("{:.2f} GiB", bytes / kGiB);
  if (bytes >= 1024.0 * 1024.0) return fmt::format("{:.1f} MiB", bytes / (1024.0 * 1024.0));
  if (bytes >= 1024.0) return fmt::format("{:.1f} KiB", bytes / 1024.0);
  return fmt::format("{:.0f} bytes", bytes);
}

}  // namespace

ResourceEstimate estimate_render_resources(const Scene& scene, double extra_image_bytes,
                                           bool always_meshed) {
  ResourceEstimate e;
  const double pixels = double(scene.camera.width) * double(scene.camera.height);
  const double image_bytes = pixels * kBytesPerPixel + extra_image_bytes;
  double triangles = 0.0;
  std::string mesh_pointer;
  if (scene.shape.type == ShapeType::kMesh) {
    const TriangleMesh& base = scene.shape.mesh->mesh;
    const bool truth = scene.representation == Representation::kDisplacement;
    triangles =
        truth ? double(plan_subdivision(base, scene.displacement.edge_length).triangle_count())
              : double(base.triangle_count());
    mesh_pointer = truth ? "/displacement/edge_length" : "/shape/file";
  } else if (scene.tessellation) {
    triangles = double(tessellated_triangle_count(scene.shape, *scene.tessellation));
    mesh_pointer = "/shape/tessellation";
  } else if (scene.representation == Representation::kDisplacement || always_meshed) {
    const double reach =
        scene.height.amplitude *
        height_bounds(scene.height.function, scene.height.height_map(), scene.shape).max_abs;
    const GridResolution r = grid_resolution(scene.shape, scene.displacement.edge_length, reach);
    triangles = 2.0 * double(r.nu) * double(r.nv);
    mesh_pointer = "/displacement/edge_length";
  }
  const double mesh_bytes = triangles * kBytesPerTriangle;
  e.memory_bytes = image_bytes + mesh_bytes;
  e.triangles = triangles;
  // Every channel a cache entry can hold (the evaluator's 8 floats), plus a
  // header with the scene JSON and attributes: about 2 KiB measured on the
  // shipped scenes; 16 KiB leaves room for long scene files.
  e.output_bytes = pixels * double(evaluator_channels().size()) * 4 + 16384.0;
  e.pointer = mesh_bytes > image_bytes ? mesh_pointer : std::string("/camera/width");
  e.detail = fmt::format("{}x{} px: {}", scene.camera.width, scene.camera.height, gib(image_bytes));
  if (triangles > 0)
    e.detail += fmt::format(", {:.2f} M triangles: {}", triangles / 1e6, gib(mesh_bytes));
  return e;
}

void check_resources(const ResourceEstimate& estimate, double max_memory_bytes,
                     const std::string& origin, const std::string& output_folder) {
  if (estimate.memory_bytes > max_memory_bytes)
    throw InputError(
        origin, estimate.pointer,
        fmt::format("expected a render within --max-memory {:.3g} GiB, this one "
                    "needs about {} ({}); lower the resolution or raise the limit",
                    max_memory_bytes / kGiB, gib(estimate.memory_bytes), estimate.detail));
  if (output_folder.empty()) return;
  std::error_code ec;
  const std::filesystem::space_info space = std::filesystem::space(output_folder, ec);
  if (!ec && double(space.available) < estimate.output_bytes)
    throw OutputError(fmt::format(
        "{}: only {} free on its file system, and the output may need up to {}; free some "
        "space or write elsewhere",
        output_folder, gib(double(space.available)), gib(estimate.output_bytes)));
}

}  // namespace penumbra
