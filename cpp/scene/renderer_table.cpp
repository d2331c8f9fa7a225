#include "scene/renderer_table.h"

#include <algorithm>

namespace penumbra {

const std::vector<RendererInfo>& renderer_table() {
  static const std::vector<RendererInfo> table{
      {RendererKind::kEvaluator,
       "evaluator",
       "Penumbra's reference evaluator",
       "",
       "",
       "",
       "penumbra",
       "reference evaluator: analytic shapes, exact displaced normals",
       /*all_methods=*/true,
       {},
       {},
       "",
       /*all_offsets=*/true,
       {},
       "",
       /*props=*/true,
       "",
       /*specular=*/true,
       "",
       /*height_maps=*/true,
       "",
       /*normal_maps=*/true,
       "",
       /*plane=*/true,
       ""},
      {RendererKind::kPovray,
       "povray",
       "POV-Ray 3.7",
       "povray",
       "povray",
       "PENUMBRA_POVRAY",
       "POV-Ray 3",
       "POV-Ray 3.7: bump via normal{function} (image height maps: the same cubic B-spline as "
       "SDL functions over nearest-texel lookups), ground truth via isosurface (image maps and "
       "the plane: the evaluator's displaced grid as a mesh2)",
       false,
       {TerminatorMethod::kNone},
       {TerminatorMethod::kNone},
       "POV-Ray has no shadow-terminator method (raw bump only)",
       false,
       {OffsetMethod::kNone},
       "POV-Ray 3.7 has no shadow-ray offset: mesh2 with normal_vectors shows the artifact "
       "(shadow line artifact, FS#242)",
       false,
       "props (extra spheres) are evaluator-only",
       false,
       "the GGX lobe is evaluator-only: the POV-Ray export is Lambertian (its specular and "
       "phong highlights are other models)",
       /*height_maps=*/true,
       "",
       /*normal_maps=*/false,
       "POV-Ray 3.7 has no tangent-space normal-map input: its normal patterns perturb the "
       "normal by the gradient of a scalar function, which a normal map does not give",
       /*plane=*/true,
       ""},
      {RendererKind::kBlender,
       "blender",
       "Blender 3.4 Cycles",
       "blender",
       "blender",
       "PENUMBRA_BLENDER",
       "Blender ",
       "Blender 3.4 Cycles: bump via ray-differential finite differences, ground truth via a "
       "displaced mesh; its chiang2019 is the Bump node, which is cycles34 (Chiang's term "
       "against Ni after ensure_valid_reflection turns the bumped normal towards Ng at grazing "
       "views); both ids render the same Blender scene",
       false,
       {TerminatorMethod::kNone, TerminatorMethod::kChiang2019, TerminatorMethod::kCycles34,
        TerminatorMethod::kShadingOffset},
       {TerminatorMethod::kNone, TerminatorMethod::kShadingOffset},
       "Blender Cycles 3.4 offers only none, chiang2019 and cycles34 (both the Bump node: Cycles "
       "3.4's own term) and shading-offset",
       false,
       {OffsetMethod::kNone, OffsetMethod::kCyclesGeometryOffset},
       "Blender Cycles 3.4 offers only its geometry offset",
       false,
       "props (extra spheres) are evaluator-only",
       false,
       "the GGX lobe is evaluator-only: the Blender export is Lambertian (Cycles' Glossy BSDF "
       "uses Fresnel and multiple-scattering options the evaluator does not model)",
       /*height_maps=*/true,
       "",
       /*normal_maps=*/true,
       "",
       /*plane=*/true,
       ""},
  };
  return table;
}

const RendererInfo& renderer_info(RendererKind r) {
  for (const RendererInfo& info : renderer_table())
    if (info.kind == r) return info;
  return renderer_table().front();  // unreachable: every enumerator has a row
}

const std::vector<RendererKind>& all_renderers() {
  static const std::vector<RendererKind> all = [] {
    std::vector<RendererKind> kinds;
    for (const RendererInfo& info : renderer_table()) kinds.push_back(info.kind);
    return kinds;
  }();
  return all;
}

const char* to_string(RendererKind r) {
  return renderer_info(r).id;
}

std::optional<RendererKind> renderer_from_id(const std::string& id) {
  for (const RendererInfo& info : renderer_table())
    if (id == info.id) return info.kind;
  return std::nullopt;
}

std::string renderer_choices() {
  std::string text;
  const auto& table = renderer_table();
  for (std::size_t i = 0; i < table.size(); ++i)
    text += (i == 0                  ? ""
             : i + 1 == table.size() ? " or "
                                     : ", ") +
            std::string("\"") + table[i].id + "\"";
  return text;
}

std::vector<TerminatorMethod> methods_offered(RendererKind r, Representation representation) {
  const RendererInfo& info = renderer_info(r);
  if (!info.all_methods)
    return representation == Representation::kBump ? info.bump_methods : info.other_methods;
  std::vector<TerminatorMethod> all;
  for (const MethodInfo& m : all_methods()) all.push_back(m.method);
  return all;
}

std::vector<OffsetMethod> offsets_offered(RendererKind r) {
  const RendererInfo& info = renderer_info(r);
  if (!info.all_offsets) return info.offsets;
  std::vector<OffsetMethod> all;
  for (const OffsetMethodInfo& m : all_offset_methods()) all.push_back(m.method);
  return all;
}

bool offers(RendererKind r, Representation representation, TerminatorMethod method) {
  const auto list = methods_offered(r, representation);
  return std::find(list.begin(), list.end(), method) != list.end();
}

bool offers(RendererKind r, OffsetMethod offset) {
  const auto list = offsets_offered(r);
  return std::find(list.begin(), list.end(), offset) != list.end();
}

}  // namespace penumbra
