#include "analysis/factor_emit.h"

#include <algorithm>
#include <span>
#include <vector>

#include <fmt/format.h>

#include "core/vec.h"

namespace penumbra {
namespace {

struct Dialect {
  const char* real;        // scalar type
  const char* int_type;    // loop and index type
  const char* array_open;  // before an array's values
  const char* array_close;
  const char* constant;  // qualifier of a table
  const char* acos;
  const char* floor;
  const char* to_int;   // opens a conversion to int, closed by ")"
  const char* to_real;  // the same to the scalar type
};

Dialect dialect(EmitLanguage language) {
  switch (language) {
    case EmitLanguage::kC:
      return {"double", "int", "{", "}", "static const", "acos", "floor", "(int)(", "(double)("};
    case EmitLanguage::kGlsl:
      return {"float", "int", "", "", "const", "acos", "floor", "int(", "float("};
    case EmitLanguage::kOsl:
      return {"float", "int", "{", "}", "", "acos", "floor", "(int)(", "(float)("};
  }
  return {};
}

// A comment line's text: nothing that could end the comment or the line.
std::string comment_text(std::string_view text) {
  std::string out;
  for (const char c : text)
    out += (c >= ' ' && c <= '~' && c != '*' && c != '/' && c != '\\') ? c : ' ';
  return out;
}

std::string real_literal(double x, EmitLanguage language) {
  // C: 17 significant digits round-trip a double; float: 9 a float.
  std::string s = language == EmitLanguage::kC ? fmt::format("{:.17g}", x)
                                               : fmt::format("{:.9g}", static_cast<float>(x));
  if (s.find_first_of(".en") == std::string::npos) s += ".0";
  return s;
}

std::string array(const char* name, std::span<const double> values, const Dialect& d,
                  EmitLanguage language) {
  std::string body;
  for (std::size_t i = 0; i < values.size(); ++i)
    body += (i % 6 == 0 ? "\n    " : " ") + real_literal(values[i], language) +
            (i + 1 < values.size() ? "," : "");
  if (language == EmitLanguage::kGlsl)
    return fmt::format("const float {}[{}] = float[{}]({});\n", name, values.size(), values.size(),
                       body);
  return fmt::format("{} {} {}[{}] = {}{}{};\n", d.constant, d.real, name, values.size(),
                     d.array_open, body, d.array_close);
}

const char* input_name(FactorInput input) {
  return name_of(std::span<const EnumName<FactorInput>>(kFactorInputNames), input);
}

// The axes in argument order (light, deviation, shading, view), with their
// position in the grid.
std::vector<std::size_t> argument_order(const FactorGrid& grid) {
  std::vector<std::size_t> order(grid.axes.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return grid.axes[a].input < grid.axes[b].input; });
  return order;
}

std::string signature(const FactorGrid& grid, const Dialect& d, EmitLanguage language) {
  std::string args;
  for (const std::size_t a : argument_order(grid))
    args += fmt::format("{}{} cos_{}", args.empty() ? "" : ", ", d.real,
                        input_name(grid.axes[a].input));
  return fmt::format("{}{} penumbra_fitted_g({})", language == EmitLanguage::kC ? "static " : "",
                     d.real, args);
}

// Per axis: the angle in degrees, the clamped position between centres
// (as FactorGrid::nodes), or G = 1 outside the grid.
std::string axis_code(const FactorGrid& grid, const Dialect& d, EmitLanguage language) {
  std::string code;
  const auto lit = [&](double x) { return real_literal(x, language); };
  for (std::size_t a = 0; a < grid.axes.size(); ++a) {
    const FactorAxis& axis = grid.axes[a];
    const int n = axis.cells();
    code += fmt::format(
        "  {{\n"
        "    {r} c = cos_{name} < -1.0 ? -1.0 : (cos_{name} > 1.0 ? 1.0 : cos_{name});\n"
        "    {r} u = ({acos}(c) * {deg} - {min}) / {step};\n"
        "    if (!(u >= 0.0) || u >= {nr}) return 1.0;\n"
        "    {r} p = u - 0.5;\n"
        "    p = p < 0.0 ? 0.0 : (p > {last} ? {last} : p);\n"
        "    lower[{a}] = {to_int}{floor}(p));\n"
        "    if (lower[{a}] > {nm1}) lower[{a}] = {nm1};\n"
        "    upper[{a}] = lower[{a}] + 1 > {nm1} ? {nm1} : lower[{a}] + 1;\n"
        "    t[{a}] = p - {to_real}lower[{a}]);\n"
        "  }}\n",
        fmt::arg("r", d.real), fmt::arg("name", input_name(axis.input)), fmt::arg("acos", d.acos),
        fmt::arg("deg", lit(180.0 / kPi)), fmt::arg("min", lit(axis.min_deg)),
        fmt::arg("step", lit(axis.step_deg)), fmt::arg("nr", lit(double(n))),
        fmt::arg("last", lit(double(n - 1))), fmt::arg("to_int", d.to_int),
        fmt::arg("to_real", d.to_real), fmt::arg("floor", d.floor), fmt::arg("a", a),
        fmt::arg("nm1", n - 1));
  }
  return code;
}

std::string body(const FactorGrid& grid, const Dialect& d, EmitLanguage language) {
  const std::size_t k = grid.axes.size();
  std::string code =
      fmt::format("{{\n  {i} lower[{k}]; {i} upper[{k}]; {r} t[{k}];\n", fmt::arg("i", d.int_type),
                  fmt::arg("k", k), fmt::arg("r", d.real));
  code += axis_code(grid, d, language);
  // C: the corners' weights multiplied in axis order, as FactorGrid::nodes
  // does, so that the sum matches FactorTable::at to rounding.
  code += fmt::format(
      "  {r} g = 0.0;\n"
      "  for ({i} corner = 0; corner < {corners}; ++corner) {{\n"
      "    {r} w = 1.0;\n"
      "    {i} index = 0;\n"
      "    {i} stride = 1;\n"
      "    for ({i} a = 0; a < {k}; ++a) {{\n"
      "      {i} up = (corner >> a) & 1;\n"
      "      w *= up == 1 ? t[a] : 1.0 - t[a];\n"
      "      index += (up == 1 ? upper[a] : lower[a]) * stride;\n"
      "      stride *= penumbra_fitted_cells[a];\n"
      "    }}\n"
      "    if (w > 0.0) g += w * penumbra_fitted_values[index];\n"
      "  }}\n"
      "  return g;\n"
      "}}\n",
      fmt::arg("r", d.real), fmt::arg("i", d.int_type), fmt::arg("corners", 1 << k),
      fmt::arg("k", k));
  return code;
}

std::string cells_array(const FactorGrid& grid, const Dialect& d, EmitLanguage language) {
  std::string values;
  for (std::size_t a = 0; a < grid.axes.size(); ++a)
    values += fmt::format("{}{}", a ? ", " : "", grid.axes[a].cells());
  if (language == EmitLanguage::kGlsl)
    return fmt::format("const int penumbra_fitted_cells[{}] = int[{}]({});\n", grid.axes.size(),
                       grid.axes.size(), values);
  return fmt::format("{} {} penumbra_fitted_cells[{}] = {}{}{};\n", d.constant, d.int_type,
                     grid.axes.size(), d.array_open, values, d.array_close);
}

std::string header(const FactorTable& table, EmitLanguage language, std::string_view provenance) {
  std::string axes;
  for (const FactorAxis& a : table.grid.axes)
    axes += fmt::format(" *   {} angle in [{}, {}) degrees, cells of {} degrees\n",
                        input_name(a.input), a.min_deg, a.max_deg, a.step_deg);
  return fmt::format(
      "/* Penumbra's fitted terminator factor G ({}).\n"
      " * {}\n"
      " * Multiply the light of the lobes the fit scaled by G. Arguments: cosines\n"
      " * cos_light = <Ng,wi>, cos_deviation = <Ng,Ns>, cos_shading = <Ns,wi>,\n"
      " * cos_view = <Ng,wo> (those the grid uses). Grid, first axis fastest:\n"
      "{}"
      " * G at the cells' centres, multilinear between them, constant from the\n"
      " * last centre to the grid's edge, 1 outside the grid. */\n",
      language == EmitLanguage::kC      ? "C99, double"
      : language == EmitLanguage::kGlsl ? "GLSL 3.30+, float"
                                        : "OSL, float",
      comment_text(provenance), axes);
}

}  // namespace

std::string_view emit_extension(EmitLanguage language) {
  switch (language) {
    case EmitLanguage::kC:
      return ".c";
    case EmitLanguage::kGlsl:
      return ".glsl";
    case EmitLanguage::kOsl:
      return ".osl";
  }
  return "";
}

std::string emit_factor_table(const FactorTable& table, EmitLanguage language,
                              std::string_view provenance) {
  const Dialect d = dialect(language);
  std::string code = header(table, language, provenance);
  if (language == EmitLanguage::kC) code += "#include <math.h>\n\n";
  const std::string tables = cells_array(table.grid, d, language) +
                             array("penumbra_fitted_values", table.values, d, language);
  if (language == EmitLanguage::kOsl)  // OSL has no global variables
    return code + signature(table.grid, d, language) + "\n{\n" + tables +
           body(table.grid, d, language) + "}\n";
  return code + tables + "\n" + signature(table.grid, d, language) + "\n" +
         body(table.grid, d, language);
}

}  // namespace penumbra
