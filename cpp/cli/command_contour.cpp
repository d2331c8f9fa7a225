// `penumbra contour`: G over light angle x normal deviation for some methods
// (analysis/contour.h), as JSON, CSV and plots.
#include <cmath>
#include <filesystem>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "analysis/contour.h"
#include "cli/command.h"
#include "image/image_io.h"
#include "study/figures.h"

namespace penumbra {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

struct ContourArgs {
  std::vector<std::string> methods;
  std::string output = "results/contour";
  double step = 1.0;
};

// The grid as contour.json's document and contour.csv's text.
std::pair<json, std::string> contour_files(const std::vector<std::string>& ids,
                                           const std::vector<MethodSettings>& methods,
                                           const ContourGrid& grid) {
  json methods_json = json::array();
  std::string csv = "method,light_deg,deviation_deg,G\n";
  for (std::size_t k = 0; k < methods.size(); ++k) {
    // JSON has no NaN: an undefined effective factor is null (empty in CSV).
    json rows = json::array();
    for (const auto& row : grid.g[k]) {
      json r = json::array();
      for (double g : row) r.push_back(std::isfinite(g) ? json(g) : json(nullptr));
      rows.push_back(std::move(r));
    }
    methods_json.push_back(
        {{"id", ids[k]},
         {"effective", method_info(methods[k].method).kind != MethodKind::kFactor},
         {"G", std::move(rows)}});
    for (std::size_t i = 0; i < grid.deviation_deg.size(); ++i)
      for (std::size_t j = 0; j < grid.light_deg.size(); ++j) {
        const double g = grid.g[k][i][j];
        csv += fmt::format("{},{},{},{}\n", ids[k], grid.light_deg[j], grid.deviation_deg[i],
                           std::isfinite(g) ? fmt::format("{}", g) : std::string());
      }
  }
  json doc = {{"format", "penumbra-contour"},
              {"version", 1},
              {"geometry",
               "Ng = z, wi = (sin light, 0, cos light), Ns = (sin deviation, 0, "
               "cos deviation), wo = Ng; angles in degrees; G dimensionless; methods with "
               "effective = true: radiance / raw bump's radiance on a white Lambertian "
               "base, null where raw bump receives no light"},
              {"light_deg", grid.light_deg},
              {"deviation_deg", grid.deviation_deg},
              {"methods", methods_json}};
  return {std::move(doc), std::move(csv)};
}

int contour(const ContourArgs& a, std::ostream& out) {
  std::vector<MethodSettings> methods;
  for (const std::string& id : a.methods) {
    const auto m = method_from_id(id);
    if (!m)
      throw UsageError(fmt::format("--method: unknown method \"{}\" (see penumbra methods)", id));
    if (method_info(*m).needs_table)
      throw UsageError(fmt::format(
          "--method {}: its G is a table over the grid of penumbra fit; fit.json's pictures hold "
          "it at the cells' centres",
          id));
    if (method_info(*m).user_defined)
      throw UsageError(fmt::format(
          "--method {}: a user method is plotted in Python (penumbra.factor, docs/python.md)", id));
    methods.push_back({*m, 0.0, nullptr, nullptr, {}});
  }
  std::error_code ec;
  fs::create_directories(a.output, ec);
  if (ec || !fs::is_directory(a.output))
    throw OutputError(fmt::format("{}: cannot create the output folder", a.output));
  const auto [doc, csv] = contour_files(a.methods, methods, make_contour_grid(methods, a.step));
  const fs::path dir(a.output);
  write_text_file((dir / "contour.json").string(), doc.dump(1) + "\n");
  write_text_file((dir / "contour.csv").string(), csv);
  run_plot_script(
      {"contour", fs::absolute(dir / "contour.json").string(), fs::absolute(dir).string()},
      (dir / "contour.log").string());
  out << fmt::format(
      "wrote {0}/contour.json, {0}/contour.csv and contour plots (PNG, SVG, PDF) "
      "in {0}\n",
      a.output);
  return kExitOk;
}

}  // namespace

Command add_contour_command(CLI::App& app, SharedOptions&) {
  auto a = std::make_shared<ContourArgs>();
  CLI::App* cmd = app.add_subcommand(
      "contour", "contour plots of G over light angle x normal deviation (Chiang Fig. 5)");
  cmd->add_option("--method", a->methods, "method id (repeatable, in plot order)")->required();
  cmd->add_option("-o,--output", a->output, "output folder")->capture_default_str();
  cmd->add_option("--step", a->step, "grid step in degrees")
      ->check(CLI::Range(0.05, 10.0))
      ->capture_default_str();
  return {cmd, [a](const CommandContext& c) { return contour(*a, c.out); }};
}

}  // namespace penumbra
