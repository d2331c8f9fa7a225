// Metrics as JSON objects with their units, for reports and `compare --json`.
#pragma once

#include <nlohmann/json.hpp>

#include "analysis/metrics.h"

namespace penumbra {

nlohmann::json profile_metrics_json(const ProfileMetrics& m);
nlohmann::json image_metrics_json(const ImageMetrics& m);
nlohmann::json view_metrics_json(const ViewMetrics& m);
nlohmann::json shadow_metrics_json(const ShadowMetrics& m);
nlohmann::json profile_json(const Profile& p);

}  // namespace penumbra
