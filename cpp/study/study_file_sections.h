// Readers of the study file's sections beside the sweeps, /filtering and
// /interplay (their settings: study_file.h; their runners:
// study/filtering_study.h, study/interplay.h). load_study calls them.
#pragma once

#include <filesystem>

#include "study/study_file.h"
#include "util/json_reader.h"

namespace penumbra {

// /filtering; scene and map paths resolve against `base`, the study file's
// folder. InputError naming the file and pointer.
FilteringSection read_filtering_section(Reader section, const std::filesystem::path& base);

// /interplay; its scene resolves against `base`.
InterplaySection read_interplay_section(Reader section, const std::filesystem::path& base);

}  // namespace penumbra
