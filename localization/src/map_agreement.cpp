// A map that does not agree with the rangers (map_agreement.hpp).
#include "rowloc/localization/map_agreement.hpp"

#include <stdexcept>

namespace rowloc::localization {

MapAgreementMonitor::MapAgreementMonitor(MapAgreementConfig config) : config_(config) {
  if (config_.window_echoes < 2 || !(config_.suspect_no_segment_fraction > 0.0) ||
      config_.suspect_no_segment_fraction > 1.0) {
    throw std::invalid_argument("map agreement: window_echoes >= 2 and suspect_no_segment_fraction in (0, 1]");
  }
}

void MapAgreementMonitor::ObserveEcho(bool found_segment) {
  recent_no_segment_.push_back(!found_segment);
  no_segment_in_window_ += found_segment ? 0 : 1;
  if (recent_no_segment_.size() > config_.window_echoes) {
    no_segment_in_window_ -= recent_no_segment_.front() ? 1 : 0;
    recent_no_segment_.pop_front();
  }
}

std::optional<std::string> MapAgreementMonitor::MapProblem() const {
  const std::size_t n = recent_no_segment_.size();
  if (n < config_.window_echoes) return std::nullopt;
  if (static_cast<double>(no_segment_in_window_) < config_.suspect_no_segment_fraction * static_cast<double>(n)) {
    return std::nullopt;
  }
  return std::to_string(no_segment_in_window_) + " of the last " + std::to_string(n) +
         " echoes found no row of the map where they point: a map of another field or with a wrong origin, or the "
         "filter off its lane";
}

}  // namespace rowloc::localization
