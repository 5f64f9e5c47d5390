// Two-sided CUSUM per wheel on the normalized speed innovations (terrain_change_detector.hpp).
#include "rowloc/localization/terrain_change_detector.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rowloc::localization {

TerrainChangeDetector::TerrainChangeDetector(std::size_t wheels, const TerrainChangeConfig& config)
    : config_(config), upper_(wheels, 0.0), lower_(wheels, 0.0), alarms_(wheels, 0) {
  if (!(config.cusum_drift_sigma >= 0.0 && std::isfinite(config.cusum_drift_sigma))) {
    throw std::invalid_argument("terrain change: cusum_drift_sigma must be finite and >= 0");
  }
  if (!(config.cusum_threshold_sigma > 0.0 && std::isfinite(config.cusum_threshold_sigma))) {
    throw std::invalid_argument("terrain change: cusum_threshold_sigma must be finite and > 0");
  }
  if (!(config.radius_sigma_fraction > 0.0 && std::isfinite(config.radius_sigma_fraction))) {
    throw std::invalid_argument("terrain change: radius_sigma_fraction must be finite and > 0");
  }
}

const std::vector<std::size_t>& TerrainChangeDetector::Observe(const Eigen::VectorXd& normalized_innovation) {
  if (static_cast<std::size_t>(normalized_innovation.size()) != upper_.size()) {
    throw std::invalid_argument("terrain change: " + std::to_string(normalized_innovation.size()) +
                                " innovations for " + std::to_string(upper_.size()) + " wheels");
  }
  fired_.clear();
  const double d = config_.cusum_drift_sigma, h = config_.cusum_threshold_sigma;
  for (std::size_t i = 0; i < upper_.size(); ++i) {
    const double e = normalized_innovation(static_cast<Eigen::Index>(i));
    if (!std::isfinite(e)) {
      upper_[i] = lower_[i] = 0.0;
      continue;
    }
    upper_[i] = std::max(0.0, upper_[i] + e - d);
    lower_[i] = std::max(0.0, lower_[i] - e - d);
    if (upper_[i] > h || lower_[i] > h) {
      upper_[i] = lower_[i] = 0.0;
      ++alarms_[i];
      fired_.push_back(i);
    }
  }
  return fired_;
}

void TerrainChangeDetector::Reset() {
  std::fill(upper_.begin(), upper_.end(), 0.0);
  std::fill(lower_.begin(), lower_.end(), 0.0);
}

}  // namespace rowloc::localization
