#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "core/tessellation.h"
#include "export/export.h"
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

// The height function in canonical coordinates: with world P = M q + c,
// dot(k, P) = dot(M^T k, q) + dot(k, c).
std::string height_function(const HeightFunction& f, const Placement& p) {
  std::string body;
  for (const SineTerm& t : f.terms) {
    const Vec3 k{dot(t.k, p.x), dot(t.k, p.y), dot(t.k, p.z)};
    const double w = 2.0 * kPi;
    const std::string factor =
        fmt::format("sin({}*x + {}*y + {}*z + {})", num(w * k.x), num(w * k.y), num(w * k.z),
                    num(t.phase + w * dot(t.k, p.origin)));
    if (!body.empty()) body += f.combine == HeightCombine::kSum ? "\n    + " : "\n    * ";
    body += f.combine == HeightCombine::kSum ? fmt::format("{}*{}", num(t.weight), factor) : factor;
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
  if (!offers(RendererKind::kPovray, scene.representation, scene.terminator.method.method))
    throw ExportError(
        fmt::format("POV-Ray has no shadow-terminator method; it renders only `none` (got `{}`)",
                    method_info(scene.terminator.method.method).id));
  if (scene.light.type != LightType::kDistant)
    throw ExportError(
        "POV-Ray export supports distant lights only (POV-Ray's point-light fade is "
        "2/(1+(d/D)^2), not the inverse-square law the evaluator uses)");
  if (scene.material.specular_weight > 0.0)
    throw ExportError("POV-Ray export supports Lambertian materials only (specular_weight 0)");
  if (!scene.props.empty())
    throw ExportError("POV-Ray export: props are evaluator-only (remove /props)");
  refuse_unoffered(scene, RendererKind::kPovray, "POV-Ray");
  // POV-Ray starts shadow rays at the hit itself: the smooth-shading
  // terminator cannot be moved there (reference sheet, section 6).
  if (!offers(RendererKind::kPovray, scene.offset.method))
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
};

SdlContext sdl_context(const Scene& scene) {
  const Shape& shape = scene.shape;
  const HeightFunction& hf = scene.height.function;
  SdlContext c{scene,
               placement(shape),
               scene.height.amplitude,
               max_abs_height(hf),
               0.0,
               shape.radius,
               0.5 * shape.height,
               false,
               shape.type == ShapeType::kCylinder,
               ""};
  c.has_height = c.amplitude > 0.0 && c.max_h > 0.0 && !hf.terms.empty();
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
  // In scene coordinates. Smooth shading: one normal per vertex, indexed like
  // the vertices (POV-Ray interpolates them barycentrically); flat: no
  // normals, POV-Ray shades with Ng.
  const TriangleMesh mesh = tessellate(scene.shape, *scene.tessellation);
  std::string faces;
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3)
    faces += fmt::format(",\n    <{}, {}, {}>", mesh.triangles[t], mesh.triangles[t + 1],
                         mesh.triangles[t + 2]);
  const bool smooth = scene.tessellation->shading == NormalShading::kSmooth;
  std::string s = fmt::format(
      "// Low-poly {} mesh: {} vertices, {} triangles. POV-Ray starts shadow rays\n"
      "// on the flat triangle (offset `none`).\n"
      "mesh2 {{\n  vertex_vectors {{\n    {}{}\n  }}\n",
      smooth ? "smooth-shaded" : "flat-shaded", mesh.vertex_count(), mesh.triangle_count(),
      mesh.vertex_count(), mesh_vectors(mesh.positions));
  if (smooth)
    s += fmt::format("  normal_vectors {{\n    {}{}\n  }}\n", mesh.vertex_count(),
                     mesh_vectors(mesh.normals));
  s += fmt::format("  face_indices {{\n    {}{}\n  }}\n{}}}\n", mesh.triangle_count(), faces,
                   c.texture);
  return s;
}

// |q| of the point q, kept away from 0: the radial distance of the base surface.
std::string rho_sdl(const SdlContext& c) {
  return c.cylinder ? "max(sqrt(x*x + z*z), " + num(1e-9 * c.r) + ")"
                    : "max(sqrt(x*x + y*y + z*z), " + num(1e-9 * c.r) + ")";
}

// h at the base point under q (radial projection onto the base surface):
// constant along the normal, so POV-Ray's 3D pattern gradient is the
// surface gradient the evaluator uses, and the isosurface is P + A h N.
std::string projected_h_sdl(const SdlContext& c) {
  const std::string rho = rho_sdl(c);
  return c.cylinder ? fmt::format("Penumbra_H({0} * x / {1}, y, {0} * z / {1})", num(c.r), rho)
                    : fmt::format("Penumbra_H({0} * x / {1}, {0} * y / {1}, {0} * z / {1})",
                                  num(c.r), rho);
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
  const std::string function =
      fmt::format("{} - {} - {} * {}", rho_sdl(c), num(c.r), num(c.amplitude), projected_h_sdl(c));
  const std::string container =
      c.cylinder ? fmt::format("box {{ <{0}, {1}, {0}>, <{2}, {3}, {2}> }}", num(-outer),
                               num(-c.half), num(outer), num(c.half))
                 : fmt::format("sphere {{ <0, 0, 0>, {} }}", num(outer));
  return fmt::format(
      "// True displacement: the surface |q| = R + A h(base point of q).\n"
      "// max_gradient = sqrt(1 + (A max|grad h| R/(R - A max|h|))^2) * 1.05, an upper bound\n"
      "// of |grad F| near the surface plus 5% for rounding.\n"
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

// The analytic primitive, with POV-Ray's bump for the bump representation.
std::string primitive_sdl(const SdlContext& c) {
  std::string normal;
  if (c.scene.representation == Representation::kBump && c.has_height) {
    // POV-Ray: Ns = normalize(N - (2/15) bump_size grad f). With
    // f = 0.5 + C h, bump_size = 7.5 A / C gives N - A grad h; C keeps f in
    // (0.1, 0.9), away from the pattern's wrap at 1.
    const double k = 0.4 / c.max_h;
    normal = fmt::format(
        "  normal {{\n    function {{ 0.5 + {} * {} }}\n"
        "    bump_size {}\n    accuracy 1e-4\n  }}\n",
        num(k), projected_h_sdl(c), num(7.5 * c.amplitude / k));
  }
  if (c.cylinder)
    return fmt::format("cylinder {{\n  <0, {}, 0>, <0, {}, 0>, {}\n{}{}{}  {}\n}}\n", num(-c.half),
                       num(c.half), num(c.r), c.scene.shape.caps ? "" : "  open\n", c.texture,
                       normal, matrix(c.place));
  return fmt::format("sphere {{\n  <0, 0, 0>, {}\n{}{}  {}\n}}\n", num(c.r), c.texture, normal,
                     matrix(c.place));
}

}  // namespace

PovrayExport export_povray(const Scene& scene) {
  check_povray_scene(scene);
  PovrayExport out;
  out.width = scene.camera.width, out.height = scene.camera.height;
  strata(scene.camera.spp, &out.supersample_x, &out.supersample_y);
  const SdlContext c = sdl_context(scene);
  const bool isosurface = scene.representation == Representation::kDisplacement && c.has_height;
  out.single_thread = isosurface;
  out.sdl = sdl_header(scene, out);
  if (scene.tessellation) {
    out.sdl += mesh_sdl(c);
    return out;
  }
  if (c.has_height)
    out.sdl += fmt::format("#declare Penumbra_H = function(x, y, z) {{\n    {}\n}}\n\n",
                           height_function(scene.height.function, c.place));
  out.sdl += isosurface ? isosurface_sdl(c) : primitive_sdl(c);
  return out;
}

}  // namespace penumbra
