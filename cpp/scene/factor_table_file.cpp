#include "scene/factor_table_file.h"

#include <cmath>
#include <span>

#include <fmt/format.h>

#include "util/hash.h"
#include "util/json_reader.h"
#include "util/strict_json.h"

namespace penumbra {
using nlohmann::json;

namespace {

FactorAxis read_axis(Reader a) {
  FactorAxis axis;
  axis.input = a.choice<FactorInput>("input", kFactorInputNames);
  const auto angle = [](double x) { return x >= 0.0 && x <= 180.0; };
  axis.min_deg = a.number("min_deg", angle, "in [0, 180] degrees");
  axis.max_deg = a.number("max_deg", angle, "in [0, 180] degrees");
  if (!(axis.max_deg > axis.min_deg))
    a.fail("max_deg", fmt::format("expected more than min_deg ({})", axis.min_deg));
  axis.step_deg = a.number(
      "step_deg", [](double x) { return x > 0.0 && x <= 180.0; }, "in (0, 180] degrees");
  const double cells = (axis.max_deg - axis.min_deg) / axis.step_deg;
  if (std::abs(cells - std::round(cells)) > 1e-9 * cells || std::round(cells) < 1.0)
    a.fail("step_deg", fmt::format("expected a step that divides max_deg - min_deg = {} degrees",
                                   axis.max_deg - axis.min_deg));
  a.finish();
  return axis;
}

FactorGrid read_grid(Reader& r) {
  const json& list = r.nonempty_array("grid", "axes");
  if (list.size() > kMaxFactorAxes)
    r.fail("grid", fmt::format("expected at most {} axes, got {}", kMaxFactorAxes, list.size()));
  FactorGrid grid;
  double cells = 1.0;
  for (std::size_t i = 0; i < list.size(); ++i) {
    grid.axes.push_back(read_axis(r.item("grid", i)));
    for (std::size_t k = 0; k < i; ++k)
      if (grid.axes[k].input == grid.axes[i].input)
        r.fail_item("grid", i, "expected each input on one axis only");
    cells *= double(grid.axes[i].cells());
  }
  if (cells > double(kMaxFactorCells))
    r.fail("grid", fmt::format("expected at most {} cells, got {}", kMaxFactorCells, cells));
  return grid;
}

}  // namespace

json factor_grid_json(const FactorGrid& grid) {
  json axes = json::array();
  for (const FactorAxis& a : grid.axes)
    axes.push_back(
        {{"input",
          std::string(name_of(std::span<const EnumName<FactorInput>>(kFactorInputNames), a.input))},
         {"min_deg", a.min_deg},
         {"max_deg", a.max_deg},
         {"step_deg", a.step_deg}});
  return axes;
}

json factor_table_json(const FactorTable& table, const json& extra) {
  json j = extra;
  j["grid"] = factor_grid_json(table.grid);
  j["values"] = table.values;
  return j;
}

std::shared_ptr<const FactorTable> load_factor_table(const std::string& path) {
  const json doc = read_json_file(path);
  Reader r(doc, "", path);
  auto table = std::make_shared<FactorTable>();
  table->grid = read_grid(r);
  const json& values = r.at("values");
  const auto n = static_cast<std::size_t>(table->grid.cells());
  if (!values.is_array() || values.size() != n)
    r.fail("values", fmt::format("expected an array of {} numbers (the grid's cells), got {}", n,
                                 Reader::describe(values)));
  table->values.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const json& v = values[i];
    if (!v.is_number() || !(v.get<double>() >= 0.0 && v.get<double>() <= kMaxFactorValue))
      r.fail_item("values", i,
                  fmt::format("expected a number in [0, {}], got {}", kMaxFactorValue,
                              Reader::describe(v)));
    table->values.push_back(v.get<double>());
  }
  // What penumbra fit writes beside the table: read, so finish() accepts them.
  r.has("smoothness");
  r.has("note");
  r.finish();
  return table;
}

std::string factor_table_digest(const FactorTable& table) {
  std::vector<double> header;
  for (const FactorAxis& a : table.grid.axes)
    header.insert(header.end(),
                  {double(static_cast<int>(a.input)), a.min_deg, a.max_deg, a.step_deg});
  ContentDigest digest;
  digest.add(header.data(), header.size() * sizeof(double));
  digest.add(table.values.data(), table.values.size() * sizeof(double));
  return digest.hex();
}

}  // namespace penumbra
