// The map-aided ultrasonic update up to the Kalman update (map_aided_updater.hpp; the models are
// map_aided_ranging.hpp's).
#include "rowloc/localization/map_aided_updater.hpp"

#include "rowloc/localization/kalman_update.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace rowloc::localization {
namespace {

MapAidedConfig Checked(const MapAidedConfig& config) {
  FilterConfig whole;  // the other sections at their (valid) defaults
  whole.map_aided = config;
  if (const auto problem = FilterConfigProblem(whole)) throw FilterConfigError("filter config: " + *problem);
  return config;
}

/// The range noise estimator of the config; disabled: one that stays at range_sigma_m.
RangeNoiseEstimator RangeNoise(const MapAidedConfig& config) {
  const AdaptiveRangeSigmaConfig& a = config.adaptive_range_sigma;
  if (!a.enabled) return RangeNoiseEstimator::Fixed(config.range_sigma_m);
  return RangeNoiseEstimator(config.range_sigma_m, a.max_sigma_m, static_cast<std::size_t>(a.window_echoes),
                             static_cast<std::size_t>(a.min_echoes));
}

}  // namespace

MapAidedUpdater::MapAidedUpdater(const mapio::VehicleConfig& vehicle, const MapAidedConfig& config,
                                 const geometry::GeoOrigin& filter_origin)
    : config_(Checked(config)),
      vehicle_name_(vehicle.name),
      filter_origin_(filter_origin),
      gate_1_(ChiSquareGate(1, config_.gate_probability)),
      gate_2_(ChiSquareGate(2, config_.gate_probability)),
      range_noise_(RangeNoise(config_)) {
  for (const mapio::SensorMount& sensor : vehicle.ultrasonic) {
    ranger_names_.push_back(sensor.name);
    mounts_.push_back(RangeSensorMount{sensor.position_m.head<2>(), sensor.yaw_rad, config_.cone_half_angle_rad});
  }
}

void MapAidedUpdater::AttachRowMap(const geometry::RowMap& map) {
  if (mounts_.empty()) {
    throw std::invalid_argument("row map: the vehicle '" + vehicle_name_ + "' has no ultrasonic sensor to use it");
  }
  ranging_ = std::make_shared<const RowMapRanging>(map, filter_origin_, config_.row_smoothing_m);
}

std::optional<std::size_t> MapAidedUpdater::RangerIndex(const std::string& name, std::size_t hint) const {
  if (hint < ranger_names_.size() && ranger_names_[hint] == name) return hint;
  const auto it = std::find(ranger_names_.begin(), ranger_names_.end(), name);
  if (it == ranger_names_.end()) return std::nullopt;
  return static_cast<std::size_t>(it - ranger_names_.begin());
}

const RangeSensorMount& MapAidedUpdater::CheckedMount(const formats::UltrasonicMessage& ping) const {
  if (!ping.range_m || !std::isfinite(*ping.range_m) || !(*ping.range_m > 0.0)) {
    throw std::invalid_argument("ultrasonic '" + ping.sensor + "': the map-aided update needs a finite range_m > 0");
  }
  const auto index = RangerIndex(ping.sensor, ping.sensor_index);
  if (!index) throw std::invalid_argument("'" + ping.sensor + "' is not an ultrasonic sensor of the vehicle");
  return mounts_[*index];
}

MapAidedEcho MapAidedUpdater::Measure(const formats::UltrasonicMessage& ping, const Eigen::Vector3d& pose,
                                      const Eigen::Matrix3d& pose_covariance) {
  if (!ranging_) throw std::logic_error("map-aided update: no row map attached");
  const RangeSensorMount& mount = CheckedMount(ping);
  ++stats_.echoes;
  MapAidedEcho echo;
  EchoTrace& trace = echo.trace;
  trace.sensor = ping.sensor;
  trace.measured_range_m = *ping.range_m;
  trace.prior_position_m = trace.posterior_position_m = pose.head<2>();
  trace.prior_covariance = trace.posterior_covariance = pose_covariance.topLeftCorner<2, 2>();
  // Association checks 1-3 of map_aided_ranging.hpp: the heading, the sensor inside a canopy, the lane.
  if (config_.k_sigma * std::sqrt(pose_covariance(2, 2)) > mount.cone_half_angle_rad) {
    ++stats_.heading_uncertain;
    trace.outcome = "heading_uncertain";
    return echo;
  }
  const std::vector<EchoCandidate>& candidates = FindCandidates(pose, pose_covariance, mount, echo);
  if (buffers_.sensor_inside_outline) {
    ++stats_.inside_outline;
    trace.outcome = "inside_outline";
    return echo;
  }
  if (candidates.empty()) {
    ++stats_.no_segment;
    trace.outcome = "no_segment";
    return echo;
  }
  if (candidates.size() > 1) ++stats_.ambiguous;
  const EchoCandidate& best = Nearest(candidates, mount, *ping.range_m, pose_covariance);
  trace.segment = ranging_->index().entries()[best.entry].segment;
  trace.line = best.edge;
  const double range_variance = best.jacobian * pose_covariance * best.jacobian.transpose();
  if (config_.k_sigma * std::sqrt(range_variance) > 0.5 * best.lane_clearance_m) {
    ++stats_.lane_ambiguous;
    trace.outcome = "lane_ambiguous";
    return echo;
  }
  const AlongUse along = CheckAlong(best, mount, pose_covariance, config_.k_sigma);
  if (along != AlongUse::kFull) ++stats_.along_ambiguous;
  if (along == AlongUse::kNone) {
    trace.outcome = "along_ambiguous";
    return echo;
  }
  const EchoCandidate used = along == AlongUse::kFull ? best : AcrossOnly(best, pose, mount);
  trace.line = used.edge;
  MapAidedConfig weighted = config_;
  weighted.range_sigma_m = range_noise_.sigma_m();
  const MapAidedMeasurement m = MakeMapAidedMeasurement(used, mount, pose, pose_covariance, *ping.range_m, weighted);
  range_noise_.Observe(*ping.range_m - used.predicted_range_m,
                       used.jacobian * pose_covariance * used.jacobian.transpose() +
                           RangeNoiseVariance(used, mount, pose_covariance, 0.0));
  if (m.innovation.size() == 0) {
    CountCutFailure(m.cut_status, trace);
    return echo;
  }
  echo.gate = m.innovation.size() == 1 ? gate_1_ : gate_2_;
  echo.measurement = m;
  return echo;
}

const std::vector<EchoCandidate>& MapAidedUpdater::FindCandidates(const Eigen::Vector3d& pose,
                                                                  const Eigen::Matrix3d& pose_covariance,
                                                                  const RangeSensorMount& mount, MapAidedEcho& echo) {
  // Candidates: every surface within k sigma (position and range) of the nearest predicted one.
  const double window_m =
      config_.k_sigma * (std::sqrt(pose_covariance.topLeftCorner<2, 2>().trace()) + range_noise_.sigma_m() +
                         ranging_->max_outline_sigma_m());
  const std::vector<EchoCandidate>& candidates =
      ranging_->Candidates(pose, mount, config_.max_range_m, window_m, buffers_);
  map_agreement_.ObserveEcho(!buffers_.sensor_inside_outline && !candidates.empty());
  if (stats_.echoes % kAgreementEveryEchoes == 0) {
    echo.agreement_checked = true;
    echo.map_problem = map_agreement_.MapProblem();
  }
  return candidates;
}

const EchoCandidate& MapAidedUpdater::Nearest(const std::vector<EchoCandidate>& candidates,
                                              const RangeSensorMount& mount, double measured_range_m,
                                              const Eigen::Matrix3d& pose_covariance) const {
  const EchoCandidate* best = nullptr;
  double best_nis = std::numeric_limits<double>::infinity();
  for (const EchoCandidate& c : candidates) {
    const double nis = RangeNis(c, mount, measured_range_m, pose_covariance, range_noise_.sigma_m());
    if (nis < best_nis || best == nullptr) {
      best_nis = nis;
      best = &c;
    }
  }
  return *best;
}

void MapAidedUpdater::CountCutFailure(geometry::CutStatus status, EchoTrace& trace) {
  switch (status) {
    case geometry::CutStatus::kEmpty: ++stats_.contradicting; trace.outcome = "contradicting"; break;
    case geometry::CutStatus::kUnchanged: ++stats_.uninformative; trace.outcome = "uninformative"; break;
    default: ++stats_.degenerate; trace.outcome = "degenerate"; break;
  }
}

}  // namespace rowloc::localization
