#include "study/fit_probes.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string_view>

namespace penumbra {

namespace {

// Where a list of values tried must hold `v`: inserted in order.
std::vector<double> with_value(std::vector<double> values, double v) {
  if (std::find(values.begin(), values.end(), v) == values.end()) {
    values.push_back(v);
    std::sort(values.begin(), values.end());
  }
  return values;
}

std::vector<double> quarter_octaves(int from, int to) {
  std::vector<double> values;
  for (int k = from; k <= to; ++k) values.push_back(std::exp2(k / 4.0));
  return values;
}

// The study's shading-offset label and its s, or nullopt-like ("", 0).
std::pair<std::string, double> study_shading_offset(const std::set<std::string>& labels) {
  constexpr std::string_view prefix = "shading-offset(s=";
  for (const std::string& l : labels)
    if (l.rfind(prefix, 0) == 0 && l.back() == ')') {
      try {
        return {l, std::stod(l.substr(prefix.size(), l.size() - prefix.size() - 1))};
      } catch (const std::exception&) {
      }
    }
  return {"", 0.0};
}

Lobes lobes_of(TerminatorMethod method, const Scene& scene) {
  switch (method_info(method).lobes) {
    case FactorLobes::kScene:
      return scene.terminator.lobes;
    case FactorLobes::kDiffuse:
      return Lobes::kDiffuse;
    case FactorLobes::kAll:
      return Lobes::kAll;
  }
  return Lobes::kDiffuse;
}

// One method's factor at every value of its constant.
void factors_at(TerminatorMethod method, const std::vector<double>& values, const ShadingPoint& p,
                double* out) {
  switch (method) {
    case TerminatorMethod::kShadingOffset:
      return shading_offsets(values, p.ns, p.wi, out);
    case TerminatorMethod::kMicroshadowChan2018:
      return microshadow_chan2018_exponents(dot(p.ns, p.wi), p.visibility, values, out);
    case TerminatorMethod::kMicroshadowBrinck2016:
      return microshadow_brinck2016_exponents(dot(p.ns, p.wi), p.visibility, values, out);
    default:
      std::fill(out, out + values.size(), 1.0);
  }
}

}  // namespace

std::vector<ProbedConstant> probed_constants(const std::set<std::string>& labels) {
  std::vector<double> s_values;
  for (int k = 0; k <= 40; ++k) s_values.push_back(k / 40.0);
  const auto [s_label, s] = study_shading_offset(labels);
  const auto label_of = [&](const char* id) { return labels.count(id) ? std::string(id) : ""; };
  return {
      {TerminatorMethod::kShadingOffset, s_label,
       "s in f = 1/(1 - s/2) of Cycles' Shading Offset (41 values in steps of 0.025)",
       s_label.empty() ? "Cycles' default (raw bump)" : "the study's value", s,
       with_value(s_values, s)},
      {TerminatorMethod::kMicroshadowChan2018, label_of("microshadow-chan2018"),
       "p in saturate(cos / sqrt(1 - V))^p (21 values in quarter octaves)", "published", 2.0,
       with_value(quarter_octaves(0, 20), 2.0)},
      {TerminatorMethod::kMicroshadowBrinck2016, label_of("microshadow-brinck2016"),
       "q in saturate(cos + 2 V^q - 1) (21 values in quarter octaves)", "published", 2.0,
       with_value(quarter_octaves(0, 20), 2.0)},
  };
}

TallyProbes probes_for(const std::vector<ProbedConstant>& constants, const Scene& scene,
                       const Image& raw_bump) {
  TallyProbes probes;
  const int theta = raw_bump.channel_index("analysis.theta");
  if (theta < 0)
    throw std::invalid_argument("probes_for: the raw-bump image has no analysis.theta");
  probes.pixels.assign(std::size_t(raw_bump.width) * raw_bump.height, 0);
  for (int y = 0; y < raw_bump.height; ++y)
    for (int x = 0; x < raw_bump.width; ++x) {
      const double t = raw_bump.at(x, y, theta);
      probes.pixels[std::size_t(y) * raw_bump.width + x] =
          t >= kTerminatorBegin - 1.0 && t < kTerminatorEnd + 1.0;
    }
  for (const ProbedConstant& c : constants) {
    FactorProbe p;
    p.lobes = lobes_of(c.method, scene);
    p.needs_visibility = method_info(c.method).needs_visibility;
    p.values = c.values.size();
    p.factors = [method = c.method, values = c.values](const ShadingPoint& point, double* out) {
      factors_at(method, values, point, out);
    };
    probes.probes.push_back(std::move(p));
  }
  return probes;
}

std::vector<std::vector<double>> probe_errors(const TallyProbes& probes, const Image& traced,
                                              double radiance_scale, const Profile& truth) {
  Image image = traced;
  const std::size_t channels = image.channels.size(), pixels = image.pixels.size() / channels;
  std::vector<int> colour;
  for (const char* name : {"R", "G", "B"})
    if (const int c = image.channel_index(name); c >= 0) colour.push_back(c);
  std::vector<std::vector<double>> errors;
  for (std::size_t f = 0; f < probes.probes.size(); ++f) {
    const std::size_t values = probes.probes[f].values;
    const std::vector<double>& radiance = probes.radiance[f];
    errors.emplace_back();
    for (std::size_t k = 0; k < values; ++k) {
      // As the evaluator writes a pixel (write_pixel): the mean, as a float.
      for (std::size_t p = 0; p < pixels; ++p)
        for (const int c : colour)
          image.pixels[p * channels + std::size_t(c)] =
              static_cast<float>(radiance[p * values + k]);
      errors.back().push_back(
          compare_profiles(terminator_profile(image, radiance_scale), truth).rmse_terminator);
    }
  }
  return errors;
}

}  // namespace penumbra
