// Per-sensor health from stuck readings and persistent gating (sensor_health.hpp).
#include "rowloc/localization/sensor_health.hpp"

#include <algorithm>
#include <stdexcept>

namespace rowloc::localization {

std::string_view SensorHealthStateName(SensorHealthState state) {
  switch (state) {
    case SensorHealthState::kOk: return "ok";
    case SensorHealthState::kSuspect: return "suspect";
    case SensorHealthState::kExcluded: return "excluded";
  }
  return "?";
}

SensorHealthMonitor::SensorHealthMonitor(SensorHealthConfig config) : config_(config) {
  if (config_.window < 1 || config_.stuck_messages < 2 || !(config_.suspect_gated_fraction > 0.0) ||
      config_.suspect_gated_fraction > 1.0 || !(config_.moving_speed_mps >= 0.0)) {
    throw std::invalid_argument("sensor health: window >= 1, stuck_messages >= 2, fraction in (0, 1], speed >= 0");
  }
}

void SensorHealthMonitor::ObserveReadings(const std::string& sensor, std::span<const double> readings, bool moving) {
  Track& t = tracks_[sensor];
  t.health.sensor = sensor;
  const bool same = t.last_readings.size() == readings.size() &&
                    std::equal(readings.begin(), readings.end(), t.last_readings.begin());
  t.last_readings.assign(readings.begin(), readings.end());
  if (same && moving) {
    ++t.repeats;
    t.changing = 0;
  } else if (!same) {
    t.repeats = 0;
    ++t.changing;
  }
  // At rest, identical readings say nothing (and neither do they end a stuck period).
  const bool was_stuck = t.stuck;
  if (t.repeats + 1 >= config_.stuck_messages) t.stuck = true;
  if (t.stuck && t.changing >= config_.stuck_messages) t.stuck = false;
  if (t.stuck != was_stuck) Evaluate();
}

void SensorHealthMonitor::ObserveUpdate(const std::string& sensor, bool accepted) {
  Track& t = tracks_[sensor];
  t.health.sensor = sensor;
  ++(accepted ? t.health.accepted : t.health.gated);
  t.recent_gated.push_back(!accepted);
  if (t.recent_gated.size() > config_.window) t.recent_gated.pop_front();
  Evaluate();
}

void SensorHealthMonitor::ObserveSkipped(const std::string& sensor) {
  Track& t = tracks_[sensor];
  t.health.sensor = sensor;
  ++t.health.skipped;
}

void SensorHealthMonitor::ObserveRefusal(const std::string& sensor, const std::string& why) {
  Track& t = tracks_[sensor];
  t.health.sensor = sensor;
  ++t.health.refused;
  t.refusal = why;
  Evaluate();
}

void SensorHealthMonitor::ObserveAccepted(const std::string& sensor) {
  const auto it = tracks_.find(sensor);
  if (it == tracks_.end() || !it->second.refusal) return;
  it->second.refusal.reset();
  Evaluate();
}

void SensorHealthMonitor::ObserveDisagreement(const std::string& sensor, const std::optional<std::string>& why) {
  auto it = tracks_.find(sensor);
  if (it == tracks_.end()) {
    if (!why) return;
    it = tracks_.emplace(sensor, Track{}).first;
    it->second.health.sensor = sensor;
  }
  if (it->second.disagreement.has_value() == why.has_value()) return;  // the state, not its numbers, matters
  it->second.disagreement = why;
  Evaluate();
}

bool SensorHealthMonitor::Inconsistent(const Track& track) const {
  if (track.recent_gated.size() < config_.window) return false;
  const auto gated = static_cast<double>(std::count(track.recent_gated.begin(), track.recent_gated.end(), true));
  return gated >= config_.suspect_gated_fraction * static_cast<double>(track.recent_gated.size());
}

void SensorHealthMonitor::Evaluate() {
  // States are decided without building text; the reason is written only when a state changes
  // (a message costs no allocation while nothing changes).
  const auto gated_text = [](const Track& t) {
    const auto gated = std::count(t.recent_gated.begin(), t.recent_gated.end(), true);
    return std::to_string(gated) + " of the last " + std::to_string(t.recent_gated.size()) + " updates gated out";
  };
  for (auto& [name, t] : tracks_) {
    SensorHealthState state = SensorHealthState::kOk;
    const Track* disagreeing = nullptr;  // the other sensor that disagrees with a stuck one
    if (t.stuck) {
      state = SensorHealthState::kSuspect;
      if (t.health.state == SensorHealthState::kExcluded) {
        state = SensorHealthState::kExcluded;  // latched while stuck: the others agree again once it is out
      } else if (Inconsistent(t)) {
        state = SensorHealthState::kExcluded;
      } else {
        for (const auto& [other_name, other] : tracks_) {
          if (other_name == name || !Inconsistent(other)) continue;
          state = SensorHealthState::kExcluded;
          disagreeing = &other;
          break;
        }
      }
    } else if (Inconsistent(t) || t.refusal || t.disagreement) {
      state = SensorHealthState::kSuspect;
    }
    if (state == t.health.state) continue;
    std::string reason;
    if (t.stuck) {
      reason = "readings identical for " + std::to_string(config_.stuck_messages) + " messages while the vehicle moves";
      if (disagreeing) {
        reason += ", while " + disagreeing->health.sensor + " disagrees (" + gated_text(*disagreeing) + ")";
      } else if (state == SensorHealthState::kExcluded) {
        reason += ", and " + gated_text(t);
      }
    } else if (Inconsistent(t)) {
      reason = gated_text(t);
    } else if (t.refusal) {
      reason = "message refused: " + *t.refusal;
    } else if (t.disagreement) {
      reason = *t.disagreement;
    }
    if (state == SensorHealthState::kExcluded) {
      ++exclusions_;
      last_excluded_ = name;
    }
    t.health.state = state;
    t.health.reason = reason;
    changes_.push_back(name + " " + std::string(SensorHealthStateName(state)) + (reason.empty() ? "" : ": " + reason));
  }
}

bool SensorHealthMonitor::Excluded(const std::string& sensor) const {
  const auto it = tracks_.find(sensor);
  return it != tracks_.end() && it->second.health.state == SensorHealthState::kExcluded;
}

std::vector<SensorHealth> SensorHealthMonitor::Report() const {
  std::vector<SensorHealth> report;
  report.reserve(tracks_.size());
  for (const auto& [name, t] : tracks_) report.push_back(t.health);
  return report;
}

std::optional<std::string> SensorHealthMonitor::TakeChanges() {
  if (changes_.empty()) return std::nullopt;
  std::string text = "sensor health: ";
  for (std::size_t i = 0; i < changes_.size(); ++i) text += (i ? "; " : "") + changes_[i];
  changes_.clear();
  return text;
}

}  // namespace rowloc::localization
