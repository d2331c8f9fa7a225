// A fitted factor table as source code a renderer can paste: one function
// of the cosines the table's grid uses, returning G, with the table and the
// same multilinear interpolation as FactorTable::at (core/factor_table.h).
// Only numbers from the table enter the code, never user text.
#pragma once

#include <string>
#include <string_view>

#include "core/enum_names.h"
#include "core/factor_table.h"

namespace penumbra {

enum class EmitLanguage { kC, kGlsl, kOsl };
inline constexpr EnumName<EmitLanguage> kEmitLanguageNames[] = {
    {"c", EmitLanguage::kC}, {"glsl", EmitLanguage::kGlsl}, {"osl", EmitLanguage::kOsl}};

// The file extension an emitted function is written with (".c", ...).
std::string_view emit_extension(EmitLanguage language);

// The function `penumbra_fitted_g(cos_<input>...)`: one argument per axis of
// the grid, in the order light, deviation, shading, view, each the cosine of
// the angle core/factor_table.h names (cos_light = <Ng,wi>, cos_deviation =
// <Ng,Ns>, cos_shading = <Ns,wi>, cos_view = <Ng,wo>). C computes in double
// (FactorTable::at to rounding); GLSL and OSL in float. `provenance` goes
// into the leading comment (digits, letters and punctuation only are kept).
std::string emit_factor_table(const FactorTable& table, EmitLanguage language,
                              std::string_view provenance);

}  // namespace penumbra
