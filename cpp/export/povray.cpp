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

PovrayExport export_povray(const Scene& scene) {
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
  // POV-Ray starts shadow rays at the hit itself: the smooth-shading
  // terminator cannot be moved there (reference sheet, section 6).
  if (!offers(RendererKind::kPovray, scene.offset.method))
    throw ExportError(
        fmt::format("POV-Ray has no shadow-ray offset; it offers only `none` (got offset `{}`)",
                    offset_method_info(scene.offset.method).id));

  PovrayExport out;
  const Camera& cam = scene.camera;
  out.width = cam.width, out.height = cam.height;
  int nx = 1, ny = 1;
  strata(cam.spp, &nx, &ny);
  out.supersample_x = nx, out.supersample_y = ny;

  const Shape& shape = scene.shape;
  const Placement place = placement(shape);
  const double amplitude = scene.height.amplitude;
  const HeightFunction& hf = scene.height.function;
  const double max_h = max_abs_height(hf);
  const bool has_height = amplitude > 0.0 && max_h > 0.0 && !hf.terms.empty();
  const double reach = has_height ? amplitude * max_h : 0.0;
  const bool cylinder = shape.type == ShapeType::kCylinder;
  const double r = shape.radius, half = 0.5 * shape.height;
  const bool isosurface = scene.representation == Representation::kDisplacement && has_height;
  out.single_thread = isosurface;

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
  const Vec3 wi = normalize(scene.light.direction);
  const double far = 1e4 * std::max(1.0, r + length(shape.center));
  const double colour = scene.light.irradiance / kPi;
  s += fmt::format("light_source {{\n  {}\n  color rgb {}\n  parallel\n  point_at {}\n}}\n\n",
                   vec(shape.center + wi * far), num(colour), vec(shape.center));

  const std::string texture = fmt::format(
      "  pigment {{ rgb {} }}\n"
      "  finish {{ ambient 0 emission 0 diffuse 1 brilliance 1 specular 0 phong 0 reflection 0 "
      "}}\n",
      num(scene.material.albedo));

  if (scene.tessellation) {
    // POV-Ray's bump perturbs the normal with the 3D pattern gradient, the
    // evaluator rotates the analytic bumped normal onto Ni: not the same
    // shading normal, so the comparison would measure that, not the mesh.
    if (scene.representation != Representation::kSmooth && has_height)
      throw ExportError(
          "POV-Ray export: bump on a tessellated shape is evaluator-only (use the smooth "
          "representation, or no /shape/tessellation)");
    // The evaluator's very triangles, in scene coordinates. Smooth shading:
    // one normal per vertex, indexed like the vertices (POV-Ray interpolates
    // them barycentrically); flat: no normals, POV-Ray shades with Ng.
    const TriangleMesh mesh = tessellate(shape, *scene.tessellation);
    std::string faces;
    for (std::size_t t = 0; t < mesh.triangles.size(); t += 3)
      faces += fmt::format(",\n    <{}, {}, {}>", mesh.triangles[t], mesh.triangles[t + 1],
                           mesh.triangles[t + 2]);
    const bool smooth = scene.tessellation->shading == NormalShading::kSmooth;
    s += fmt::format(
        "// Low-poly {} mesh: {} vertices, {} triangles. POV-Ray starts shadow rays\n"
        "// on the flat triangle (offset `none`).\n"
        "mesh2 {{\n  vertex_vectors {{\n    {}{}\n  }}\n",
        smooth ? "smooth-shaded" : "flat-shaded", mesh.vertex_count(), mesh.triangle_count(),
        mesh.vertex_count(), mesh_vectors(mesh.positions));
    if (smooth)
      s += fmt::format("  normal_vectors {{\n    {}{}\n  }}\n", mesh.vertex_count(),
                       mesh_vectors(mesh.normals));
    s += fmt::format("  face_indices {{\n    {}{}\n  }}\n{}}}\n", mesh.triangle_count(), faces,
                     texture);
    out.sdl = std::move(s);
    return out;
  }

  if (has_height)
    s += fmt::format("#declare Penumbra_H = function(x, y, z) {{\n    {}\n}}\n\n",
                     height_function(hf, place));

  // h at the base point under q (radial projection onto the base surface):
  // constant along the normal, so POV-Ray's 3D pattern gradient is the
  // surface gradient the evaluator uses, and the isosurface is P + A h N.
  const std::string rho = cylinder ? "max(sqrt(x*x + z*z), " + num(1e-9 * r) + ")"
                                   : "max(sqrt(x*x + y*y + z*z), " + num(1e-9 * r) + ")";
  const std::string projected_h =
      cylinder
          ? fmt::format("Penumbra_H({0} * x / {1}, y, {0} * z / {1})", num(r), rho)
          : fmt::format("Penumbra_H({0} * x / {1}, {0} * y / {1}, {0} * z / {1})", num(r), rho);
  if (isosurface) {
    // |grad F| = sqrt(1 + A^2 |grad (h o projection)|^2); the projection onto
    // the base surface stretches tangential gradients by at most R / r_min.
    const double stretch = r / std::max(r - reach, 1e-9 * r);
    const double gradient =
        std::sqrt(1.0 + std::pow(amplitude * max_gradient_norm(hf) * std::max(1.0, stretch), 2));
    const double outer = r + 1.01 * reach + 1e-6 * r;
    const std::string function =
        fmt::format("{} - {} - {} * {}", rho, num(r), num(amplitude), projected_h);
    const std::string container = cylinder
                                      ? fmt::format("box {{ <{0}, {1}, {0}>, <{2}, {3}, {2}> }}",
                                                    num(-outer), num(-half), num(outer), num(half))
                                      : fmt::format("sphere {{ <0, 0, 0>, {} }}", num(outer));
    s += fmt::format(
        "// True displacement: the surface |q| = R + A h(base point of q).\n"
        "// max_gradient = sqrt(1 + (A max|grad h| R/(R - A max|h|))^2) * 1.05, an upper bound\n"
        "// of |grad F| near the surface plus 5% for rounding.\n"
        "isosurface {{\n  function {{ {} }}\n  contained_by {{ {} }}\n  threshold 0\n"
        "  accuracy 1e-5\n  max_gradient {}\n{}{}  {}\n}}\n",
        function, container, num(1.05 * gradient), cylinder && !shape.caps ? "  open\n" : "",
        texture, matrix(place));
    out.sdl = std::move(s);
    return out;
  }

  std::string normal;
  if (scene.representation == Representation::kBump && has_height) {
    // POV-Ray: Ns = normalize(N - (2/15) bump_size grad f). With
    // f = 0.5 + C h, bump_size = 7.5 A / C gives N - A grad h; C keeps f in
    // (0.1, 0.9), away from the pattern's wrap at 1.
    const double c = 0.4 / max_h;
    normal = fmt::format(
        "  normal {{\n    function {{ 0.5 + {} * {} }}\n"
        "    bump_size {}\n    accuracy 1e-4\n  }}\n",
        num(c), projected_h, num(7.5 * amplitude / c));
  }
  if (cylinder)
    s += fmt::format("cylinder {{\n  <0, {}, 0>, <0, {}, 0>, {}\n{}{}{}  {}\n}}\n", num(-half),
                     num(half), num(r), shape.caps ? "" : "  open\n", texture, normal,
                     matrix(place));
  else
    s += fmt::format("sphere {{\n  <0, 0, 0>, {}\n{}{}  {}\n}}\n", num(r), texture, normal,
                     matrix(place));
  out.sdl = std::move(s);
  return out;
}

}  // namespace penumbra
