// The reference evaluator (cpp/evaluator/) behind the renderer interface.
#pragma once

#include "renderers/renderer.h"

namespace penumbra {

const RendererEntry& evaluator_entry();

}  // namespace penumbra
