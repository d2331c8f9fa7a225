// The POV-Ray exporter: the scene as SDL. In POV-Ray's part of the cache key
// (code_digest.h).
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include <filesystem>

#include "core/surface_map.h"
#include "core/tessellation.h"
#include "image/image_io.h"
#include "renderers/external/external.h"
#include "renderers/external/povray/povray.h"
#include "scene/scene_json.h"

namespace penumbra {
namespace {

// Every number in the SDL goes through here: shortest round-trip decimal,
// never a locale separator, never inf/nan (the scene reader refuses those).
std::string num(double v) {
  if (!std::isfinite(v)) throw ExportError("POV-Ray export: a non-finite number reached the SDL");
  return fmt::format("{}", v == 0.0 ? 0.0 : v);
}
std::string vec(const Vec3& v) {
  return fmt::format("<{}, {}, {}>", num(v.x), num(v.y), num(v.z));
}
// Mesh data are single precision, and POV-Ray stores mesh2 vectors as floats:
// the shortest decimal that rounds back to the float gives POV-Ray the
// evaluator's vertices bit for bit, in fewer characters than the double.
std::string num(float v) {
  if (!std::isfinite(v)) throw ExportError("POV-Ray export: a non-finite number reached the SDL");
  return fmt::format("{}", v == 0.0f ? 0.0f : v);
}
std::string mesh_vectors(const std::vector<float>& xyz) {
  std::string out;
  for (std::size_t i = 0; i < xyz.size(); i += 3)
    out += fmt::format(",\n    <{}, {}, {}>", num(xyz[i]), num(xyz[i + 1]), num(xyz[i + 2]));
  return out;
}

// A proper rotation taking canonical +y to the shape's axis. POV-Ray's
// isosurface container box and cylinder primitive are built around +y, then
// moved with this matrix; no scaling, so bump amplitudes are unaffected.
struct Placement {
  Vec3 x, y, z, origin;
};
Placement placement(const Shape& shape) {
  const Frame f = Frame::from_z(shape.axis);
  Placement p{f.t, shape.axis, f.s, shape.center};
  if (dot(p.x, cross(p.y, p.z)) < 0.0) p.z = -p.z;
  return p;
}
std::string matrix(const Placement& p) {
  return fmt::format("matrix <{}, {}, {},  {}, {}, {},  {}, {}, {},  {}, {}, {}>", num(p.x.x),
                     num(p.x.y), num(p.x.z), num(p.y.x), num(p.y.y), num(p.y.z), num(p.z.x),
                     num(p.z.y), num(p.z.z), num(p.origin.x), num(p.origin.y), num(p.origin.z));
}

// POV-Ray's function VM folds nothing, and an isosurface evaluates its
// function tens of millions of times: the SDL leaves out what changes no bit
// (a factor 1, a term 0 * x, a phase + 0; a + (+-0) is a for every a, and the
// sign of a zero never reaches F or the bump pattern).
std::string times(double factor, const std::string& expression) {
  return factor == 1.0 ? expression : num(factor) + "*" + expression;
}
std::string linear_sdl(const Vec3& k, double constant) {
  std::string out;
  const std::pair<double, const char*> terms[] = {{k.x, "x"}, {k.y, "y"}, {k.z, "z"}};
  for (const auto& [factor, name] : terms)
    if (factor != 0.0) out += (out.empty() ? "" : " + ") + times(factor, name);
  if (constant != 0.0 || out.empty()) out += (out.empty() ? "" : " + ") + num(constant);
  return out;
}

// The height function in canonical coordinates: with world P = M q + c,
// dot(k, P) = dot(M^T k, q) + dot(k, c).
std::string height_function(const HeightFunction& f, const Placement& p) {
  std::string body;
  for (const SineTerm& t : f.terms) {
    const Vec3 k{dot(t.k, p.x), dot(t.k, p.y), dot(t.k, p.z)};
    const double w = 2.0 * kPi;
    const std::string factor =
        fmt::format("sin({})", linear_sdl(w * k, t.phase + w * dot(t.k, p.origin)));
    if (!body.empty()) body += f.combine == HeightCombine::kSum ? "\n    + " : "\n    * ";
    body += f.combine == HeightCombine::kSum ? times(t.weight, factor) : factor;
  }
  return body.empty() ? "0" : body;
}

}  // namespace

std::string comment_safe(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (out.size() >= 80) break;
    const bool ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                    c == ' ' || c == '_' || c == '.' || c == '+' || c == '-';
    out += ok ? c : '_';
  }
  return out;
}

std::vector<std::string> PovrayExport::arguments(const std::string& input,
                                                 const std::string& output, int threads) const {
  return {"+I" + input,
          "+O" + output,
          "+FE",  // OpenEXR, linear half float
          fmt::format("+W{}", width * supersample_x),
          fmt::format("+H{}", height * supersample_y),
          "-A",   // no anti-aliasing: one ray through each (sub)pixel centre
          "+UA",  // alpha: the background is transparent, alpha = coverage
          "-D",   // no display
          "-P",   // no pause
          "+MV3.7",
          fmt::format("+WT{}", single_thread ? 1 : std::max(1, threads))};
}

namespace {

// What POV-Ray 3.7 cannot express; ExportError says why.
void check_povray_scene(const Scene& scene) {
  const RendererInfo& info = povray_entry().info;
  if (!offers(info, scene.representation, scene.terminator.method.method))
    throw ExportError(
        fmt::format("POV-Ray has no shadow-terminator method; it renders only `none` (got `{}`)",
                    method_info(scene.terminator.method.method).id));
  if (scene.light.type == LightType::kPoint)
    throw ExportError(
        "POV-Ray export supports distant lights only (POV-Ray's point-light fade is "
        "2/(1+(d/D)^2), not the inverse-square law the evaluator uses)");
  if (scene.light.type == LightType::kSphere || scene.light.type == LightType::kQuad)
    throw ExportError(
        "POV-Ray export supports distant lights only: its area_light is a grid of point "
        "lights that emit equally in every direction, not a Lambertian sphere or quad");
  if (scene.light.type == LightType::kGroup)
    throw ExportError(
        "POV-Ray export supports one distant light only: its lights cannot express the group's "
        "area lights or environment, and the studies compare it under the sun");
  if (scene.light.type == LightType::kEnvironment)
    throw ExportError(
        "POV-Ray export supports distant lights only: an environment lights a POV-Ray scene "
        "only through radiosity, which is not the same estimator as the evaluator's direct "
        "light");
  if (scene.material.specular_weight > 0.0)
    throw ExportError("POV-Ray export supports Lambertian materials only (specular_weight 0)");
  if (!scene.props.empty())
    throw ExportError("POV-Ray export: props are evaluator-only (remove /props)");
  refuse_unoffered(scene, info, "POV-Ray");
  // POV-Ray starts shadow rays at the hit itself: the smooth-shading
  // terminator cannot be moved there (reference sheet, section 6).
  if (!offers(info, scene.offset.method))
    throw ExportError(
        fmt::format("POV-Ray has no shadow-ray offset; it offers only `none` (got offset `{}`)",
                    offset_method_info(scene.offset.method).id));
}

// The values every part of the SDL shares.
struct SdlContext {
  const Scene& scene;
  Placement place;
  double amplitude, max_h, reach, r, half;
  bool has_height, cylinder;
  std::string texture;
  const SurfaceMap* map;  // an image height map, or null
};

SdlContext sdl_context(const Scene& scene) {
  const Shape& shape = scene.shape;
  const HeightFunction& hf = scene.height.function;
  const SurfaceMap* map = scene.height.height_map();
  SdlContext c{scene,
               placement(shape),
               scene.height.amplitude,
               map ? height_bounds(hf, map, shape).max_abs : max_abs_height(hf),
               0.0,
               shape.radius,
               0.5 * shape.height,
               false,
               shape.type == ShapeType::kCylinder,
               "",
               map};
  c.has_height = c.amplitude > 0.0 && c.max_h > 0.0 && (map || !hf.terms.empty());
  c.reach = c.has_height ? c.amplitude * c.max_h : 0.0;
  c.texture = fmt::format(
      "  pigment {{ rgb {} }}\n"
      "  finish {{ ambient 0 emission 0 diffuse 1 brilliance 1 specular 0 phong 0 reflection 0 "
      "}}\n",
      num(scene.material.albedo));
  return c;
}

// Header comment with the command line, global settings, camera and light.
std::string sdl_header(const Scene& scene, const PovrayExport& out) {
  const Camera& cam = scene.camera;
  const int nx = out.supersample_x, ny = out.supersample_y;
  std::string s;
  s += fmt::format("// Penumbra {} export of scene \"{}\" ({}).\n", kPenumbraVersion,
                   comment_safe(scene.name), to_string(scene.representation));
  s += fmt::format(
      "// Render: povray +Iscene.pov +Oscene.exr +FE +W{} +H{} -A +UA -D -P +MV3.7 +WT{}\n"
      "// then box-filter the result {}x{} down to {}x{}: {} samples per pixel at the\n"
      "// evaluator's stratum centres. Radiance in W m^-2 sr^-1 (light colour E/pi).\n",
      out.width * nx, out.height * ny, out.single_thread ? 1 : 2, nx, ny, out.width, out.height,
      nx * ny);
  s += "#version 3.7;\n";
  s += "global_settings { assumed_gamma 1.0 max_trace_level 1 ambient_light rgb 0 }\n";
  s += "background { rgbt <0, 0, 0, 1> }\n\n";

  // Camera: every vector explicit (look_at and angle would rescale them).
  s += fmt::format("camera {{\n  {}\n  location {}\n  direction {}\n  right {}\n  up {}\n}}\n\n",
                   cam.projection == Projection::kOrthographic ? "orthographic" : "perspective",
                   vec(cam.position), vec(cam.direction), vec(cam.right), vec(cam.up));

  // A parallel light far away along the direction towards the light. POV-Ray
  // gives colour * pigment * cos, so colour E/pi yields albedo/pi * E * cos.
  const Shape& shape = scene.shape;
  const Vec3 wi = normalize(scene.light.direction);
  const double far = 1e4 * std::max(1.0, shape.radius + length(shape.center));
  const double colour = scene.light.irradiance / kPi;
  s += fmt::format("light_source {{\n  {}\n  color rgb {}\n  parallel\n  point_at {}\n}}\n\n",
                   vec(shape.center + wi * far), num(colour), vec(shape.center));
  return s;
}

// A triangle mesh in scene coordinates as a mesh2: with `normals`, one per
// vertex, indexed like the vertices (POV-Ray interpolates them
// barycentrically); without, POV-Ray shades with Ng.
std::string mesh2_sdl(const TriangleMesh& mesh, bool normals, const std::string& texture) {
  std::string faces;
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3)
    faces += fmt::format(",\n    <{}, {}, {}>", mesh.triangles[t], mesh.triangles[t + 1],
                         mesh.triangles[t + 2]);
  std::string s = fmt::format("mesh2 {{\n  vertex_vectors {{\n    {}{}\n  }}\n",
                              mesh.vertex_count(), mesh_vectors(mesh.positions));
  if (normals)
    s += fmt::format("  normal_vectors {{\n    {}{}\n  }}\n", mesh.vertex_count(),
                     mesh_vectors(mesh.normals));
  s += fmt::format("  face_indices {{\n    {}{}\n  }}\n{}}}\n", mesh.triangle_count(), faces,
                   texture);
  return s;
}

// A tessellated shape: the evaluator's very triangles as a mesh2.
std::string mesh_sdl(const SdlContext& c) {
  const Scene& scene = c.scene;
  // POV-Ray's bump perturbs the normal with the 3D pattern gradient, the
  // evaluator rotates the analytic bumped normal onto Ni: not the same
  // shading normal, so the comparison would measure that, not the mesh.
  if (scene.representation != Representation::kSmooth && c.has_height)
    throw ExportError(
        "POV-Ray export: bump on a tessellated shape is evaluator-only (use the smooth "
        "representation, or no /shape/tessellation)");
  const TriangleMesh mesh = tessellate(scene.shape, *scene.tessellation);
  const bool smooth = scene.tessellation->shading == NormalShading::kSmooth;
  return fmt::format(
             "// Low-poly {} mesh: {} vertices, {} triangles. POV-Ray starts shadow rays\n"
             "// on the flat triangle (offset `none`).\n",
             smooth ? "smooth-shaded" : "flat-shaded", mesh.vertex_count(), mesh.triangle_count()) +
         mesh2_sdl(mesh, smooth, c.texture);
}

// A mesh shape: its own triangles and normals, or its displaced truth's
// (mesh_shape_triangles). Its bump was refused before (refuse_unoffered,
// the renderer table's mesh_bump_why_not).
std::string mesh_shape_sdl(const SdlContext& c) {
  const Scene& scene = c.scene;
  const bool truth = scene.representation == Representation::kDisplacement;
  const TriangleMesh mesh = external::mesh_shape_triangles(scene, truth);
  return fmt::format(
             "// Mesh shape{}: {} vertices, {} triangles. POV-Ray starts shadow rays on\n"
             "// the flat triangle.\n",
             truth ? ", its displaced truth at the evaluator's subdivision with the exact normals"
                   : "",
             mesh.vertex_count(), mesh.triangle_count()) +
         mesh2_sdl(mesh, /*normals=*/true, c.texture);
}

// The displaced surface as the evaluator's own grid (make_grid_mesh at the
// scene's edge length), its vertex normals the exact displaced normals: the
// ground truth of image height maps and of the plane, which have no closed
// form for an isosurface.
std::string displaced_grid_sdl(const SdlContext& c) {
  const Scene& scene = c.scene;
  const double reach = c.amplitude * c.max_h;
  const GridResolution res = grid_resolution(scene.shape, scene.displacement.edge_length, reach);
  const TriangleMesh mesh =
      make_grid_mesh(scene.shape, scene.height.function, c.amplitude, res, c.map);
  return fmt::format(
             "// True displacement: the evaluator's displaced grid ({} x {} segments, {} "
             "triangles),\n// with the exact displaced normal at each vertex.\n",
             res.nu, res.nv, mesh.triangle_count()) +
         mesh2_sdl(mesh, /*normals=*/true, c.texture);
}

// |q| of the point q, kept away from 0: the radial distance of the base surface.
std::string rho_sdl(const SdlContext& c) {
  return c.cylinder ? "max(sqrt(x*x + z*z), " + num(1e-9 * c.r) + ")"
                    : "max(sqrt(x*x + y*y + z*z), " + num(1e-9 * c.r) + ")";
}

// h at the base point under q (radial projection onto the base surface),
// with `rho` the name of |q|'s value: constant along the normal, so POV-Ray's
// 3D pattern gradient is the surface gradient the evaluator uses, and the
// isosurface is P + A h N.
std::string h_at_base_sdl(const SdlContext& c, const std::string& rho) {
  if (c.scene.shape.type == ShapeType::kPlane) return "Penumbra_H(x, 0, z)";
  auto projected = [&](const char* axis) { return times(c.r, axis) + " / " + rho; };
  return c.cylinder ? fmt::format("Penumbra_H({}, y, {})", projected("x"), projected("z"))
                    : fmt::format("Penumbra_H({}, {}, {})", projected("x"), projected("y"),
                                  projected("z"));
}

// A function of (x, y, z) declared as `name` from `body`, a function of x, y,
// z and Crho = |q| (rho_sdl): its call computes |q| once, not once per use
// (the VM would compute each use again).
std::string with_rho_sdl(const SdlContext& c, const std::string& name, std::string body,
                         std::string* call) {
  *call = fmt::format("{}(x, y, z, {})", name, rho_sdl(c));
  return fmt::format("#declare {} = function(x, y, z, Crho) {{ {} }}\n", name, body);
}

// True displacement: the isosurface |q| = R + A h(base point of q).
std::string isosurface_sdl(const SdlContext& c) {
  // |grad F| = sqrt(1 + A^2 |grad (h o projection)|^2); the projection onto
  // the base surface stretches tangential gradients by at most R / r_min.
  const double stretch = c.r / std::max(c.r - c.reach, 1e-9 * c.r);
  const double gradient =
      std::sqrt(1.0 + std::pow(c.amplitude * max_gradient_norm(c.scene.height.function) *
                                   std::max(1.0, stretch),
                               2));
  const double outer = c.r + 1.01 * c.reach + 1e-6 * c.r;
  std::string function;
  const std::string declaration = with_rho_sdl(
      c, "Penumbra_F",
      fmt::format("Crho - {} - {} * {}", num(c.r), num(c.amplitude), h_at_base_sdl(c, "Crho")),
      &function);
  const std::string container =
      c.cylinder ? fmt::format("box {{ <{0}, {1}, {0}>, <{2}, {3}, {2}> }}", num(-outer),
                               num(-c.half), num(outer), num(c.half))
                 : fmt::format("sphere {{ <0, 0, 0>, {} }}", num(outer));
  return declaration +
         fmt::format(
             "// True displacement: the surface |q| = R + A h(base point of q).\n"
             "// max_gradient = sqrt(1 + (A max|grad h| R/(R - A max|h|))^2) * 1.05:\n"
             "// an upper bound of |grad F| near the surface, plus 5% for rounding.\n"
             "// accuracy 1e-6 and max_trace 2: a hit lies up to `accuracy` inside the surface,\n"
             "// and at grazing light a shadow ray from it finds the surface's own skin first;\n"
             "// with max_trace 1 that root either shadows the point (darker cast-shadow\n"
             "// edges) or, nearer than 1e-4, is dropped with the real occluder behind it\n"
             "// (light leaks). Measured in the README, \"POV-Ray's isosurface\".\n"
             "isosurface {{\n  function {{ {} }}\n  contained_by {{ {} }}\n  threshold 0\n"
             "  accuracy 1e-6\n  max_trace 2\n  max_gradient {}\n{}{}  {}\n}}\n",
             function, container, num(1.05 * gradient),
             c.cylinder && !c.scene.shape.caps ? "  open\n" : "", c.texture, matrix(c.place));
}

// The plane's corners in canonical coordinates (y along its normal), closed:
// the rectangle of half sides width/2 along frame.s and height/2 along frame.t.
std::string plane_corners(const SdlContext& c) {
  const Shape& shape = c.scene.shape;
  std::string out;
  const double signs[5][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}, {-1, -1}};
  for (const auto& [a, b] : signs) {
    const Vec3 d =
        shape.frame.s * (0.5 * a * shape.width) + shape.frame.t * (0.5 * b * shape.height);
    out += (out.empty() ? "" : ", ") +
           vec(Vec3{dot(d, c.place.x), dot(d, c.place.y), dot(d, c.place.z)});
  }
  return out;
}

// The analytic primitive, with POV-Ray's bump for the bump representation.
std::string primitive_sdl(const SdlContext& c) {
  std::string normal, declaration;
  if (c.scene.representation == Representation::kBump && c.has_height) {
    // POV-Ray: Ns = normalize(N - (2/15) bump_size grad f). With
    // f = 0.5 + C h, bump_size = 7.5 A / C gives N - A grad h; C keeps f in
    // (0.1, 0.9), away from the pattern's wrap at 1.
    const double k = 0.4 / c.max_h;
    std::string h = h_at_base_sdl(c, "Crho");  // the plane's needs no Crho
    if (c.scene.shape.type != ShapeType::kPlane) declaration = with_rho_sdl(c, "Penumbra_B", h, &h);
    normal = fmt::format(
        "  normal {{\n    function {{ 0.5 + {} * {} }}\n"
        "    bump_size {}\n    accuracy 1e-4\n  }}\n",
        num(k), h, num(7.5 * c.amplitude / k));
  }
  if (c.scene.shape.type == ShapeType::kPlane)
    return declaration + fmt::format("polygon {{\n  5, {}\n{}{}  {}\n}}\n", plane_corners(c),
                                     c.texture, normal, matrix(c.place));
  if (c.cylinder)
    return declaration + fmt::format("cylinder {{\n  <0, {}, 0>, <0, {}, 0>, {}\n{}{}{}  {}\n}}\n",
                                     num(-c.half), num(c.half), num(c.r),
                                     c.scene.shape.caps ? "" : "  open\n", c.texture, normal,
                                     matrix(c.place));
  return declaration + fmt::format("sphere {{\n  <0, 0, 0>, {}\n{}{}  {}\n}}\n", num(c.r),
                                   c.texture, normal, matrix(c.place));
}

// ---- image height maps ------------------------------------------------------

// The map's texels rescaled to [0, 1] as R = G = B (POV-Ray reads colours;
// a constant map stays 0): the SDL maps them back with `low` + `range` x.
struct MapTexels {
  Image image;
  double low = 0.0, range = 0.0;
};

MapTexels map_texels(const SurfaceMap& m) {
  MapTexels out;
  const auto [lo, hi] = std::minmax_element(m.texels.begin(), m.texels.end());
  out.low = *lo, out.range = double(*hi) - double(*lo);
  out.image.width = m.width, out.image.height = m.height;
  out.image.channels = {"R", "G", "B"};
  out.image.pixels.reserve(m.texels.size() * 3);
  for (float t : m.texels) {
    const float v = out.range > 0.0 ? float((double(t) - out.low) / out.range) : 0.0f;
    out.image.pixels.insert(out.image.pixels.end(), {v, v, v});
  }
  return out;
}

// The coordinate of canonical q along the world direction `d`: dot(M q, d).
std::string along_sdl(const Placement& p, const Vec3& d) {
  return fmt::format("{} * x + {} * y + {} * z", num(dot(p.x, d)), num(dot(p.y, d)),
                     num(dot(p.z, d)));
}

// The shape's (u, v) of canonical q (surface_parameters, core/surface_map.h):
// Penumbra_U and Penumbra_V, over the local axes Penumbra_Ls, _Lt, _Ln.
std::string map_parameters_sdl(const SdlContext& c) {
  const Shape& shape = c.scene.shape;
  std::string s = fmt::format(
      "#declare Penumbra_Ls = function {{ {} }}\n#declare Penumbra_Lt = function {{ {} }}\n"
      "#declare Penumbra_Ln = function {{ {} }}\n",
      along_sdl(c.place, shape.frame.s), along_sdl(c.place, shape.frame.t),
      along_sdl(c.place, shape.frame.n));
  if (shape.type == ShapeType::kPlane)
    return s + fmt::format(
                   "#declare Penumbra_U = function {{ Penumbra_Ls(x, y, z) / {} + 0.5 }}\n"
                   "#declare Penumbra_V = function {{ Penumbra_Lt(x, y, z) / {} + 0.5 }}\n",
                   num(shape.width), num(shape.height));
  // The azimuth in [0, 2 pi) as the evaluator measures it, over 2 pi.
  s += fmt::format(
      "#declare Penumbra_Az = function(Ca, Cb) {{ select(atan2(Cb, Ca), atan2(Cb, Ca) + {0}, "
      "atan2(Cb, Ca)) / {0} }}\n"
      "#declare Penumbra_U = function {{ Penumbra_Az(Penumbra_Ls(x, y, z), Penumbra_Lt(x, y, "
      "z)) }}\n",
      num(2.0 * kPi));
  if (c.cylinder)
    return s +
           fmt::format("#declare Penumbra_V = function {{ (Penumbra_Ln(x, y, z) + {}) / {} }}\n",
                       num(c.half), num(shape.height));
  return s + fmt::format(
                 "#declare Penumbra_V = function {{ 1 - acos(max(-1, min(1, Penumbra_Ln(x, y, z) / "
                 "max(sqrt(x * x + y * y + z * z), {})))) / {} }}\n",
                 num(1e-12 * c.r), num(kPi));
}

// Penumbra_H: the uniform cubic B-spline of the texels at the shape's (u, v)
// (sample_map: Cycles' Cubic, -0.5 texel offset), from 16 nearest-texel
// lookups of the image: column i at x = (i + 0.5) / W, row j (0 the top) at
// y = 1 - (j + 0.5) / H of the unit square POV-Ray lays the image on.
std::string map_functions_sdl(const SdlContext& c, const MapTexels& t) {
  const SurfaceMap& m = *c.map;
  const auto index = [&](const char* name, int size) {
    return m.edge == MapEdge::kWrap
               ? fmt::format("#declare {0} = function(Ci) {{ mod(mod(Ci, {1}) + {1}, {1}) }}\n",
                             name, size)
               : fmt::format("#declare {} = function(Ci) {{ min(max(Ci, 0), {}) }}\n", name,
                             size - 1);
  };
  std::string s = fmt::format(
      "// The image height map: texels rescaled to [0, 1] in {}; h = {} + {} x texel.\n"
      "#declare Penumbra_Img = function {{ pigment {{ image_map {{ exr \"{}\" }} }} }}\n",
      kPovrayMapFile, num(t.low), num(t.range), kPovrayMapFile);
  s += index("Penumbra_I", m.width) + index("Penumbra_J", m.height);
  s += fmt::format(
      "#declare Penumbra_Tex = function(Ci, Cj) {{ Penumbra_Img((Penumbra_I(Ci) + 0.5) / {}, 1 - "
      "(Penumbra_J(Cj) + 0.5) / {}, 0).red }}\n",
      m.width, m.height);
  s +=
      "#declare Penumbra_W0 = function(Ff) { (1 - Ff) * (1 - Ff) * (1 - Ff) / 6 }\n"
      "#declare Penumbra_W1 = function(Ff) { (3 * Ff * Ff * Ff - 6 * Ff * Ff + 4) / 6 }\n"
      "#declare Penumbra_W2 = function(Ff) { (-3 * Ff * Ff * Ff + 3 * Ff * Ff + 3 * Ff + 1) / 6 }\n"
      "#declare Penumbra_W3 = function(Ff) { Ff * Ff * Ff / 6 }\n"
      "#declare Penumbra_Row = function(Ci, Cj, Ff) { Penumbra_W0(Ff) * Penumbra_Tex(Ci - 1, Cj) "
      "+ Penumbra_W1(Ff) * Penumbra_Tex(Ci, Cj) + Penumbra_W2(Ff) * Penumbra_Tex(Ci + 1, Cj) + "
      "Penumbra_W3(Ff) * Penumbra_Tex(Ci + 2, Cj) }\n"
      "#declare Penumbra_S4 = function(Ci, Ff, Cj, Gg) { Penumbra_W0(Gg) * Penumbra_Row(Ci, Cj - "
      "1, Ff) + Penumbra_W1(Gg) * Penumbra_Row(Ci, Cj, Ff) + Penumbra_W2(Gg) * Penumbra_Row(Ci, Cj "
      "+ 1, Ff) + Penumbra_W3(Gg) * Penumbra_Row(Ci, Cj + 2, Ff) }\n"
      "#declare Penumbra_S2 = function(Xs, Ys) { Penumbra_S4(floor(Xs), Xs - floor(Xs), "
      "floor(Ys), Ys - floor(Ys)) }\n";
  s += map_parameters_sdl(c);
  s += fmt::format(
      "#declare Penumbra_H = function {{ {} + {} * Penumbra_S2({} * Penumbra_U(x, y, z) - 0.5, "
      "(1 - {} * Penumbra_V(x, y, z)) * {} - 0.5) }}\n\n",
      num(t.low), num(t.range), num(m.tiles_u * m.width), num(m.tiles_v), m.height);
  return s;
}

}  // namespace

PovrayExport export_povray(const Scene& scene) {
  check_povray_scene(scene);
  PovrayExport out;
  out.width = scene.camera.width, out.height = scene.camera.height;
  strata(scene.camera.spp, &out.supersample_x, &out.supersample_y);
  const SdlContext c = sdl_context(scene);
  const bool displaced = scene.representation == Representation::kDisplacement && c.has_height;
  const bool grid = displaced && (c.map || scene.shape.type == ShapeType::kPlane);
  out.single_thread = displaced && !grid && scene.shape.type != ShapeType::kMesh;  // the isosurface
  out.sdl = sdl_header(scene, out);
  if (scene.tessellation) {
    out.sdl += mesh_sdl(c);
    return out;
  }
  if (scene.shape.type == ShapeType::kMesh) {
    out.sdl += mesh_shape_sdl(c);
    return out;
  }
  if (grid) {
    out.sdl += displaced_grid_sdl(c);
    return out;
  }
  if (c.has_height && c.map) {
    MapTexels texels = map_texels(*c.map);
    out.sdl += map_functions_sdl(c, texels);
    out.map = std::move(texels.image);
  } else if (c.has_height) {
    out.sdl += fmt::format("#declare Penumbra_H = function(x, y, z) {{\n    {}\n}}\n\n",
                           height_function(scene.height.function, c.place));
  }
  out.sdl += displaced ? isosurface_sdl(c) : primitive_sdl(c);
  return out;
}

void write_povray_files(const PovrayExport& job, const std::string& folder) {
  const std::filesystem::path dir(folder);
  if (!job.map.pixels.empty()) write_exr(job.map, (dir / kPovrayMapFile).string());
  write_text_file((dir / kPovraySceneFile).string(), job.sdl);
}

}  // namespace penumbra
