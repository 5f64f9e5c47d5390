// One localization run over a message stream (see localization_session.hpp).
#include "rowloc/localization/localization_session.hpp"

#include "rowloc/localization/wheel_slip_estimate.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>
#include <variant>

namespace rowloc::localization {

std::vector<formats::WheelCalibrationRecord> WheelCalibrationOf(const VehicleEkf& ekf, const Eigen::VectorXd& x,
                                                                const Eigen::MatrixXd& p) {
  const StateLayout& layout = ekf.layout();
  if (!layout.slip_aware()) return {};
  std::vector<formats::WheelCalibrationRecord> wheels;
  for (std::size_t i = 0; i < layout.wheel_count(); ++i) {
    const int r = layout.rolling_radius[i], k = layout.slip_compliance[i];
    wheels.push_back({ekf.vehicle().wheels[i].name, x(r), std::sqrt(std::max(p(r, r), 0.0)), x(k),
                      std::sqrt(std::max(p(k, k), 0.0))});
  }
  return wheels;
}

std::vector<formats::SensorHealthRecord> SensorHealthOf(const VehicleEkf& ekf) {
  std::vector<formats::SensorHealthRecord> records;
  for (const SensorHealth& h : ekf.health().Report()) {
    if (h.state == SensorHealthState::kOk) continue;
    records.push_back({h.sensor, std::string(SensorHealthStateName(h.state)), h.reason, h.accepted, h.gated, h.skipped,
                       h.refused});
  }
  return records;
}

namespace {

/// The mount check's suspect rangers in the sensor health records (a ranger the filter's own health
/// already distrusts keeps its state, with the finding added to its reason).
void AddMountFindings(const RangerMountMonitor& monitor, std::vector<formats::SensorHealthRecord>& records) {
  for (const RangerMountFinding& f : monitor.suspects()) {
    const std::string reason = RangerMountMonitor::Reason(f, monitor.config().window_s);
    const auto it = std::find_if(records.begin(), records.end(),
                                 [&](const formats::SensorHealthRecord& r) { return r.sensor == f.ranger; });
    if (it == records.end()) {
      records.push_back({f.ranger, "suspect", reason, 0, 0, 0, 0});
    } else {
      it->reason += "; " + reason;
    }
  }
}

}  // namespace

LocalizationSession::LocalizationSession(mapio::VehicleConfig vehicle, FilterConfig config,
                                         const formats::LogHeader& header, SessionOptions options)
    : vehicle_(vehicle),
      header_(header),
      options_(std::move(options)),
      ekf_(std::move(vehicle), std::move(config), header.origin, header.wheels) {
  if (!(options_.estimate_period_s > 0.0) || !std::isfinite(options_.estimate_period_s)) {
    throw std::invalid_argument("estimate period must be finite and > 0 s");
  }
  if (vehicle_.kind == mapio::VehicleKind::kSkidSteer) {
    const bool first_is_right = vehicle_.wheels[0].position_m.y() < vehicle_.wheels[1].position_m.y();
    right_track_ = first_is_right ? 0 : 1;
    TrackSlipObserverConfig observer;
    observer.track_width_m = std::abs(vehicle_.wheels[0].position_m.y() - vehicle_.wheels[1].position_m.y());
    tracks_.emplace(observer);
  }
}

void LocalizationSession::SetPose(double time_s, const Eigen::Vector3d& pose, const Eigen::Matrix3d& covariance) {
  ekf_.SetPose(time_s, pose, covariance);
}

void LocalizationSession::EnableSmoothing() {
  ekf_.EnableSmoothing();
  marks_.emplace();
}

std::vector<std::pair<std::string, double>> LocalizationSession::TrackSlip() const {
  if (!tracks_ || !tracks_->initialised()) return {};
  return {{vehicle_.wheels[right_track_].name, tracks_->slip_right()},
          {vehicle_.wheels[1 - right_track_].name, tracks_->slip_left()}};
}

formats::EstimateRecord LocalizationSession::EstimateOf(double time_s, const Eigen::VectorXd& x,
                                                        const Eigen::MatrixXd& p,
                                                        const std::vector<double>& speeds_radps) const {
  formats::EstimateRecord record;
  record.time_s = time_s;
  record.position_m = x.head<2>();
  record.heading_rad = x(StateLayout::kPhi);
  record.covariance = p.topLeftCorner<3, 3>();
  record.wheel_calibration = WheelCalibrationOf(ekf_, x, p);
  record.sensor_health = SensorHealthOf(ekf_);
  if (mount_monitor_) AddMountFindings(*mount_monitor_, record.sensor_health);
  if (tracks_) {
    record.slip = TrackSlip();
    return record;
  }
  if (speeds_radps.empty()) return record;
  const std::vector<double> slip = EstimateWheelSlip(x, ekf_.vehicle(), ekf_.layout(), speeds_radps,
                                                     ekf_.config().slip_aware_odometry.slip_with_rolling_radius);
  for (std::size_t i = 0; i < slip.size(); ++i) record.slip.emplace_back(ekf_.vehicle().wheels[i].name, slip[i]);
  return record;
}

formats::EstimateRecord LocalizationSession::CurrentEstimate() const {
  if (!ekf_.initialised()) throw std::logic_error("CurrentEstimate: the filter is not initialised");
  return EstimateOf(ekf_.time_s(), ekf_.state(), ekf_.covariance(), ekf_.last_wheel_speeds_radps());
}

bool LocalizationSession::ObserveTracks(const formats::SensorMessage& message, std::string& error) {
  if (!tracks_ || !ekf_.initialised() || !std::holds_alternative<formats::WheelsMessage>(message)) return true;
  const std::vector<double>& speeds = ekf_.last_wheel_speeds_radps();
  const auto& wheels = vehicle_.wheels;
  const std::size_t left = 1 - right_track_;
  const Eigen::VectorXd& x = ekf_.state();
  try {
    tracks_->Update({ekf_.time_s(), x(0), x(1), x(2), speeds[right_track_] * wheels[right_track_].nominal_radius_m,
                     speeds[left] * wheels[left].nominal_radius_m});
  } catch (const std::invalid_argument& e) {
    error = std::string("track-slip observer rejected the input: ") + e.what();
    return false;
  }
  return true;
}

void LocalizationSession::CountUpdates(const ProcessResult& result, SessionStep& step) {
  for (const UpdateRecord& u : result.updates) {
    SensorUpdateCounts& c = counts_[u.sensor];
    ++(u.outcome.accepted ? c.accepted : c.gated);
    c.last_nis = u.outcome.nis;
    if (!options_.record_updates || !std::isfinite(u.outcome.nis)) continue;
    step.updates.push_back({u.time_s, u.sensor, u.outcome.innovation, u.outcome.innovation_covariance, u.outcome.nis,
                            u.outcome.accepted});
  }
}

SessionStep LocalizationSession::Process(const formats::SensorMessage& message) {
  SessionStep step;
  ++messages_;
  const std::string_view type = formats::TypeOf(message);
  if (std::find(options_.skip_types.begin(), options_.skip_types.end(), type) != options_.skip_types.end()) {
    ++skipped_;
    step.skipped = true;
    return step;
  }
  if (std::holds_alternative<formats::UltrasonicMessage>(message)) ++ultrasonic_;
  ProcessResult result;
  try {
    result = ekf_.Process(message);
  } catch (const FilterInputError& e) {
    ++refused_;
    step.error = e.what();
    return step;
  }
  step.changed_state = true;
  step.notice = std::move(result.notice);
  if (std::string error; !ObserveTracks(message, error)) {
    ++refused_;
    step.error = std::move(error);
  }
  CountUpdates(result, step);
  if (std::holds_alternative<formats::GpsMessage>(message) &&
      std::any_of(result.updates.begin(), result.updates.end(),
                  [](const UpdateRecord& u) { return u.outcome.accepted; })) {
    last_fix_time_s_ = ekf_.time_s();
  }
  step.echo = std::move(result.echo);
  CheckRangerMounts(message, step);
  if (ekf_.initialised() && ekf_.time_s() >= next_estimate_s_) {
    step.estimate = CurrentEstimate();
    if (marks_) {
      marks_->push_back({step.estimate->slip, ekf_.last_wheel_speeds_radps()});
      ekf_.MarkForSmoothing();
    }
    ++estimates_;
    next_estimate_s_ = ekf_.time_s() + options_.estimate_period_s;
  }
  return step;
}

void LocalizationSession::AttachRowMap(const geometry::RowMap& map) {
  ekf_.AttachRowMap(map);
  if (!options_.check_ranger_mounts) return;
  mount_monitor_.emplace(ekf_.row_map_ranging(), vehicle_.ultrasonic, ekf_.config().map_aided);
}

void LocalizationSession::CheckRangerMounts(const formats::SensorMessage& message, SessionStep& step) {
  if (!mount_monitor_) return;
  // Until the heading is known well enough for the echoes' association (map_aided_ranging.hpp,
  // check 1), a fit would split one ranger's offset with its opposite neighbour's.
  const MapAidedConfig& map_aided = ekf_.config().map_aided;
  if (!ekf_.initialised() || map_aided.k_sigma * std::sqrt(ekf_.covariance()(2, 2)) > map_aided.cone_half_angle_rad) {
    mount_monitor_->Restart();
    return;
  }
  mount_monitor_->ObservePose(ekf_.time_s(), ekf_.state().head<3>(), ekf_.state().segment<3>(StateLayout::kVx));
  const auto* ping = std::get_if<formats::UltrasonicMessage>(&message);
  if (ping && ping->range_m) {
    const auto& rangers = vehicle_.ultrasonic;
    const auto it = std::find_if(rangers.begin(), rangers.end(),
                                 [&](const mapio::SensorMount& m) { return m.name == ping->sensor; });
    if (it != rangers.end()) mount_monitor_->ObserveEcho(ping->time_s, static_cast<std::size_t>(it - rangers.begin()), *ping->range_m);
  }
  if (!mount_monitor_->Check(ekf_.time_s())) return;
  std::string notice;
  for (const RangerMountFinding& f : mount_monitor_->suspects()) {
    notice += (notice.empty() ? "" : "; ") + f.ranger + " suspect: " +
              RangerMountMonitor::Reason(f, mount_monitor_->config().window_s);
  }
  if (notice.empty()) notice = "ranger mounts: every ranger agrees with the map again";
  step.notice = step.notice ? *step.notice + "; " + notice : notice;
}

std::vector<formats::EstimateRecord> LocalizationSession::FinishSmoothing() {
  if (!marks_) throw std::logic_error("FinishSmoothing: smoothing is not enabled");
  const std::vector<SmoothedState> smoothed = ekf_.FinishSmoothing();
  if (smoothed.size() != marks_->size()) throw std::logic_error("smoothed estimates do not match the marks");
  std::vector<formats::EstimateRecord> records;
  for (std::size_t i = 0; i < smoothed.size(); ++i) {
    const SmoothingMark& mark = (*marks_)[i];
    formats::EstimateRecord record =
        EstimateOf(smoothed[i].time_s, smoothed[i].state, smoothed[i].covariance, mark.speeds_radps);
    if (tracks_) record.slip = mark.track_slip;  // the observer's at that time
    records.push_back(std::move(record));
  }
  marks_.reset();
  return records;
}

}  // namespace rowloc::localization
