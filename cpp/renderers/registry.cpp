#include "renderers/registry.h"

#include <iterator>
#include <stdexcept>

#include "renderers/evaluator_entry.h"
#include "renderers/external/blender/blender.h"
#include "renderers/external/povray/povray.h"

namespace penumbra {

namespace {

struct Registered {
  RendererKind kind;
  const RendererEntry& (*entry)();
};

// Every renderer's entry, in the enumerators' order, so that an enumerator
// is its row's index.
constexpr Registered kRegistry[] = {
    {RendererKind::kEvaluator, evaluator_entry},
    {RendererKind::kPovray, povray_entry},
    {RendererKind::kBlender, blender_entry},
};

constexpr bool rows_in_enumerator_order() {
  for (std::size_t k = 0; k < std::size(kRegistry); ++k)
    if (static_cast<std::size_t>(kRegistry[k].kind) != k) return false;
  return true;
}
static_assert(rows_in_enumerator_order(), "a row of kRegistry out of RendererKind's order");

}  // namespace

const RendererEntry& renderer(RendererKind r) {
  const auto k = static_cast<std::size_t>(r);
  // An enumerator without its row: a programming error, not bad input.
  if (k >= std::size(kRegistry)) throw std::logic_error("a RendererKind without a registry row");
  return kRegistry[k].entry();
}

const RendererInfo& renderer_info(RendererKind r) {
  return renderer(r).info;
}

const std::vector<RendererKind>& all_renderers() {
  static const std::vector<RendererKind> all = [] {
    std::vector<RendererKind> kinds;
    for (const Registered& row : kRegistry) kinds.push_back(row.kind);
    return kinds;
  }();
  return all;
}

const char* to_string(RendererKind r) {
  return renderer_info(r).id;
}

std::optional<RendererKind> renderer_from_id(const std::string& id) {
  for (RendererKind r : all_renderers())
    if (id == renderer_info(r).id) return r;
  return std::nullopt;
}

std::string renderer_choices(const char* quote) {
  std::string text;
  const auto& all = all_renderers();
  for (std::size_t i = 0; i < all.size(); ++i)
    text += (i == 0                ? ""
             : i + 1 == all.size() ? " or "
                                   : ", ") +
            std::string(quote) + to_string(all[i]) + quote;
  return text;
}

std::vector<TerminatorMethod> methods_offered(RendererKind r, Representation representation) {
  return methods_offered(renderer_info(r), representation);
}

std::vector<OffsetMethod> offsets_offered(RendererKind r) {
  return offsets_offered(renderer_info(r));
}

bool offers(RendererKind r, Representation representation, TerminatorMethod method) {
  return offers(renderer_info(r), representation, method);
}

bool offers(RendererKind r, OffsetMethod offset) {
  return offers(renderer_info(r), offset);
}

}  // namespace penumbra
