// Reading scenes from JSON: strict (unknown keys are errors), with errors that
// name the file, the JSON pointer and what was expected.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "scene/scene.h"
#include "util/strict_json.h"

namespace penumbra {

// "POINTER=VALUE" as given to --set: VALUE is JSON, or a bare string (UTF-8).
// InputError (bad input, exit 2) for invalid pointers and over-deep values.
struct Override {
  std::string pointer;
  nlohmann::json value;
};
Override parse_override(const std::string& text);

// Applies overrides in order; `origin` names the source in errors. Missing
// objects on the way are created; an array index past the end is an error.
// read_json_file (util/strict_json.h) reads the document strictly.
void apply_overrides(nlohmann::json& document, const std::vector<Override>& overrides,
                     const std::string& origin);

// A file name of this prefix ("blender:studiolights/world/forest.exr") is
// read from the installed Blender's data folder, found when the scene is
// read; resolve_map_files leaves it as it is.
inline constexpr char kBlenderDataPrefix[] = "blender:";
// Makes a relative /height/file, /terminator/parameters/table and
// /light/map relative to the folder of the scene file `scene_path` (as
// Mitsuba resolves scene resources), so that a scene finds its maps and
// tables from any working directory. load_scene does this.
void resolve_map_files(nlohmann::json& document, const std::string& scene_path);

// /terminator alone, `j` being its object: what pn.factor (python/) reads
// a method and its parameters with, so that they are checked as in a scene.
TerminatorSettings terminator_from_json(const nlohmann::json& j, const std::string& origin);
// /material and /offset alone, likewise (pn.factor's material, pn.offset).
Material material_from_json(const nlohmann::json& j, const std::string& origin);
OffsetSettings offset_from_json(const nlohmann::json& j, const std::string& origin);

// Validates and converts. `origin` is the file name used in error messages.
Scene scene_from_json(const nlohmann::json& document, const std::string& origin);
Scene load_scene(const std::string& path, const std::vector<Override>& overrides = {});

// Names used in JSON and reports.
const char* to_string(Representation r);
const char* to_string(HeightFamily f);

// Whether `path` names a scene file (.json) rather than a mesh file.
bool is_scene_file_name(const std::string& path);

// A scene for a mesh file given where a scene file is expected (`penumbra
// render asset.glb`): the mesh (absolute path) as the shape, seen along +z
// by an orthographic camera that frames its bounding box with a margin of
// 10 % (a square view, 256 x 256 px, 16 spp), lit by the sun from the calibration
// scenes' direction (towards the light (-1, 0.3, -0.2): a terminator crosses
// the view), albedo 0.8, the bump representation with the asset's own
// normal map where its materials name one (MeshSurface::normal_texture),
// no height otherwise (smooth until a height is set with --set). InputError
// naming the file when it is not a mesh Assimp reads. With `node`, the
// scene is of that node of the file (/shape/node), framed and shaded as
// the node's meshes are.
nlohmann::json asset_scene_document(const std::string& path, const std::string& node = "");

}  // namespace penumbra
