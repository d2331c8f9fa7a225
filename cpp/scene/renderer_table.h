// The one table of renderers: what each is, where it comes from, and what it
// can render. The exporters, the study's "missing" rows, the command line's
// choices, `penumbra renderers` and the README all read it; render_with
// (renderers/renderers.h) is the one switch that runs them.
//
// Adding a renderer: an enumerator and a row here, an exporter in export/,
// a case in render_with and in pixel_code_digest (renderers/renderers.cpp).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/shadow_origin.h"
#include "core/terminator.h"
#include "scene/scene.h"

namespace penumbra {

enum class RendererKind { kEvaluator, kPovray, kBlender };

struct RendererInfo {
  RendererKind kind;
  const char* id;    // what users type and reports print: "povray"
  const char* name;  // "POV-Ray 3.7"
  // External renderers: the Debian package, the executable it installs and
  // the environment variable that points Penumbra at another one. Empty for
  // the built-in evaluator.
  const char* debian_package;
  const char* executable;
  const char* executable_variable;
  // A line of `EXECUTABLE --version` that contains this names the version.
  const char* version_marker;
  const char* note;  // how it renders bump and the ground truth (reports, docs)
  // Terminator methods (scene /terminator/method) per representation; the
  // evaluator offers every method of the method table.
  bool all_methods;
  std::vector<TerminatorMethod> bump_methods;
  std::vector<TerminatorMethod> other_methods;  // smooth and displacement
  const char* methods_why_not;                  // why the others are missing
  // Shadow-ray offsets (scene /offset/method).
  bool all_offsets;
  std::vector<OffsetMethod> offsets;
  const char* offsets_why_not;
  bool props;                       // extra spheres in the scene (/props)
  const char* props_why_not;        // "" when props are offered
  bool specular;                    // the GGX lobe (/material/specular_weight > 0)
  const char* specular_why_not;     // "" when it is offered
  bool height_maps;                 // /height/type "height-map"
  const char* height_maps_why_not;  // "" when they are offered
  bool normal_maps;                 // /height/type "normal-map"
  const char* normal_maps_why_not;  // "" when they are offered
  bool plane;                       // /shape/type "plane"
  const char* plane_why_not;        // "" when it is offered
};

// Every renderer, in the order reports list them.
const std::vector<RendererInfo>& renderer_table();
const RendererInfo& renderer_info(RendererKind r);
const std::vector<RendererKind>& all_renderers();
const char* to_string(RendererKind r);
std::optional<RendererKind> renderer_from_id(const std::string& id);
// "\"evaluator\", \"povray\" or \"blender\"": for error messages.
std::string renderer_choices();

// What a renderer can render, from the table.
std::vector<TerminatorMethod> methods_offered(RendererKind r, Representation representation);
std::vector<OffsetMethod> offsets_offered(RendererKind r);
bool offers(RendererKind r, Representation representation, TerminatorMethod method);
bool offers(RendererKind r, OffsetMethod offset);

}  // namespace penumbra
