#include "analysis/metrics_json.h"

#include <cmath>

namespace penumbra {
namespace {

// JSON has no NaN: undefined quantities are null.
nlohmann::json number(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
}

}  // namespace

nlohmann::json profile_metrics_json(const ProfileMetrics& m) {
  return {{"unit", "fraction of albedo*E/pi; angles in degrees"},
          {"rmse_terminator", number(m.rmse_terminator)},
          {"rmse_overall", number(m.rmse_overall)},
          {"max_error_terminator", number(m.max_error)},
          {"max_step", number(m.max_step)},
          {"reference_max_step", number(m.reference_max_step)},
          {"position_deg", number(m.position)},
          {"reference_position_deg", number(m.reference_position)},
          {"position_error_deg", number(m.position_error)},
          {"width_deg", number(m.width)},
          {"reference_width_deg", number(m.reference_width)},
          {"lit_bias", number(m.lit_bias)},
          {"common_bins", m.common_bins}};
}

nlohmann::json image_metrics_json(const ImageMetrics& m) {
  return {{"unit", "W m^-2 sr^-1"},
          {"mask_iou", number(m.mask_iou)},
          {"rmse", number(m.rmse)},
          {"max_error", number(m.max_error)},
          {"ssim", number(m.ssim)},
          {"mean_error", number(m.mean_error)},
          {"reference_mean", number(m.reference_mean)},
          {"peak", number(m.peak)},
          {"pixels", m.pixels},
          {"nonfinite", m.nonfinite}};
}

nlohmann::json view_metrics_json(const ViewMetrics& m) {
  return {{"unit", "fraction of albedo*E/pi"},
          {"grazing_deg", {kGrazingBegin, kGrazingEnd}},
          {"rmse_grazing", number(m.rmse_grazing)},
          {"bias_grazing", number(m.bias_grazing)},
          {"pixels", m.pixels}};
}

nlohmann::json shadow_metrics_json(const ShadowMetrics& m) {
  return {
      {"unit", "fraction of albedo*E/pi (max_darkening), of pixels (fractions), pixels (shift)"},
      {"lit_pixels", m.lit_pixels},
      {"darkened_pixels", m.darkened_pixels},
      {"darkened_fraction", number(m.darkened_fraction)},
      {"max_darkening", number(m.max_darkening)},
      {"shadowed_pixels", m.shadowed_pixels},
      {"test_shadowed_pixels", m.test_shadowed_pixels},
      {"lost_shadow_fraction", number(m.lost_shadow_fraction)},
      {"shadow_shift_px", number(m.shadow_shift_px)}};
}

nlohmann::json profile_json(const Profile& p) {
  nlohmann::json value = nlohmann::json::array(), count = nlohmann::json::array();
  for (std::size_t k = 0; k < p.value.size(); ++k) {
    value.push_back(p.count[k] ? nlohmann::json(p.value[k]) : nlohmann::json());
    count.push_back(p.count[k]);
  }
  return {{"bin_degrees", p.bin_degrees}, {"value", value}, {"count", count}};
}

}  // namespace penumbra
