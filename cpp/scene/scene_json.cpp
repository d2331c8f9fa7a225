#include "scene/scene_json.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
#include <set>
#include <span>
#include <sstream>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "image/bump_maps.h"
#include "image/environment_file.h"
#include "scene/factor_table_file.h"
#include "scene/mesh_file.h"
#include "util/json_reader.h"

namespace penumbra {

using nlohmann::json;

namespace {

std::string describe(const json& j) {
  return describe_json(j, 60);
}

// Three finite numbers, each of magnitude at most `bound`.
Vec3 vec3(Reader& r, const std::string& key, double bound = kMaxCoordinate) {
  const json& v = r.at(key);
  if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
    r.fail(key, "expected an array of 3 numbers, got " + describe(v));
  const Vec3 out{v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
  if (!is_finite(out) || std::abs(out.x) > bound || std::abs(out.y) > bound ||
      std::abs(out.z) > bound)
    r.fail(key, fmt::format("expected 3 numbers in [-{0:g}, {0:g}] (scene units), got {1}", bound,
                            describe(v)));
  return out;
}

Vec3 vec3_or(Reader& r, const std::string& key, const Vec3& fallback) {
  return r.has(key) ? vec3(r, key) : fallback;
}

Vec3 check_direction(const Reader& r, const std::string& key, const Vec3& v) {
  const double largest = std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
  if (!(largest > 0.0))
    r.fail(key, fmt::format("expected a non-zero vector (a direction), got [{}, {}, {}]", v.x, v.y,
                            v.z));
  return normalize(v / largest);
}

// A direction divided by its largest component only (exact for the usual
// unit components; make_weave normalises it).
Vec3 scaled_direction(Reader& r, const std::string& key) {
  const Vec3 v = vec3(r, key, std::numeric_limits<double>::max());
  check_direction(r, key, v);
  return v / std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
}

// A direction: any non-zero finite vector, returned normalised (scaled by
// its largest component first, so that neither 1e200 nor 1e-200 over- or
// underflows the length).
Vec3 direction(Reader& r, const std::string& key) {
  return normalize(scaled_direction(r, key));
}

// "a, b, c": the ids of a registry table, for "unknown id" errors.
template <typename Table>
std::string id_list(const Table& table) {
  std::string ids;
  for (const auto& info : table) ids += (ids.empty() ? "" : ", ") + std::string(info.id);
  return ids;
}

bool non_negative(double x) {
  return x >= 0.0;
}
bool unit_interval(double x) {
  return x >= 0.0 && x <= 1.0;
}
bool length_scale(double x) {
  return x >= kMinLength && x <= kMaxCoordinate;
}
bool frequency_range(double x) {
  return x > 0.0 && x <= kMaxFrequency;
}
bool radiant_range(double x) {
  return x >= 0.0 && x <= kMaxRadiant;
}
bool phase_range(double x) {
  return std::abs(x) <= kMaxCoordinate;
}

Camera read_camera(Reader r) {
  Camera c;
  c.projection = r.choice<Projection>("projection", kProjectionNames, Projection::kOrthographic);
  c.position = vec3(r, "position");
  c.direction = vec3(r, "direction");  // keep the length: it is the focal length in perspective
  check_direction(r, "direction", c.direction);
  c.right = vec3(r, "right");
  check_direction(r, "right", c.right);
  c.up = vec3(r, "up");
  check_direction(r, "up", c.up);
  c.width = static_cast<int>(r.integer("width", 1, kMaxImageSize));
  c.height = static_cast<int>(r.integer("height", 1, kMaxImageSize));
  c.spp = static_cast<int>(r.integer_or("spp", 16, 1, 65536));
  c.seed = static_cast<std::uint64_t>(r.integer_or("seed", 0, 0, (1ll << 53)));
  c.jitter = r.boolean_or("jitter", true);
  r.finish();
  return c;
}

// An area light's radiance: "radiance" (W/(m^2 sr)) or "power" (W), one of
// the two; a power is spread over `emitting_area` (m^2) of a Lambertian
// emitter, whose exitance is pi L.
double read_radiance(Reader& r, double emitting_area) {
  const bool has_radiance = r.has("radiance"), has_power = r.has("power");
  if (has_radiance == has_power)
    r.fail("", has_radiance ? "expected one of \"radiance\" and \"power\", got both"
                            : "expected \"radiance\" (W/(m^2 sr)) or \"power\" (W)");
  if (has_radiance) return r.number("radiance", radiant_range, "in [0, 1e9] (W/(m^2 sr))");
  return r.number("power", radiant_range, "in [0, 1e9] (W)") / (kPi * emitting_area);
}

void read_quad(Reader& r, Light* l) {
  l->corner = vec3(r, "corner");
  l->edge_u = vec3(r, "edge_u");
  l->edge_v = vec3(r, "edge_v");
  const double eu = length(l->edge_u), ev = length(l->edge_v);
  if (!(eu >= kMinLength)) r.fail("edge_u", fmt::format("expected a length >= {:g}", kMinLength));
  if (!(ev >= kMinLength)) r.fail("edge_v", fmt::format("expected a length >= {:g}", kMinLength));
  // Parallel edges span no area: sin of their angle below 1e-6.
  if (!(length(cross(l->edge_u, l->edge_v)) > 1e-6 * eu * ev))
    r.fail("edge_v", "expected an edge not parallel to edge_u (the quad has no area)");
}

// Where "blender:PATH" points: PATH under the installed Blender's data
// folder (datafiles/), looked for where Debian's blender-data puts it and in
// versioned folders of other installs; PENUMBRA_BLENDER_DATAFILES first.
std::string blender_data_file(Reader& r, const std::string& key, const std::string& relative) {
  namespace fs = std::filesystem;
  std::vector<fs::path> folders;
  if (const char* env = std::getenv("PENUMBRA_BLENDER_DATAFILES")) folders.emplace_back(env);
  folders.emplace_back("/usr/share/blender/datafiles");
  std::error_code error;
  for (const auto& entry : fs::directory_iterator("/usr/share/blender", error))
    if (entry.is_directory(error)) folders.push_back(entry.path() / "datafiles");
  std::string tried;
  for (const fs::path& folder : folders) {
    if (fs::is_regular_file(folder / relative, error)) return (folder / relative).string();
    if (!tried.empty()) tried += ", ";
    tried += folder.string();
  }
  r.fail(key, fmt::format("\"{}{}\" names a file of Blender's data folder, not found under {} "
                          "(install Debian's blender-data, or set PENUMBRA_BLENDER_DATAFILES)",
                          kBlenderDataPrefix, relative, tried));
}

void read_environment(Reader& r, Light* l) {
  std::string file = r.string("map");
  if (file.empty()) r.fail("map", "expected the path of an OpenEXR or HDR file, got \"\"");
  if (file.starts_with(kBlenderDataPrefix))
    file = blender_data_file(r, "map", file.substr(std::string_view(kBlenderDataPrefix).size()));
  l->rotation_deg = r.number_or(
      "rotation_deg", 0.0, [](double x) { return std::abs(x) <= 360.0; },
      "in [-360, 360] (degrees about the up axis)");
  l->scale = r.number_or("scale", 1.0, radiant_range, "in [0, 1e9] (times the map's values)");
  try {
    const LoadedEnvironment loaded = load_environment_map(file, radians(l->rotation_deg));
    l->environment = loaded.map;
    l->map_digest = loaded.digest;
  } catch (const InputError& e) {
    r.fail("map", e.what());
  }
}

Light read_light(Reader r);

// A group's lights: 2 to 8, none a group, at most one environment (a
// renderer's world holds one) and an environment beside delta lights only.
// Lights do not shadow one another in the evaluator; in Cycles a sphere or
// quad is a mesh that its BSDF rays stop at, which hides the environment
// behind it (a quad beside Blender's forest: 0.7 % darker than the sum of
// their renders at 1,024 samples, 13 standard errors).
void read_group(Reader& r, Light* l) {
  const json& list = r.at("lights");
  if (!list.is_array() || list.size() < 2 || list.size() > 8)
    r.fail("lights", "expected an array of 2 to 8 lights, got " + Reader::describe(list));
  int environments = 0, areas = 0;
  for (std::size_t i = 0; i < list.size(); ++i) {
    Reader item = r.item("lights", i);
    // By the type's name, before a map is read.
    const json* name = list[i].is_object() && list[i].contains("type") ? &list[i]["type"] : nullptr;
    const std::string type = name && name->is_string() ? name->get<std::string>() : "";
    if (type == "group")
      item.fail("type", "expected a light that is not a group (groups do not nest)");
    environments += type == "environment";
    areas += type == "sphere" || type == "quad";
    if (environments > 1) item.fail("type", "expected at most one environment in a group");
    if (environments > 0 && areas > 0)
      item.fail("type",
                "expected an environment beside distant and point lights only: a sphere or quad "
                "light would hide the environment behind it in Cycles, which the evaluator does "
                "not model");
    l->members.push_back(read_light(item));
  }
}

Light read_light(Reader r) {
  Light l;
  l.type = r.choice<LightType>("type", kLightTypeNames);
  switch (l.type) {
    case LightType::kGroup:
      read_group(r, &l);
      break;
    case LightType::kDistant:
      l.direction = direction(r, "direction");
      l.irradiance = r.number("irradiance", radiant_range, "in [0, 1e9] (W/m^2)");
      break;
    case LightType::kPoint:
      l.position = vec3(r, "position");
      l.intensity = r.number("intensity", radiant_range, "in [0, 1e9] (W/sr)");
      break;
    case LightType::kSphere:
      l.position = vec3(r, "position");
      l.radius = r.number("radius", length_scale, "in [1e-6, 1e6] (scene units)");
      l.radiance = read_radiance(r, 4.0 * kPi * l.radius * l.radius);
      break;
    case LightType::kQuad:
      read_quad(r, &l);
      l.radiance = read_radiance(r, length(cross(l.edge_u, l.edge_v)));
      break;
    case LightType::kEnvironment:
      read_environment(r, &l);
      break;
  }
  if (is_area_light(l) && l.type != LightType::kGroup)
    l.sampling = r.choice<LightSampling>("sampling", kLightSamplingNames, l.sampling);
  r.finish();
  return l;
}

Tessellation read_tessellation(Reader r, const Shape& shape) {
  if (shape.type == ShapeType::kPlane)
    r.fail("",
           "expected null for a plane (a plane is its own flat mesh: there is no smooth "
           "surface for a tessellation to approximate)");
  Tessellation t;
  t.scheme =
      r.choice<TessellationScheme>("scheme", kTessellationSchemeNames, TessellationScheme::kUv);
  if (t.scheme == TessellationScheme::kUv) {
    t.segments = static_cast<unsigned>(r.integer_or("segments", t.segments, 3, 65536));
    const long long min_rings = shape.type == ShapeType::kSphere ? 2 : 1;
    t.rings = r.has("rings") ? static_cast<unsigned>(r.integer("rings", min_rings, 65536)) : 0;
  } else {
    if (shape.type != ShapeType::kSphere)
      r.fail("scheme", "expected \"uv\" for a cylinder (\"icosphere\" tessellates spheres only)");
    t.frequency = static_cast<unsigned>(r.integer_or("frequency", t.frequency, 1, 2048));
  }
  t.shading = r.choice<NormalShading>("shading", kNormalShadingNames, NormalShading::kSmooth);
  t.phong_level = static_cast<unsigned>(r.integer_or("phong_level", t.phong_level, 1, 64));
  t.phong_alpha = r.number_or(
      "phong_alpha", t.phong_alpha, [](double x) { return x >= 0.0 && x <= 1.0; },
      "in [0, 1] (Phong tessellation's shape factor)");
  r.finish();
  return t;
}

OffsetSettings read_offset(Reader r) {
  OffsetSettings o;
  const std::string id = r.string("method");
  const auto method = offset_method_from_id(id);
  if (!method) {
    const std::string ids = id_list(all_offset_methods());
    r.fail("method", fmt::format("unknown offset method \"{}\" (valid: {})", id, ids));
  }
  o.method = *method;
  // Only the chosen method's parameters are keys here; any other is an error.
  for (const MethodParameter& parameter : offset_method_info(o.method).parameters) {
    const double value = r.number_or(
        std::string(parameter.name), parameter.default_value,
        [&](double x) { return x >= parameter.min_value && x <= parameter.max_value; },
        fmt::format("in [{}, {}] ({})", parameter.min_value, parameter.max_value, parameter.unit)
            .c_str());
    if (double* field = offset_parameter(&o)) *field = value;
  }
  r.finish();
  return o;
}

// /shape of type "mesh": its file (a relative path made relative to the
// scene file by resolve_map_files), the node to take, transform and normals.
Shape read_mesh_shape(Reader& r) {
  Shape s;
  s.type = ShapeType::kMesh;
  const std::string file = r.string("file");
  if (file.empty()) r.fail("file", "expected the path of a mesh file, got \"\"");
  if (r.has("tessellation"))
    r.fail("tessellation",
           "expected no tessellation on a mesh (it is triangles already: its vertex normals "
           "shade it smooth, and the offset methods act on its triangles)");
  MeshTransform t;
  t.scale = r.number_or("scale", 1.0, length_scale, "in [1e-6, 1e6] (uniform scale)");
  t.rotate_deg = vec3_or(r, "rotate_deg", {0, 0, 0});
  t.translate = vec3_or(r, "translate", {0, 0, 0});
  const MeshNormals normals =
      r.choice<MeshNormals>("normals", kMeshNormalsNames, MeshNormals::kFile);
  const std::string node = r.has("node") ? r.string("node") : std::string();
  if (r.has("node") && node.empty())
    r.fail("node", "expected the name of a node in the mesh file, got \"\"");
  LoadedMesh loaded;
  try {
    loaded = load_mesh_file(file, t, normals, node);
  } catch (const MeshNodeError& e) {
    r.fail("node", fmt::format("{}: {}", file, e.what()));
  } catch (const MeshFileError& e) {
    r.fail("file", fmt::format("{}: {}", file, e.what()));
  }
  s.mesh = loaded.surface;
  s.center = mesh_centre(*s.mesh);
  s.radius = mesh_radius(*s.mesh);
  if (!length_scale(s.radius))
    r.fail("file", fmt::format("{}: expected a mesh of size in [1e-6, 1e6] scene units, got a "
                               "bounding sphere of radius {}",
                               file, s.radius));
  r.finish();
  return with_frame(s);
}

Shape read_shape(Reader r, std::optional<Tessellation>* tessellation = nullptr) {
  Shape s;
  s.type = r.choice<ShapeType>("type", kShapeTypeNames);
  if (s.type == ShapeType::kMesh) {
    if (!tessellation) r.fail("type", "expected \"sphere\" (props are spheres)");
    return read_mesh_shape(r);
  }
  s.center = vec3_or(r, "center", {0, 0, 0});
  s.axis = r.has("axis") ? direction(r, "axis") : Vec3{0, 1, 0};
  if (s.type == ShapeType::kPlane) {
    s.width = r.number("width", length_scale, "in [1e-6, 1e6] (scene units)");
    s.height = r.number("height", length_scale, "in [1e-6, 1e6] (scene units)");
    s.radius = 0.5 * std::max(s.width, s.height);
  } else {
    s.radius = r.number("radius", length_scale, "in [1e-6, 1e6] (scene units)");
  }
  if (s.type == ShapeType::kCylinder) {
    s.height = r.number("height", length_scale, "in [1e-6, 1e6] (scene units)");
    s.caps = r.boolean_or("caps", false);
  }
  s = with_frame(s);
  if (tessellation && r.has("tessellation") && !r.at("tessellation").is_null())
    *tessellation = read_tessellation(r.object("tessellation"), s);
  r.finish();
  return s;
}

Material read_material(Reader r) {
  Material m;
  m.albedo = r.number_or("albedo", m.albedo, unit_interval, "in [0, 1]");
  if (r.has("specular")) {
    Reader s = r.object("specular");
    m.specular_weight = s.number("weight", unit_interval, "in [0, 1]");
    m.specular_roughness = s.number_or(
        "roughness", m.specular_roughness, [](double x) { return x > 0.0 && x <= 1.0; },
        "in (0, 1] (GGX alpha)");
    s.finish();
  }
  r.finish();
  return m;
}

// The image a map reads: /height/file, or for a normal map on a mesh
// without one, the normal texture the mesh file's materials name.
std::string map_file(Reader& r, MapKind kind, const Shape& shape) {
  if (kind == MapKind::kNormal && shape.type == ShapeType::kMesh && !r.has("file")) {
    if (shape.mesh->normal_texture.empty())
      r.fail("file", fmt::format("expected the path of an image file: the mesh {} has no normal "
                                 "texture of its own to read ({})",
                                 shape.mesh->file, shape.mesh->normal_texture_why_not));
    return shape.mesh->normal_texture;
  }
  const std::string file = r.string("file");
  if (file.empty()) r.fail("file", "expected the path of an image file, got \"\"");
  return file;
}

// /height/file and its placement. A relative path is taken from the working
// directory here; load_scene and studies make it relative to the scene file
// first, after every override (resolve_map_files).
void read_map(Reader& r, HeightSpec* h, const Shape& shape) {
  const MapKind kind = h->family == HeightFamily::kHeightMap ? MapKind::kHeight : MapKind::kNormal;
  const std::string file = map_file(r, kind, shape);
  const std::string channel =
      kind == MapKind::kHeight && r.has("channel") ? r.string("channel") : "";
  std::shared_ptr<const SurfaceMap> loaded;
  try {
    loaded = load_surface_map(file, kind, channel);
  } catch (const InputError& e) {
    r.fail("file", e.what());
  }
  SurfaceMap map = *loaded;
  if (r.has("tiles")) {
    const json& t = r.at("tiles");
    const auto valid = [](const json& x) {
      return x.is_number() && std::isfinite(x.get<double>()) && x.get<double>() > 0.0 &&
             x.get<double>() <= 1e6;
    };
    if (!t.is_array() || t.size() != 2 || !valid(t[0]) || !valid(t[1]))
      r.fail("tiles",
             "expected [tiles_u, tiles_v], two numbers in (0, 1e6] (repeats of the map "
             "over the shape's u and v), got " +
                 describe(t));
    map.tiles_u = t[0].get<double>();
    map.tiles_v = t[1].get<double>();
  }
  map.edge = r.choice<MapEdge>("edge", kMapEdgeNames, MapEdge::kWrap);
  h->map = std::make_shared<const SurfaceMap>(std::move(map));
}

// /height/filter: a roughness filter id, its parameters and an optional
// fixed pyramid level.
struct FilterChoice {
  FilterSettings settings;
  double level = -1.0;
};

FilterChoice read_filter(Reader r) {
  FilterChoice c;
  const std::string id = r.string("method");
  const auto filter = roughness_filter_from_id(id);
  if (!filter) {
    const std::string ids = id_list(all_roughness_filters());
    r.fail("method", fmt::format("unknown roughness filter \"{}\" (valid: {})", id, ids));
  }
  const RoughnessFilterInfo& info = roughness_filter_info(*filter);
  if (info.distribution == FilteredDistribution::kSchillingBlinnPhong)
    r.fail("method", fmt::format("\"{}\" shades with Schilling's modified Blinn-Phong, which has "
                                 "no normalised form to render with (penumbra filtering compares "
                                 "it instead)",
                                 id));
  c.settings.filter = *filter;
  if (r.has("parameters")) {
    Reader p = r.object("parameters");
    for (const FilterParameter& parameter : info.parameters) {
      const std::string name(parameter.name);
      const double value = p.number_or(
          name, parameter.default_value,
          [&](double x) { return x >= parameter.min_value && x <= parameter.max_value; },
          fmt::format("in [{}, {}] ({})", parameter.min_value, parameter.max_value, parameter.unit)
              .c_str());
      if (name == "gain") c.settings.gain = value;
      if (name == "kernel_variance") c.settings.kernel_variance = value;
      if (name == "kernel_clamp") c.settings.kernel_clamp = value;
    }
    p.finish();
  }
  if (r.has("level"))
    c.level = r.number(
        "level", [](double x) { return x >= 0.0 && x <= 24.0; },
        "in [0, 24] (pyramid level: footprints of 2^level texels; absent: from the footprint)");
  r.finish();
  return c;
}

// An image map on a mesh shape is laid over the file's UVs: a mesh without
// them is refused, and so is a filter (its footprints assume an analytic
// shape's parameterisation).
void check_map_on_mesh(Reader& r, const Shape& shape) {
  if (shape.type != ShapeType::kMesh) return;
  if (!shape.mesh->has_uvs())
    r.fail("type", fmt::format("expected an analytic family (grating, weave, noise) on the mesh "
                               "{}: it has no texture coordinates, so an image map has nothing "
                               "to be laid over",
                               shape.mesh->file));
  if (r.has("filter"))
    r.fail("filter",
           "expected no filter on a mesh shape (filtered maps and pyramids follow an analytic "
           "shape's parameterisation, not a mesh's UVs)");
}

HeightSpec read_height(Reader r, const Shape& shape) {
  HeightSpec h;
  h.family = r.choice<HeightFamily>("type", kHeightFamilyNames);
  if (h.family == HeightFamily::kNone) {
    r.finish();
    return h;
  }
  const bool image = h.family == HeightFamily::kHeightMap || h.family == HeightFamily::kNormalMap;
  if (image) check_map_on_mesh(r, shape);
  if (image) read_map(r, &h, shape);
  std::optional<FilterChoice> filter;
  if (image && r.has("filter")) filter = read_filter(r.object("filter"));
  if (h.family == HeightFamily::kNormalMap) {
    r.finish();
    if (filter)
      h.filtered = std::make_shared<const FilteredMap>(
          make_filtered_map(*h.map, 0.0, shape, filter->settings, filter->level));
    return h;
  }
  h.amplitude = r.number("amplitude", non_negative, ">= 0 (scene units)");
  switch (h.family) {
    case HeightFamily::kGrating: {
      const double frequency =
          r.number("frequency", frequency_range, "in (0, 1e6] (cycles per scene unit)");
      const Vec3 dir = direction(r, "direction");
      const double phase = r.number_or("phase", 0.0, phase_range, "in [-1e6, 1e6] (radians)");
      h.function = make_grating(dir, frequency, phase);
      break;
    }
    case HeightFamily::kWeave: {
      const double frequency =
          r.number("frequency", frequency_range, "in (0, 1e6] (cycles per scene unit)");
      const json& list = r.at("directions");
      if (!list.is_array() || list.size() < 2 || list.size() > kMaxProductFactors)
        r.fail("directions", fmt::format("expected an array of 2 to {} directions, got {}",
                                         kMaxProductFactors, describe(list)));
      std::vector<Vec3> directions;
      for (std::size_t i = 0; i < list.size(); ++i) {
        const json wrapper{{"d", list[i]}};
        Reader item(wrapper, r.child_pointer("directions") + "/" + std::to_string(i), r.origin());
        directions.push_back(scaled_direction(item, "d"));
      }
      const HeightCombine combine =
          r.choice<HeightCombine>("combine", kHeightCombineNames, HeightCombine::kProduct);
      h.function = make_weave(directions, frequency, combine);
      break;
    }
    case HeightFamily::kNoise: {
      const int terms = static_cast<int>(r.integer("terms", 1, 256));
      const double f_min =
          r.number("frequency_min", frequency_range, "in (0, 1e6] (cycles per scene unit)");
      const double f_max =
          r.number("frequency_max", frequency_range, "in (0, 1e6] (cycles per scene unit)");
      if (f_max < f_min)
        r.fail("frequency_max",
               fmt::format("expected a number >= frequency_min ({}), got {}", f_min, f_max));
      const auto seed = static_cast<std::uint64_t>(r.integer_or("seed", 0, 0, (1ll << 53)));
      h.function = make_noise(terms, f_min, f_max, seed);
      break;
    }
    case HeightFamily::kNone:
    case HeightFamily::kHeightMap:
    case HeightFamily::kNormalMap:
      break;
  }
  r.finish();
  // The displaced surface must not reach the axis (cylinder) or the centre
  // (sphere): past that the displacement folds the surface through itself.
  const double max_h = height_bounds(h.function, h.height_map(), shape).max_abs;
  const double reach = h.amplitude * max_h;
  if (reach >= shape.radius)
    r.fail("amplitude", fmt::format("expected amplitude * max|h| < radius ({} scene units), got "
                                    "{} * {} = {}",
                                    shape.radius, h.amplitude, max_h, reach));
  if (filter)
    h.filtered = std::make_shared<const FilteredMap>(
        make_filtered_map(*h.map, h.amplitude, shape, filter->settings, filter->level));
  return h;
}

// /terminator/parameters/table: a path, relative ones already made relative
// to the scene file (resolve_map_files).
std::shared_ptr<const FactorTable> read_table_file(Reader& p) {
  const std::string file = p.string("table");
  if (file.empty()) p.fail("table", "expected the path of a table.json, got \"\"");
  try {
    return load_factor_table(file);
  } catch (const InputError& e) {
    p.fail("table", e.what());
  }
}

// /terminator/parameters of a user method: each of its parameters, its
// default where absent, and no other key.
void read_user_parameters(Reader& r, MethodSettings* method) {
  const UserMethod& user = *method->user;
  method->user_values.clear();
  std::optional<Reader> p;
  if (r.has("parameters")) p.emplace(r.object("parameters"));
  for (const UserParameter& parameter : user.parameters) {
    if (!p) {
      method->user_values.push_back(parameter.default_value);
      continue;
    }
    method->user_values.push_back(p->number_or(
        parameter.name, parameter.default_value,
        [&](double x) { return x >= parameter.min_value && x <= parameter.max_value; },
        fmt::format("in [{}, {}] ({})", parameter.min_value, parameter.max_value,
                    parameter.description)
            .c_str()));
  }
  if (p) p->finish();
}

TerminatorSettings read_terminator(Reader r) {
  TerminatorSettings t;
  if (r.has("method")) {
    const std::string id = r.string("method");
    const auto method = method_from_id(id);
    if (!method) {
      const std::string ids = id_list(all_methods());
      r.fail("method", fmt::format("unknown method \"{}\" (valid: {}, or a user method "
                                   "registered with @penumbra.method: docs/python.md)",
                                   id, ids));
    }
    t.method.method = *method;
    if (*method == TerminatorMethod::kPython) {
      t.method.user = find_user_method(id);
      if (!t.method.user) {
        const std::vector<std::string> users = user_method_ids();
        r.fail("method",
               fmt::format("\"python\" stands for the user methods: name one by the id it was "
                           "registered under with @penumbra.method ({}; docs/python.md)",
                           users.empty() ? "none is registered in this process"
                                         : fmt::format("registered: {}", fmt::join(users, ", "))));
      }
    }
  }
  const MethodInfo& info = method_info(t.method.method);
  if (t.method.user) read_user_parameters(r, &t.method);
  if (info.needs_table && !r.has("parameters"))
    r.fail("parameters", fmt::format("method \"{}\" needs {{\"table\": FILE}}, the table.json "
                                     "that penumbra fit writes",
                                     info.id));
  if (r.has("parameters") && !t.method.user) {
    Reader p = r.object("parameters");
    if (info.needs_table) t.method.table = read_table_file(p);
    for (const MethodParameter& parameter : info.parameters) {
      const std::string name(parameter.name);
      const double value = p.number_or(
          name, parameter.default_value,
          [&](double x) { return x >= parameter.min_value && x <= parameter.max_value; },
          fmt::format("in [{}, {}]", parameter.min_value, parameter.max_value).c_str());
      if (t.method.method == TerminatorMethod::kShadingOffset) t.method.shading_offset = value;
    }
    p.finish();
  }
  if (r.has("normal_adjustment")) {
    const std::string id = r.string("normal_adjustment");
    const auto adjustment = normal_adjustment_from_id(id);
    if (!adjustment) {
      const std::string ids = id_list(all_normal_adjustments());
      r.fail("normal_adjustment",
             fmt::format("unknown normal adjustment \"{}\" (valid: {})", id, ids));
    }
    if (*adjustment != NormalAdjustment::kNone && t.method.user)
      r.fail("normal_adjustment",
             fmt::format("user method \"{}\" is a plain factor: it takes no normal adjustment",
                         t.method.user->id));
    if (*adjustment != NormalAdjustment::kNone && info.adjustment != NormalAdjustment::kNone)
      r.fail("normal_adjustment",
             fmt::format("method \"{}\" already applies the normal adjustment \"{}\"; a scene "
                         "combines at most one adjustment with one factor",
                         info.id, normal_adjustment_info(info.adjustment).id));
    t.normal_adjustment = *adjustment;
  }
  t.reference_normal = r.choice<ReferenceNormal>("reference_normal", kReferenceNormalNames,
                                                 ReferenceNormal::kGeometric);
  t.lobes = r.choice<Lobes>("lobes", kLobesNames, Lobes::kDiffuse);
  r.finish();
  return t;
}

// The ground-truth tessellation is capped so that a typo cannot ask for more
// memory than the machine has (about 100 bytes per triangle with the BVH).
constexpr double kMaxDisplacementTriangles = 4.0e7;

double estimated_triangles(const Shape& shape, double reach, double edge) {
  if (shape.type == ShapeType::kMesh)
    return double(plan_subdivision(shape.mesh->mesh, edge).triangle_count());
  const double r = shape.radius + reach;
  if (shape.type == ShapeType::kPlane)
    return 2.0 * std::ceil(shape.width / edge) * std::ceil(shape.height / edge);
  if (shape.type == ShapeType::kSphere)
    return 2.0 * std::ceil(2.0 * kPi * r / edge) * std::ceil(kPi * r / edge);
  return 2.0 * std::ceil(2.0 * kPi * r / edge) * std::ceil(shape.height / edge);
}

// What image maps cannot do yet, or cannot do at all.
void check_maps(const Scene& s, const std::string& origin) {
  if (!s.height.map) return;
  if (s.height.normal_map() && s.representation == Representation::kDisplacement)
    throw InputError(origin, "/representation",
                     "expected \"bump\" or \"smooth\" with a normal map (a normal map has no "
                     "heights, so no displaced surface; use a height map for a ground truth)");
  if (s.representation != Representation::kSmooth &&
      method_info(s.terminator.method.method).needs_visibility)
    throw InputError(origin, "/terminator/method",
                     fmt::format("\"{}\" searches the analytic height function for its "
                                 "horizons, which an image map does not have yet",
                                 method_info(s.terminator.method.method).id));
}

}  // namespace

TerminatorSettings terminator_from_json(const json& j, const std::string& origin) {
  return read_terminator(Reader(j, "/terminator", origin));
}

Material material_from_json(const json& j, const std::string& origin) {
  return read_material(Reader(j, "/material", origin));
}

OffsetSettings offset_from_json(const json& j, const std::string& origin) {
  return read_offset(Reader(j, "/offset", origin));
}

void resolve_map_files(json& document, const std::string& scene_path) {
  for (const char* pointer :
       {"/height/file", "/terminator/parameters/table", "/light/map", "/shape/file"}) {
    const json::json_pointer file(pointer);
    if (!document.is_object() || !document.contains(file) || !document[file].is_string()) continue;
    const std::string text = document[file].get<std::string>();
    if (text.starts_with(kBlenderDataPrefix)) continue;  // resolved when read
    const std::filesystem::path path(text);
    if (path.empty() || path.is_absolute()) continue;
    // A bare file name has no parent: its folder is the working directory.
    const std::filesystem::path folder = std::filesystem::path(scene_path).parent_path();
    const std::filesystem::path base =
        folder.empty() ? std::filesystem::current_path() : std::filesystem::absolute(folder);
    document[file] = (base / path).lexically_normal().string();
  }
}

Override parse_override(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || text.empty() || text[0] != '/')
    throw InputError("--set", text, "expected /json/pointer=VALUE");
  Override o;
  o.pointer = text.substr(0, eq);
  const std::string value = text.substr(eq + 1);
  try {
    if (pointer_tokens(o.pointer).size() > static_cast<std::size_t>(kMaxJsonDepth))
      throw InputError("--set", o.pointer,
                       fmt::format("expected a pointer of at most {} keys", kMaxJsonDepth));
  } catch (const std::invalid_argument& e) {
    throw InputError("--set", o.pointer, std::string("expected a JSON pointer: ") + e.what());
  }
  if (!is_utf8(text)) throw InputError("--set", o.pointer, "expected UTF-8 text");
  const std::optional<json> parsed = parse_json_value_or_word(value, "--set", o.pointer);
  o.value = parsed ? *parsed : json(value);  // a bare word is a string
  return o;
}

namespace {

// The array element `token` names: an index up to the size (the size, or
// "-", appends). Anything past the end is an error rather than a resize, so
// that /x/100000000 cannot allocate gigabytes.
json& array_element(json& array, const std::string& token, const std::string& origin,
                    const std::string& pointer) {
  if (token == "-") return array.emplace_back(nullptr);
  const bool digits =
      !token.empty() && token.size() <= 9 &&
      std::all_of(token.begin(), token.end(), [](char c) { return c >= '0' && c <= '9'; });
  if (!digits || (token.size() > 1 && token[0] == '0'))
    throw InputError(origin, pointer,
                     fmt::format("cannot apply --set: \"{}\" is not an array index", token));
  const std::size_t index = std::stoul(token);
  if (index > array.size())
    throw InputError(origin, pointer,
                     fmt::format("cannot apply --set: index {} is past the end of an array of {} "
                                 "(use {} or - to append)",
                                 index, array.size(), array.size()));
  if (index == array.size()) return array.emplace_back(nullptr);
  return array[index];
}

}  // namespace

void apply_overrides(json& document, const std::vector<Override>& overrides,
                     const std::string& origin) {
  // Missing intermediate objects are created: a misspelt key is still
  // caught, with its pointer, by the strict reader's unknown-key check.
  for (const Override& o : overrides) {
    std::vector<std::string> tokens;
    try {
      tokens = pointer_tokens(o.pointer);
    } catch (const std::invalid_argument& e) {
      throw InputError(origin, o.pointer, std::string("cannot apply --set: ") + e.what());
    }
    if (tokens.size() > static_cast<std::size_t>(kMaxJsonDepth))
      throw InputError(origin, o.pointer,
                       fmt::format("expected a pointer of at most {} keys", kMaxJsonDepth));
    json* node = &document;
    for (const std::string& token : tokens) {
      if (node->is_null()) *node = token == "0" || token == "-" ? json::array() : json::object();
      if (node->is_object()) {
        node = &(*node)[token];
      } else if (node->is_array()) {
        node = &array_element(*node, token, origin, o.pointer);
      } else {
        throw InputError(origin, o.pointer,
                         fmt::format("cannot apply --set: \"{}\" is inside a {}, not an object "
                                     "or array",
                                     token, node->type_name()));
      }
    }
    *node = o.value;
  }
}

Scene scene_from_json(const json& document, const std::string& origin) {
  Reader r(document, "", origin);
  const long long version = r.integer("version", 1, 1000);
  if (version != kSceneFormatVersion)
    r.fail("version",
           fmt::format("expected scene format version {}, got {}", kSceneFormatVersion, version));
  Scene s;
  if (r.has("name")) s.name = r.string("name");
  s.camera = read_camera(r.object("camera"));
  s.light = read_light(r.object("light"));
  s.shape = read_shape(r.object("shape"), &s.tessellation);
  if (s.light.type == LightType::kGroup) set_member_weights(&s.light, s.shape.center);
  if (r.has("material")) s.material = read_material(r.object("material"));
  if (r.has("height")) s.height = read_height(r.object("height"), s.shape);
  s.representation =
      r.choice<Representation>("representation", kRepresentationNames, Representation::kBump);
  if (r.has("terminator")) s.terminator = read_terminator(r.object("terminator"));
  if (r.has("offset")) s.offset = read_offset(r.object("offset"));
  if (r.has("props")) {
    const json& list = r.at("props");
    if (!list.is_array() || list.size() > 64)
      r.fail("props", "expected an array of at most 64 spheres, got " + describe(list));
    for (std::size_t i = 0; i < list.size(); ++i) {
      Reader item = r.item("props", i);
      Shape prop = read_shape(item);
      if (prop.type != ShapeType::kSphere)
        item.fail("type", "expected \"sphere\" (props are spheres)");
      s.props.push_back(prop);
    }
  }
  if (s.tessellation && s.representation == Representation::kDisplacement)
    throw InputError(origin, "/shape/tessellation",
                     "expected no tessellation for the displacement representation (the ground "
                     "truth is its own fine mesh; see /displacement/edge_length)");
  if (!s.tessellation && s.shape.type != ShapeType::kMesh && s.offset.method != OffsetMethod::kNone)
    throw InputError(origin, "/offset/method",
                     fmt::format("expected \"none\" on an analytic shape, got \"{}\" (offset "
                                 "methods act on triangle meshes: set /shape/tessellation)",
                                 offset_method_info(s.offset.method).id));
  if (s.tessellation && static_cast<double>(tessellated_triangle_count(s.shape, *s.tessellation)) >
                            kMaxDisplacementTriangles)
    throw InputError(origin, "/shape/tessellation",
                     fmt::format("expected at most {:.0f} million triangles, got {}",
                                 kMaxDisplacementTriangles / 1e6,
                                 tessellated_triangle_count(s.shape, *s.tessellation)));
  s.displacement.edge_length = s.shape.radius / 256.0;
  if (r.has("displacement")) {
    Reader d = r.object("displacement");
    // Longer than the radius is no tessellation of the surface (and would
    // make the shadow-ray lift, e^2 kappa / 8, overflow for huge values).
    const double radius = s.shape.radius;
    s.displacement.edge_length = d.number_or(
        "edge_length", s.displacement.edge_length, [&](double e) { return e > 0.0 && e <= radius; },
        fmt::format("in (0, radius = {}] (scene units)", radius).c_str());
    d.finish();
  }
  r.finish();
  check_maps(s, origin);
  const double reach =
      s.height.amplitude * height_bounds(s.height.function, s.height.height_map(), s.shape).max_abs;
  const double triangles = estimated_triangles(s.shape, reach, s.displacement.edge_length);
  if (s.representation == Representation::kDisplacement && triangles > kMaxDisplacementTriangles)
    throw InputError(
        origin, "/displacement/edge_length",
        fmt::format("expected an edge length giving at most {:.0f} million "
                    "triangles, got {} ({:.0f} million)",
                    kMaxDisplacementTriangles / 1e6, s.displacement.edge_length, triangles / 1e6));
  return s;
}

Scene load_scene(const std::string& path, const std::vector<Override>& overrides) {
  json document = read_json_file(path);
  const std::string origin = overrides.empty() ? path : path + " (after --set)";
  apply_overrides(document, overrides, origin);
  resolve_map_files(document, path);  // after --set: its /height/file too
  return scene_from_json(document, origin);
}

const char* to_string(Representation r) {
  return name_of<Representation>(kRepresentationNames, r);
}

const char* to_string(HeightFamily f) {
  return name_of<HeightFamily>(kHeightFamilyNames, f);
}

bool is_scene_file_name(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
  return extension == ".json";
}

nlohmann::json asset_scene_document(const std::string& path, const std::string& node) {
  const std::string file = std::filesystem::absolute(path).lexically_normal().string();
  LoadedMesh loaded;
  try {
    loaded = load_mesh_file(file, MeshTransform{}, MeshNormals::kFile, node);
  } catch (const MeshNodeError& e) {
    throw InputError(path, "/shape/node", e.what());
  } catch (const MeshFileError& e) {
    throw InputError(
        path, "",
        fmt::format("expected a scene file (.json) or a mesh file Assimp reads: {}", e.what()));
  }
  const MeshSurface& m = *loaded.surface;
  const Vec3 c = mesh_centre(m), extent = m.bounds_max - m.bounds_min;
  const double r = mesh_radius(m);
  // The box's face towards the camera, with 10 % to spare; a flat mesh seen
  // edge-on still gets a view of its size.
  const double side = 1.1 * std::max({extent.x, extent.y, 0.1 * r});
  nlohmann::json doc = {
      {"version", 1},
      {"name", std::filesystem::path(path).stem().string()},
      {"camera",
       {{"projection", "orthographic"},
        {"position", {c.x, c.y, c.z - 3.0 * r}},
        {"direction", {0, 0, 1}},
        {"right", {side, 0, 0}},
        {"up", {0, side, 0}},
        {"width", 256},
        {"height", 256},
        {"spp", 16},
        {"seed", 1}}},
      {"light", {{"type", "distant"}, {"direction", {-1, 0.3, -0.2}}, {"irradiance", kPi}}},
      {"shape", {{"type", "mesh"}, {"file", file}}},
      {"material", {{"albedo", 0.8}}},
      {"representation", "bump"}};
  if (!node.empty()) doc["shape"]["node"] = node;
  // An asset that names its own normal map is shaded with it.
  if (!m.normal_texture.empty() && m.has_uvs()) doc["height"] = {{"type", "normal-map"}};
  return doc;
}

}  // namespace penumbra
