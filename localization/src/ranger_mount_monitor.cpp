// Online check of the rangers' mounts (ranger_mount_monitor.hpp).
#include "rowloc/localization/ranger_mount_monitor.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace rowloc::localization {
namespace {

void CheckPositive(const char* name, double value) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw std::invalid_argument(std::string("ranger mount monitor: ") + name + " must be positive and finite");
  }
}

}  // namespace

RangerMountMonitor::RangerMountMonitor(std::shared_ptr<const RowMapRanging> ranging,
                                       std::vector<mapio::SensorMount> mounts, const MapAidedConfig& map_aided,
                                       RangerMountMonitorConfig config)
    : ranging_(std::move(ranging)),
      mounts_(std::move(mounts)),
      map_aided_(map_aided),
      config_(std::move(config)),
      streak_(mounts_.size(), 0),
      suspect_(mounts_.size(), false) {
  if (!ranging_) throw std::invalid_argument("ranger mount monitor: no row map");
  CheckPositive("window_s", config_.window_s);
  CheckPositive("check_every_s", config_.check_every_s);
  CheckPositive("min_span_s", config_.min_span_s);
  CheckPositive("knot_interval_s", config_.knot_interval_s);
  CheckPositive("max_pose_jump_m", config_.max_pose_jump_m);
  CheckPositive("suspect_offset_m", config_.suspect_offset_m);
  CheckPositive("k_sigma", config_.k_sigma);
  if (config_.confirmations < 1) throw std::invalid_argument("ranger mount monitor: confirmations must be at least 1");
  if (config_.window_s < config_.min_span_s) {
    throw std::invalid_argument("ranger mount monitor: window_s must be at least min_span_s");
  }
  try {
    ValidateRangerMountFitConfig(config_.fit);
  } catch (const RangerMountFitError& e) {
    throw std::invalid_argument(std::string("ranger mount monitor: ") + e.what());
  }
}

void RangerMountMonitor::ObservePose(double time_s, const Eigen::Vector3d& pose, const Eigen::Vector3d& body_rates) {
  if (!knots_.empty()) {
    if (time_s < knots_.back().time_s + config_.knot_interval_s) return;
    if ((pose.head<2>() - knots_.back().pose.head<2>()).norm() > config_.max_pose_jump_m) Restart();
  }
  knots_.push_back({time_s, pose, body_rates});
  DropBefore(time_s - config_.window_s);
}

void RangerMountMonitor::ObserveEcho(double time_s, std::size_t ranger, double range_m) {
  if (ranger >= mounts_.size()) throw std::invalid_argument("ranger mount monitor: unknown ranger index");
  echoes_.push_back({time_s, ranger, range_m});
}

void RangerMountMonitor::Restart() {
  knots_.clear();
  echoes_.clear();
}

void RangerMountMonitor::DropBefore(double time_s) {
  while (!knots_.empty() && knots_.front().time_s < time_s) knots_.pop_front();
  while (!echoes_.empty() && echoes_.front().time_s < time_s) echoes_.pop_front();
}

bool RangerMountMonitor::Check(double time_s) {
  if (last_check_s_ && time_s < *last_check_s_ + config_.check_every_s) return false;
  if (knots_.size() < 2 || knots_.back().time_s - knots_.front().time_s < config_.min_span_s) return false;
  last_check_s_ = time_s;
  ++checks_;
  const std::vector<ReferenceKnot> knots(knots_.begin(), knots_.end());
  const std::vector<EchoRecord> echoes(echoes_.begin(), echoes_.end());
  RangerMountFit fit;
  try {
    fit = FitRangerMounts(*ranging_, mounts_, map_aided_.cone_half_angle_rad, map_aided_.max_range_m, knots, echoes,
                          config_.fit);
  } catch (const RangerMountFitError&) {
    // Echoes that mostly meet no row: not judged here (map_agreement.hpp reports it); keep the findings.
    return false;
  }
  bool changed = false;
  std::vector<RangerMountFinding> suspects;
  for (std::size_t i = 0; i < fit.rangers.size(); ++i) {
    const RangerMountEstimate& r = fit.rangers[i];
    const double magnitude = std::abs(r.along_beam_m);
    // A NaN sigma (no covariance) judges by the offset alone.
    const bool off = r.calibrated && magnitude > config_.suspect_offset_m &&
                     !(magnitude <= config_.k_sigma * r.along_beam_sigma_m);
    streak_[i] = off == suspect_[i] ? 0 : streak_[i] + 1;
    if (streak_[i] >= config_.confirmations) {
      suspect_[i] = off;
      streak_[i] = 0;
      changed = true;
    }
    if (suspect_[i]) suspects.push_back({r.name, r.along_beam_m, r.along_beam_sigma_m});
  }
  suspects_ = std::move(suspects);
  return changed;
}

std::string RangerMountMonitor::Reason(const RangerMountFinding& finding, double window_s) {
  char text[256];
  std::snprintf(text, sizeof text,
                "its echoes over the last %.0f s fit the map with the ranger %.1f cm %s the rows it hears than "
                "configured (along its beam; 1-sigma %.1f mm): check its mount, or run rowloc calibrate",
                window_s, 100.0 * std::abs(finding.along_beam_m), finding.along_beam_m > 0.0 ? "nearer to" : "further from",
                1e3 * finding.sigma_m);
  return text;
}

}  // namespace rowloc::localization
