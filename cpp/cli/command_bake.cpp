// `penumbra bake`: a scene's analytic height function as a height map of the
// plane, or as a height or normal map over its shape (core/surface_map.h);
// or its normal map integrated into a height map (core/normal_integration.h).
#include <stdexcept>

#include <fmt/format.h>

#include "cli/command.h"
#include "core/normal_integration.h"
#include "core/surface_map.h"
#include "image/bump_maps.h"
#include "image/image_io.h"
#include "util/strict_json.h"

namespace penumbra {

namespace {

struct BakeArgs {
  std::string scene, output;
  std::vector<std::string> sets;
  int size = 1024;
  double extent = 1.0;
  std::string on = "plane";     // "plane": z = 0 over [0, extent)^2; "shape": the shape's (u, v)
  std::string kind = "height";  // "height" or "normal" (shape only)
  bool integrate = false;       // the scene's normal map integrated into a height map
};

// --on shape: the map over the shape's (u, v), texels as square as the
// parameterisation allows (on the sphere, at the equator).
int bake_on_shape(const BakeArgs& a, const Scene& scene, std::ostream& out) {
  const Shape& s = scene.shape;
  const int rows = shape_map_rows(s, a.size, kMaxImageSize);
  const MapKind kind = a.kind == "normal" ? MapKind::kNormal : MapKind::kHeight;
  const Image map =
      bake_surface_map(s, scene.height.function, scene.height.amplitude, a.size, rows, kind);
  write_exr(map, a.output, {{"penumbra:baked_from", a.scene}});
  const std::string use =
      kind == MapKind::kHeight
          ? fmt::format(R"({{"type": "height-map", "file": "{}", "amplitude": 1}})", a.output)
          : fmt::format(R"({{"type": "normal-map", "file": "{}"}})", a.output);
  out << fmt::format("wrote {} ({}x{} over the {}'s (u, v)): use it as /height = {}\n", a.output,
                     a.size, rows, name_of<ShapeType>(kShapeTypeNames, s.type), use);
  return kExitOk;
}

// --integrate: the scene's normal map as the height map whose bump normal it
// is, over the same (u, v) (core/normal_integration.h).
int bake_integrated(const BakeArgs& a, const LoadedScene& loaded, std::ostream& out) {
  const Scene& scene = loaded.scene;
  if (!scene.height.normal_map())
    throw InputError(loaded.origin, "/height/type",
                     fmt::format("expected \"normal-map\" to integrate, got \"{}\"",
                                 to_string(scene.height.family)));
  check_extension(a.output, ".exr", "-o", ": an integrated height map is float OpenEXR");
  check_writable(a.output);
  const SurfaceMap& map = *scene.height.map;
  if (static_cast<long long>(map.width) * map.height > kMaxIntegratedTexels)
    throw InputError(loaded.origin, "/height/file",
                     fmt::format("expected a normal map of at most {} texels to integrate, got "
                                 "{}x{} (the solve holds about 56 bytes a texel)",
                                 kMaxIntegratedTexels, map.width, map.height));
  const MapLengths lengths = scene.shape.type == ShapeType::kMesh
                                 ? mesh_map_lengths(*scene.shape.mesh)
                                 : map_lengths(scene.shape);
  if (!(lengths.u > 0.0) || !(lengths.v > 0.0))
    throw InputError(loaded.origin, "/shape",
                     "expected a shape whose (u, v) have a length (every triangle's UV area is "
                     "zero)");
  // A map tiled n times spans 1/n of the shape's u (v) lines.
  const IntegratedHeight h =
      integrate_normal_map(map, lengths.u / map.tiles_u, lengths.v / map.tiles_v);
  Image image;
  image.width = h.width;
  image.height = h.height;
  image.channels = {"Y"};
  image.pixels = h.heights;
  if (!h.converged)
    throw std::runtime_error(
        fmt::format("{}: the integration of {}x{} texels did not converge in {} conjugate-gradient "
                    "iterations; nothing written",
                    a.scene, h.width, h.height, h.iterations));
  write_exr(image, a.output, {{"penumbra:integrated_from", a.scene}});
  out << fmt::format(
      "wrote {} ({}x{}, heights in scene units over the map's (u, v), spanning {:.6g} x {:.6g} "
      "scene units; {} conjugate-gradient iterations): use /height = {{\"type\": \"height-map\", "
      "\"file\": \"{}\", \"amplitude\": 1}}\n"
      "the map's normals against the integrated height's (the part of the map no height gives): "
      "RMS {:.3g} deg, largest {:.3g} deg over {} texels{}\n",
      a.output, h.width, h.height, lengths.u / map.tiles_u, lengths.v / map.tiles_v, h.iterations,
      a.output, h.rms_angle_deg, h.largest_angle_deg, h.heights.size(),
      h.clamped > 0 ? fmt::format("; {} texels steeper than {:.0f} deg were clamped", h.clamped,
                                  std::acos(kMinNormalZ) * 180.0 / kPi)
                    : "");
  return kExitOk;
}

int bake(const BakeArgs& a, std::ostream& out) {
  SceneArgs scene_args;
  scene_args.sets = a.sets;
  const LoadedScene loaded = read_scene(a.scene, scene_args);
  const Scene& scene = loaded.scene;
  if (a.integrate) return bake_integrated(a, loaded, out);
  if (scene.height.family == HeightFamily::kNone || scene.height.map)
    throw InputError(loaded.origin, "/height",
                     fmt::format("expected an analytic height function to bake, got \"{}\"",
                                 to_string(scene.height.family)));
  check_extension(a.output, ".exr", "-o", ": a baked map is float OpenEXR");
  if (a.kind == "normal" && a.on != "shape")
    throw InputError("--kind", "", "a normal map is baked over a shape: add --on shape");
  // A mesh's UVs may overlap or leave gaps, so "the shape's (u, v)" has no
  // single point per texel to bake from.
  if (a.on == "shape" && scene.shape.type == ShapeType::kMesh)
    throw InputError(loaded.origin, "/shape/type",
                     "expected an analytic shape to bake over (a mesh's UVs need not cover the "
                     "map once); bake --on plane and lay the map over the mesh's UVs");
  check_writable(a.output);
  if (a.on == "shape") return bake_on_shape(a, scene, out);
  const Image map =
      bake_height_map(scene.height.function, scene.height.amplitude, a.size, a.extent);
  // A huge extent overflows the height function's phase (sin(Inf) is NaN).
  if (const std::size_t bad = count_nonfinite(map); bad > 0)
    throw InputError(loaded.origin, "/height",
                     fmt::format("--extent {:.6g}: {} of {} baked heights are NaN or Inf; expected "
                                 "an extent over which the height function stays finite",
                                 a.extent, bad, map.pixels.size()));
  write_exr(map, a.output, {{"penumbra:baked_from", a.scene}});
  const double texel = a.extent / a.size;
  out << fmt::format(
      "wrote {} ({}x{}, heights in scene units, texel {:.6g} scene units): use penumbra pyramid "
      "{} --texel-size {:.6g} --edge {}\n",
      a.output, a.size, a.size, texel, a.output, texel,
      "wrap (if the extent holds whole periods) or clamp");
  return kExitOk;
}

}  // namespace

Command add_bake_command(CLI::App& app, SharedOptions&) {
  auto a = std::make_shared<BakeArgs>();
  CLI::App* cmd = app.add_subcommand(
      "bake",
      "a scene's analytic height function (/height) as a height map of the plane z = 0, or as a "
      "height or normal map over its shape's (u, v)");
  cmd->add_option("scene", a->scene, "scene file (JSON)")->required();
  cmd->add_option("-o,--output", a->output, "height map (.exr)")->required();
  cmd->add_option("--set", a->sets, "JSON-pointer override, /pointer=VALUE");
  cmd->add_option("--size", a->size, "texels a side")
      ->check(CLI::Range(1, 16384))
      ->capture_default_str();
  cmd->add_option("--extent", a->extent, "side of the baked square, scene units")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--on", a->on,
                  "plane: the plane z = 0 (for penumbra pyramid and filtering); shape: the "
                  "scene's cylinder or sphere over its map parameters (u, v), --size texels "
                  "around and as many along v as keep texels square")
      ->check(CLI::IsMember({"plane", "shape"}))
      ->capture_default_str();
  cmd->add_option("--kind", a->kind,
                  "height: amplitude * h in scene units (channel Y); normal: the exact bump "
                  "normal as a tangent-space normal map (R, G, B = 0.5 n + 0.5; --on shape only)")
      ->check(CLI::IsMember({"height", "normal"}))
      ->capture_default_str();
  cmd->add_flag("--integrate", a->integrate,
                "instead: integrate the scene's normal map (/height, a normal-map) into the "
                "height map whose bump normal it is, over the same (u, v) of the scene's shape "
                "(a mesh: its mean UV scale), and say how far the map is from any height's "
                "normals");
  return {cmd, [a](const CommandContext& c) { return bake(*a, c.out); }};
}

}  // namespace penumbra
