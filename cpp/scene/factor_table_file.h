// The file a factor table lives in: table.json, which `penumbra fit` writes
// and the `fitted` method reads (/terminator/parameters/table). Read
// strictly, like scenes: a wrong key, axis or value count is an error naming
// the file and the JSON pointer.
#pragma once

#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "core/factor_table.h"

namespace penumbra {

// {"grid": [{"input", "min_deg", "max_deg", "step_deg"}...], "values": [...]}
// plus whatever `extra` holds (the fit's smoothness, a note).
nlohmann::json factor_table_json(const FactorTable& table,
                                 const nlohmann::json& extra = nlohmann::json::object());
nlohmann::json factor_grid_json(const FactorGrid& grid);

// The table in `path`; values finite and in [0, kMaxFactorValue], at most
// kMaxFactorCells cells, axes distinct, steps dividing their ranges.
std::shared_ptr<const FactorTable> load_factor_table(const std::string& path);

// A content digest of the grid and values (32 hex digits): what enters a
// render's cache key in place of the table's path.
std::string factor_table_digest(const FactorTable& table);

inline constexpr double kMaxFactorValue = 16.0;
inline constexpr int kMaxFactorCells = 1 << 22;

}  // namespace penumbra
