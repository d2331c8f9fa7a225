// The registry of renderers: an enumerator each here and its row in the
// table of entries (registry.cpp), which every list of renderers reads
// (studies, the command line's choices, `penumbra renderers`,
// docs/renderers.md). What a renderer is and does is its entry
// (renderers/renderer.h); nothing switches over renderers.
//
// Adding a renderer: its folder renderers/external/<id>/ with its entry, an
// enumerator here and its row in the table (docs/extending.md).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "renderers/renderer.h"

namespace penumbra {

// In the order reports list them.
enum class RendererKind { kEvaluator, kPovray, kBlender };

const RendererEntry& renderer(RendererKind r);
const RendererInfo& renderer_info(RendererKind r);
// Every renderer, in the enumerators' order.
const std::vector<RendererKind>& all_renderers();
const char* to_string(RendererKind r);
std::optional<RendererKind> renderer_from_id(const std::string& id);
// "\"evaluator\", \"povray\" or \"blender\"" (ids between `quote`s): for
// messages.
std::string renderer_choices(const char* quote = "\"");

// What a renderer can render, from its row.
std::vector<TerminatorMethod> methods_offered(RendererKind r, Representation representation);
std::vector<OffsetMethod> offsets_offered(RendererKind r);
bool offers(RendererKind r, Representation representation, TerminatorMethod method);
bool offers(RendererKind r, OffsetMethod offset);

}  // namespace penumbra
