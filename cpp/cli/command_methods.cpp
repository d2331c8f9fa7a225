// `penumbra methods`: the terminator methods, normal adjustments, shadow-ray
// offsets and roughness filters, from their tables (core/terminator.h,
// core/normal_adjust.h, core/shadow_origin.h, core/roughness_filter.h) with
// the names of core/method_names.h.
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli/command.h"
#include "core/method_names.h"
#include "core/shadow_origin.h"

namespace penumbra {

using nlohmann::json;

namespace {

std::string parameter_domain(const MethodParameter& p) {
  return fmt::format("{} in [{}, {}] {}, default {}", p.name, p.min_value, p.max_value, p.unit,
                     p.default_value);
}

json parameters_json(std::span<const MethodParameter> list) {
  json parameters = json::array();
  for (const MethodParameter& p : list)
    parameters.push_back({{"name", p.name},
                          {"unit", p.unit},
                          {"min", p.min_value},
                          {"max", p.max_value},
                          {"default", p.default_value},
                          {"description", p.description}});
  return parameters;
}

// One line saying how the method acts, for the text listing.
std::string method_family_text(const MethodInfo& m) {
  const std::string adjustment(normal_adjustment_info(m.adjustment).id);
  const char* lobes = name_of<FactorLobes>(kFactorLobesPhrases, m.lobes);
  const std::string reference = m.reference_is_ni ? ", reference Ni" : "";
  switch (m.kind) {
    case MethodKind::kFactor:
      return fmt::format("factor on {}", lobes);
    case MethodKind::kFactorAndAdjustment:
      return fmt::format("factor on {}{} + normal adjustment {}", lobes, reference, adjustment);
    case MethodKind::kAdjustment:
      return fmt::format("normal adjustment {}{}", adjustment, reference);
    case MethodKind::kMicrofacet:
      return "microfacet model: replaces the BSDF (both lobes)";
  }
  return "";
}

}  // namespace

json methods_json() {
  json list = json::array();
  for (const MethodInfo& m : all_methods())
    list.push_back({{"id", m.id},
                    {"kind", "terminator"},
                    {"source", m.source},
                    {"summary", m.summary},
                    {"parameters", parameters_json(m.parameters)},
                    {"family", name_of<MethodKind>(kMethodKindNames, m.kind)},
                    {"normal_adjustment", normal_adjustment_info(m.adjustment).id},
                    {"factor_lobes", name_of<FactorLobes>(kFactorLobesNames, m.lobes)},
                    {"reference_normal", m.reference_is_ni ? "Ni" : "scene"},
                    {"identity_without_deviation", m.identity_without_deviation},
                    {"note", m.identity_note}});
  for (const NormalAdjustmentInfo& a : all_normal_adjustments())
    list.push_back({{"id", a.id},
                    {"kind", "normal_adjustment"},
                    {"source", a.source},
                    {"summary", a.summary},
                    {"touches_diffuse", a.touches_diffuse}});
  for (const OffsetMethodInfo& m : all_offset_methods())
    list.push_back({{"id", m.id},
                    {"kind", "offset"},
                    {"source", m.source},
                    {"summary", m.summary},
                    {"parameters", parameters_json(m.parameters)}});
  for (const RoughnessFilterInfo& f : all_roughness_filters())
    list.push_back({{"id", f.id},
                    {"kind", "roughness_filter"},
                    {"source", f.source},
                    {"summary", f.summary},
                    {"parameters", parameters_json(f.parameters)},
                    {"distribution",
                     name_of<FilteredDistribution>(kFilteredDistributionNames, f.distribution)},
                    {"input", f.needs_normal_derivatives ? "normal screen-space derivatives"
                                                         : "bump and roughness pyramid"}});
  return list;
}

namespace {

// "-", or the domain of the last parameter (every method has at most one).
std::string parameters_text(std::span<const MethodParameter> parameters) {
  std::string text = "-";
  for (const MethodParameter& p : parameters) text = parameter_domain(p);
  return text;
}

void print_terminator_methods(std::ostream& out) {
  out << fmt::format("{:<24} {:<40} {}\n", "id", "parameters", "source");
  for (const MethodInfo& m : all_methods()) {
    out << fmt::format("{:<24} {:<40} {}\n", m.id, parameters_text(m.parameters), m.source);
    out << fmt::format("{:<24} {}\n", "", m.summary);
    out << fmt::format("{:<24} ({})\n", "", method_family_text(m));
    if (!m.identity_without_deviation) out << fmt::format("{:<24} note: {}\n", "", m.identity_note);
  }
  out << "\nFactors lie in [0,1] and multiply the light's contribution (BSDF times <Ns,wi>) of "
         "their lobes; adjustments change Ns; microfacet models replace the BSDF.\n";
}

void print_adjustments_and_offsets(std::ostream& out) {
  out << fmt::format(
      "\nNormal adjustments (/terminator/normal_adjustment, at most one besides the method's "
      "own):\n{:<24} {}\n",
      "id", "source");
  for (const NormalAdjustmentInfo& a : all_normal_adjustments()) {
    out << fmt::format("{:<24} {}\n", a.id, a.source);
    out << fmt::format("{:<24} {}\n", "", a.summary);
  }
  out << fmt::format(
      "\nShadow-ray origin methods (/offset/method; low-poly meshes only):\n{:<24} "
      "{:<40} {}\n",
      "id", "parameters", "source");
  for (const OffsetMethodInfo& m : all_offset_methods()) {
    out << fmt::format("{:<24} {:<40} {}\n", m.id, parameters_text(m.parameters), m.source);
    out << fmt::format("{:<24} {}\n", "", m.summary);
  }
}

void print_roughness_filters(std::ostream& out) {
  out << fmt::format(
      "\nRoughness filters (bump-map filtering: a scene's /height/filter and `penumbra "
      "filtering`; `penumbra pyramid` builds their input; the lobe they give is a slope-space "
      "alpha^2 tensor A on the named distribution):\n{:<24} "
      "{:<40} {}\n",
      "id", "distribution", "source");
  for (const RoughnessFilterInfo& f : all_roughness_filters()) {
    out << fmt::format("{:<24} {:<40} {}\n", f.id,
                       name_of<FilteredDistribution>(kFilteredDistributionNames, f.distribution),
                       f.source);
    out << fmt::format("{:<24} {}\n", "", f.summary);
    for (const FilterParameter& p : f.parameters)
      out << fmt::format("{:<24} parameter {}: {}\n", "", parameter_domain(p), p.description);
  }
}

}  // namespace

Command add_methods_command(CLI::App& app, SharedOptions&) {
  auto as_json = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand("methods", "list the terminator methods");
  cmd->add_flag("--json", *as_json, "print a JSON array");
  return {cmd, [as_json](const CommandContext& c) {
            if (*as_json) {
              c.out << methods_json().dump(2) << "\n";
              return kExitOk;
            }
            print_terminator_methods(c.out);
            print_adjustments_and_offsets(c.out);
            print_roughness_filters(c.out);
            return kExitOk;
          }};
}

}  // namespace penumbra
