// The Blender exporter: the scene as a job for harness/blender_render.py and a
// mesh. In Blender's part of the cache key (code_digest.h).
#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <filesystem>

#include "core/mesh_surface.h"
#include "core/tessellation.h"
#include "image/image_io.h"
#include "renderers/external/blender/blender.h"
#include "renderers/external/external.h"
#include "scene/scene_json.h"

namespace penumbra {
namespace {

using nlohmann::json;

json to_json(const Vec3& v) {
  return json::array({v.x, v.y, v.z});
}

bool nearly(double a, double b) {
  return std::abs(a - b) <= 1e-9 * std::max(std::abs(a), std::abs(b));
}

// Blender's camera looks down its local -Z with +Y up and +X right; Cycles
// has no separate right/up lengths, so the camera must be orthonormal with
// square pixels.
json camera_json(const Camera& c) {
  const double lr = length(c.right), lu = length(c.up), ld = length(c.direction);
  const Vec3 x = to_blender(c.right / lr), y = to_blender(c.up / lu),
             z = to_blender(-c.direction / ld);
  if (std::abs(dot(c.right, c.up)) > 1e-9 * lr * lu ||
      std::abs(dot(c.right, c.direction)) > 1e-9 * lr * ld ||
      std::abs(dot(c.up, c.direction)) > 1e-9 * lu * ld)
    throw ExportError("Blender export needs camera right, up and direction mutually orthogonal");
  if (!nearly(lr / c.width, lu / c.height))
    throw ExportError(
        fmt::format("Blender export needs square pixels: |right|/width = {} but |up|/height = {}",
                    lr / c.width, lu / c.height));
  const Vec3 p = to_blender(c.position);
  json camera = {
      {"projection", name_of<Projection>(kProjectionNames, c.projection)},
      {"matrix_world",
       json::array({json::array({x.x, y.x, z.x, p.x}), json::array({x.y, y.y, z.y, p.y}),
                    json::array({x.z, y.z, z.z, p.z}), json::array({0.0, 0.0, 0.0, 1.0})})},
      {"width", c.width},
      {"height", c.height}};
  if (c.projection == Projection::kOrthographic) {
    // ortho_scale spans the larger image side (sensor fit AUTO).
    camera["ortho_scale"] = std::max(lr, lu);
  } else {
    // Horizontal field: tan(fov/2) = (|right|/2) / |direction|.
    constexpr double kSensor = 36.0;  // mm
    camera["sensor_width"] = kSensor;
    camera["lens"] = kSensor * ld / lr;
  }
  return camera;
}

}  // namespace

namespace {

// What Blender 3.4 Cycles cannot express; ExportError says why.
void check_blender_scene(const Scene& scene) {
  const TerminatorMethod method = scene.terminator.method.method;
  const RendererInfo& info = blender_entry().info;
  if (!offers(info, scene.representation, method))
    throw ExportError(fmt::format(
        "Blender Cycles 3.4 offers `none`, `chiang2019` and `cycles34` (bump only; both the "
        "Bump node) and `shading-offset`; "
        "`{}` is not available for the {} representation",
        method_info(method).id, to_string(scene.representation)));
  if (method == TerminatorMethod::kChiang2019 && scene.terminator.lobes != Lobes::kDiffuse)
    throw ExportError(
        "Cycles applies chiang2019 to diffuse lobes only: set /terminator/lobes to "
        "\"diffuse\"");
  const auto is_point = [](const Light& l) { return l.type == LightType::kPoint; };
  if (is_point(scene.light) ||
      std::any_of(scene.light.members.begin(), scene.light.members.end(), is_point))
    throw ExportError(
        "Blender export supports distant, sphere, quad and environment lights; a point light "
        "carries Blender's own power convention, which the evaluator does not model");
  if (scene.material.specular_weight > 0.0)
    throw ExportError("Blender export supports Lambertian materials only (specular_weight 0)");
  if (!scene.props.empty())
    throw ExportError("Blender export: props are evaluator-only (remove /props)");
  refuse_unoffered(scene, info, "Blender");
  // Cycles 3.4 applies its terminator term to any closure normal other than
  // the shading normal: a Normal Map node always gets it, and a normal map
  // cannot reach the Displacement socket that raw bump goes through.
  if (scene.height.normal_map() && scene.representation == Representation::kBump &&
      method != TerminatorMethod::kChiang2019 && method != TerminatorMethod::kCycles34)
    throw ExportError(fmt::format(
        "Blender export: a normal map shades through Cycles' Normal Map node, which always "
        "carries Cycles' terminator term: use chiang2019 or cycles34, not `{}`",
        method_info(method).id));
  // Cycles' object "Geometry Offset" is its only shadow-ray offset; 0 turns
  // it off, which is `none`.
  if (!offers(info, scene.offset.method))
    throw ExportError(fmt::format(
        "Blender Cycles 3.4 offers the shadow-ray offsets `none` and `cycles-geometry-offset`; "
        "`{}` is not available",
        offset_method_info(scene.offset.method).id));
  // The script builds one node group per term and refuses more (MAX_TERMS).
  if (scene.height.function.terms.size() > kBlenderMaxHeightTerms)
    throw ExportError(fmt::format(
        "Blender export: at most {} height terms (harness/blender_render.py builds a node group "
        "per term), the scene has {}; lower /height/terms",
        kBlenderMaxHeightTerms, scene.height.function.terms.size()));
}

BlenderShading blender_shading(const Scene& scene, bool has_height) {
  // Cycles would bump the flat triangle with h differenced over its own
  // plane; the evaluator rotates the analytic bumped normal onto Ni. Not the
  // same shading normal, so a low-poly bump render would not be comparable.
  if (scene.tessellation && scene.representation != Representation::kSmooth && has_height)
    throw ExportError(
        "Blender export: bump on a tessellated shape is evaluator-only (use the smooth "
        "representation, or no /shape/tessellation)");
  // A mesh shape's bump is not refused: the evaluator differentiates h
  // over the flat triangle and tilts Ni by it as Cycles' Bump node does
  // (facet_bump_gradient, core/mesh_surface.h), and a normal map is read in
  // the MikkTSpace frame Cycles' Normal Map node uses (core/surface_map.h).
  switch (scene.representation) {
    case Representation::kSmooth:
      return BlenderShading::kSmooth;
    case Representation::kBump:
      return !has_height ? BlenderShading::kSmooth
             : (scene.terminator.method.method == TerminatorMethod::kChiang2019 ||
                scene.terminator.method.method == TerminatorMethod::kCycles34)
                 ? BlenderShading::kBumpNode
                 : BlenderShading::kBumpDisplacement;
    case Representation::kDisplacement:
      return BlenderShading::kMesh;
  }
  return BlenderShading::kSmooth;
}

const char* mode_name(BlenderShading shading) {
  switch (shading) {
    case BlenderShading::kSmooth:
      return "smooth";
    case BlenderShading::kBumpDisplacement:
      return "bump-displacement";
    case BlenderShading::kBumpNode:
      return "bump-node";
    case BlenderShading::kMesh:
      return "mesh";
  }
  return "smooth";
}

// The mesh Blender loads, in Blender coordinates with outward winding.
TriangleMesh blender_mesh(const Scene& scene, bool displaced) {
  TriangleMesh mesh = external::scene_triangles(scene, displaced);
  // Swap y and z (a mirror), then restore outward winding: Cycles flips the
  // shading normal on back faces, so a reversed triangle would shade dark.
  for (std::size_t i = 0; i < mesh.positions.size(); i += 3) {
    std::swap(mesh.positions[i + 1], mesh.positions[i + 2]);
    std::swap(mesh.normals[i + 1], mesh.normals[i + 2]);
  }
  auto point = [&](unsigned v) {
    return Vec3{mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]};
  };
  auto normal = [&](unsigned v) {
    return Vec3{mesh.normals[3 * v], mesh.normals[3 * v + 1], mesh.normals[3 * v + 2]};
  };
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3) {
    unsigned* tri = &mesh.triangles[t];
    const Vec3 ng = cross(point(tri[1]) - point(tri[0]), point(tri[2]) - point(tri[0]));
    if (dot(ng, normal(tri[0]) + normal(tri[1]) + normal(tri[2])) < 0.0) std::swap(tri[1], tri[2]);
  }
  return mesh;
}

// The map's (u, v) times its tiling at every corner of the Blender mesh's
// triangles, unwrapped where a triangle straddles the u seam and, at a
// sphere's pole (where u is undefined), given the other corners' mean u.
std::vector<float> corner_uvs(const Scene& scene, const TriangleMesh& mesh) {
  const SurfaceMap& map = *scene.height.map;
  std::vector<float> uvs(mesh.triangles.size() * 2);
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3) {
    Vec3 corners[3];
    for (int k = 0; k < 3; ++k) {
      const float* q = &mesh.positions[3 * std::size_t(mesh.triangles[t + k])];
      corners[k] = to_blender(Vec3(q[0], q[1], q[2]));
    }
    double u[3], v[3];
    triangle_parameters(scene.shape, corners, u, v);
    for (int k = 0; k < 3; ++k) {
      uvs[2 * (t + k)] = float(u[k] * map.tiles_u);
      uvs[2 * (t + k) + 1] = float(v[k] * map.tiles_v);
    }
  }
  return uvs;
}

// A mesh shape's own UVs times the map's tiling at every corner of the
// Blender mesh's triangles: the same triangles in the same order, some
// rewound (blender_mesh), so each corner is found by its vertex.
std::vector<float> mesh_corner_uvs(const Scene& scene, const TriangleMesh& mesh) {
  const MeshSurface& surface = *scene.shape.mesh;
  const SurfaceMap& map = *scene.height.map;
  std::vector<float> uvs(mesh.triangles.size() * 2);
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3)
    for (std::size_t k = 0; k < 3; ++k) {
      std::size_t j = 0;
      while (j < 2 && surface.mesh.triangles[t + j] != mesh.triangles[t + k]) ++j;
      uvs[2 * (t + k)] = float(surface.uvs[2 * (t + j)] * map.tiles_u);
      uvs[2 * (t + k) + 1] = float(surface.uvs[2 * (t + j) + 1] * map.tiles_v);
    }
  return uvs;
}

// An environment's radiance as the grey image Blender's world reads, row 0
// the top (the zenith), as the evaluator reads its texels.
Image environment_image(const EnvironmentMap& map) {
  Image image;
  image.width = map.width(), image.height = map.height();
  image.channels = {"R", "G", "B"};
  image.pixels.resize(std::size_t(image.width) * image.height * 3);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      for (int c = 0; c < 3; ++c) image.at(x, y, c) = float(map.texel(x, y));
  return image;
}

// The map's texels as the image Blender loads (row 0 the top, as in the file).
Image map_image(const SurfaceMap& map) {
  Image image;
  image.width = map.width, image.height = map.height;
  image.channels = map.kind == MapKind::kHeight ? std::vector<std::string>{"Y"}
                                                : std::vector<std::string>{"R", "G", "B"};
  image.pixels = map.texels;
  return image;
}

// The light for harness/blender_render.py. Area lights become emissive
// meshes of the scene's radiance (an Emission shader's strength is the
// radiance the camera would see), one-sided, seen by shadow rays only:
// Cycles 3.4's own point light of a radius is a disk facing each shading
// point (kernel/light/point.h), not a sphere, and a mesh keeps the
// radiance exact. The quad's emitting normal is given, since the y <-> z
// swap to Blender's frame reverses the sense of the edges' cross product.
json light_json(const Light& light) {
  switch (light.type) {
    case LightType::kDistant:
      return {{"type", "sun"},
              {"direction", to_json(to_blender(normalize(light.direction)))},
              {"strength", light.irradiance}};
    case LightType::kSphere:
      return {{"type", "sphere"},
              {"center", to_json(to_blender(light.position))},
              {"radius", light.radius},
              {"radiance", light.radiance}};
    case LightType::kQuad: {
      const Vec3 c = light.corner, u = light.edge_u, v = light.edge_v;
      return {
          {"type", "quad"},
          {"vertices", json::array({to_json(to_blender(c)), to_json(to_blender(c + u)),
                                    to_json(to_blender(c + u + v)), to_json(to_blender(c + v))})},
          {"normal", to_json(to_blender(normalize(cross(u, v))))},
          {"radiance", light.radiance}};
    }
    case LightType::kEnvironment:
      return {{"type", "environment"},
              {"file", kBlenderEnvironmentFile},
              {"rotation_deg", light.rotation_deg},
              {"strength", light.scale}};
    case LightType::kGroup: {
      json lights = json::array();
      for (const Light& m : light.members) lights.push_back(light_json(m));
      return {{"type", "group"}, {"lights", lights}};
    }
    case LightType::kPoint:
      break;
  }
  throw ExportError("Blender export: a point light cannot be exported");
}

json job_json(const Scene& scene, const BlenderExport& out, bool has_height) {
  const HeightFunction& hf = scene.height.function;
  json terms = json::array();
  for (const SineTerm& t : hf.terms)
    terms.push_back({{"k", to_json(to_blender(t.k))}, {"phase", t.phase}, {"weight", t.weight}});
  const bool flat = scene.tessellation && scene.tessellation->shading == NormalShading::kFlat;
  const TerminatorMethod method = scene.terminator.method.method;
  return {
      {"format", "penumbra-blender-job"},
      {"version", 2},
      {"camera", camera_json(scene.camera)},
      {"render", {{"samples", scene.camera.spp}, {"seed", scene.camera.seed % 2147483647u}}},
      {"light", light_json(scene.light)},
      {"mesh",
       {{"positions", kBlenderPositionsFile},
        {"normals", kBlenderNormalsFile},
        {"triangles", kBlenderTrianglesFile},
        {"vertex_count", out.mesh.vertex_count()},
        {"triangle_count", out.mesh.triangle_count()},
        {"faces", flat ? "flat" : "smooth"}}},
      {"material", {{"albedo", scene.material.albedo}}},
      {"height",
       {{"amplitude", has_height ? scene.height.amplitude : 0.0},
        {"combine", name_of<HeightCombine>(kHeightCombineNames, hf.combine)},
        {"terms", terms}}},
      {"shading",
       {{"mode", mode_name(out.shading)},
        {"shading_offset",
         method == TerminatorMethod::kShadingOffset ? scene.terminator.method.shading_offset : 0.0},
        {"geometry_offset",
         scene.offset.method == OffsetMethod::kCyclesGeometryOffset ? scene.offset.cutoff : 0.0}}}};
}

}  // namespace

BlenderExport export_blender(const Scene& scene) {
  check_blender_scene(scene);
  const bool has_height = scene.height.normal_map() ||
                          (scene.height.amplitude > 0.0 &&
                           (scene.height.height_map() || !scene.height.function.terms.empty()));
  BlenderExport out;
  out.shading = blender_shading(scene, has_height);
  out.mesh = blender_mesh(scene, out.shading == BlenderShading::kMesh && has_height);
  json job = job_json(scene, out, has_height);
  if (scene.height.map && out.shading != BlenderShading::kMesh &&
      out.shading != BlenderShading::kSmooth) {
    out.uvs = scene.shape.type == ShapeType::kMesh ? mesh_corner_uvs(scene, out.mesh)
                                                   : corner_uvs(scene, out.mesh);
    out.map = map_image(*scene.height.map);
    job["mesh"]["uvs"] = kBlenderUvsFile;
    job["height"]["image"] = {
        {"file", kBlenderMapFile},
        {"kind", scene.height.normal_map() ? "normal" : "height"},
        {"extension", scene.height.map->edge == MapEdge::kWrap ? "REPEAT" : "EXTEND"}};
  }
  if (scene.light.environment) out.environment = environment_image(*scene.light.environment);
  for (const Light& m : scene.light.members)
    if (m.environment) out.environment = environment_image(*m.environment);
  out.job_json = job.dump(2) + "\n";
  return out;
}

void write_blender_files(const BlenderExport& job, const std::string& folder) {
  const std::filesystem::path dir(folder);
  const TriangleMesh& m = job.mesh;
  write_binary_file((dir / kBlenderPositionsFile).string(), m.positions.data(),
                    m.positions.size() * sizeof(float));
  write_binary_file((dir / kBlenderNormalsFile).string(), m.normals.data(),
                    m.normals.size() * sizeof(float));
  write_binary_file((dir / kBlenderTrianglesFile).string(), m.triangles.data(),
                    m.triangles.size() * sizeof(unsigned));
  if (!job.uvs.empty())
    write_binary_file((dir / kBlenderUvsFile).string(), job.uvs.data(),
                      job.uvs.size() * sizeof(float));
  if (!job.map.pixels.empty()) write_exr(job.map, (dir / kBlenderMapFile).string());
  if (!job.environment.pixels.empty())
    write_exr(job.environment, (dir / kBlenderEnvironmentFile).string());
  write_text_file((dir / kBlenderJobFile).string(), job.job_json);
}

}  // namespace penumbra
