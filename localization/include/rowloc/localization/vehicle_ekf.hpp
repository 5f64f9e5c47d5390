// The vehicle EKF: GPS, IMU, wheel encoders, steering encoders and visual odometry fused over the
// state of StateLayout (issue 4; Danzi 2026 ch. 4 and 6; Lindgren et al. 2002 for the
// slip-aware odometry). docs/localization-filter.md describes the whole filter.
//
// Each message is processed in time order: the state is predicted to the message's time stamp
// (process_model.hpp, in steps of at most max_prediction_step_s), then the message's measurement
// is applied as one sequential update (kalman_update.hpp: Joseph form, chi-square gate, NIS).
// Initialisation (docs/localization-filter.md §2): the heading is not observable from one GNSS fix,
// so the filter waits until the antenna has moved heading_baseline_m (and at least 10 fix sigmas)
// from an anchor fix that a consensus of fixes confirms (vehicle_ekf_initialisation.cpp: a third
// fix agrees with both, every pair agrees with the odometry between them; an outlier is never the
// anchor) and takes
// the course of that displacement (corrected by the mean steering angle, reversed when the wheels
// turn backwards) as the initial heading; or SetPose initialises it directly. Ultrasonic echoes are
// used once a row map is attached (AttachRowMap; map_aided_ranging.hpp, issue 5): each echo is one
// update named "ultrasonic" by the method of config.map_aided, against the segment it comes from,
// once its association is certain (map_aided_ranging.hpp, checks 1-3: heading, sensor inside a
// canopy, lane; otherwise the echo is skipped and counted in MapAidedStats). MapAidedUpdater
// (map_aided_updater.hpp) makes the measurement from the pose block; the filter applies it.
//
// Inputs are checked: non-finite values, out-of-range values (sigma <= 0, |omega| above
// max_speed_radps, |delta| above the vehicle's limit + 0.1 rad, a sigma above 1e4, a non-positive range, an
// echo from a ranger the vehicle does not list while a row map is attached), a wheel count that does not match
// and time going backwards throw FilterInputError and leave the filter unchanged. A gap longer than
// max_prediction_gap_s is a clock or logging fault: the filter drops its state and re-initialises
// (reported as a notice). GNSS re-acquisition: when every fix for longer than gps.reacquire_after_s was gated
// out, the filter (not the receiver) is taken to have drifted: the position covariance is inflated
// by the innovation's outer product and the fix is applied (reported as a notice). With
// gps.estimate_bias, GnssBiasModel (gnss_bias_model.hpp) gives the bias states' Gauss-Markov
// transition, their columns of the fix's measurement and their initialisation.
// Clock faults: |t| > kMaxTimeS is refused; a stamp more than max_time_jump_s from the filter's time
// is refused and counted (time_jumps_refused), unless a run of such messages shows the whole clock
// moved (the filter then re-initialises on the new time base, with a notice). A prediction never
// takes more than kMaxPredictionSteps steps. Sensor health (sensor_health.hpp; docs §7): a sensor
// whose readings are stuck while the vehicle moves and that disagrees with the others is excluded
// (its updates skipped, the state dropped and re-initialised without it, except for the GNSS),
// every change reported as a notice.
// Smoothing (EnableSmoothing, off by default): the filter records every transition and update for
// the fixed-interval smoother (fixed_interval_smoother.hpp) through SmoothingRecorder
// (smoothing_recorder.hpp); the filter's own results do not change.
#pragma once

#include "rowloc/formats/sensor_messages.hpp"
#include "rowloc/geometry/row_map.hpp"
#include "rowloc/localization/filter_config.hpp"
#include "rowloc/localization/fixed_interval_smoother.hpp"
#include "rowloc/localization/gnss_bias_model.hpp"
#include "rowloc/localization/kalman_update.hpp"
#include "rowloc/localization/map_aided_updater.hpp"
#include "rowloc/localization/measurement_models.hpp"
#include "rowloc/localization/sensor_health.hpp"
#include "rowloc/localization/smoothing_recorder.hpp"
#include "rowloc/localization/state_layout.hpp"
#include "rowloc/localization/terrain_change_detector.hpp"
#include "rowloc/localization/traction_updater.hpp"
#include "rowloc/localization/wheel_angle_model.hpp"
#include "rowloc/localization/wheel_angle_updater.hpp"
#include "rowloc/mapio/local_frame.hpp"
#include "rowloc/mapio/vehicle_config.hpp"

#include <Eigen/Core>
#include <boost/container/small_vector.hpp>

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace rowloc::localization {

class FilterInputError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct UpdateRecord {
  double time_s = 0.0;
  std::string sensor;  ///< the message's sensor name, or "wheels", "nonholonomic", "steering", "ultrasonic"
  UpdateOutcome outcome;
};

/// One wheel's slip-aware calibration from a previous drive (e.g. the last `wheel_calibration` of
/// an estimate stream, docs/protocol.md §3): the prior of R_w and kappa at initialisation instead
/// of the filter file's (nominal radius, slip_compliance_initial).
struct WheelCalibrationPrior {
  std::string wheel;
  double rolling_radius_m = 0.0;        ///< > 0
  double rolling_radius_sigma_m = 0.0;  ///< > 0 (a zero prior variance would freeze the state)
  double slip_compliance = 0.0;         ///< kappa >= 0
  double slip_compliance_sigma = 0.0;   ///< > 0
};

struct ProcessResult {
  /// The updates made (none before initialisation; at most two per message, kept inline: a
  /// message costs no heap allocation for them).
  boost::container::small_vector<UpdateRecord, 2> updates;
  std::optional<std::string> notice;  ///< initialisation, re-initialisation after a gap
  std::optional<EchoTrace> echo;      ///< ultrasonic messages with a row map attached
};

/// The name the health monitor (VehicleEkf::health) knows a message's sensor by: the message's
/// sensor name, "wheels" or "steering".
std::string HealthSensorName(const formats::SensorMessage& message);

class VehicleEkf {
 public:
  /// |t| above this is refused: beyond it a double cannot resolve 0.1 ms (Unix time, 1.7e9 s, fits).
  static constexpr double kMaxTimeS = 1e12;

  /// wheel_order: the wheel names of the messages (the log header's), a permutation of the
  /// vehicle's wheel names. Throws FilterConfigError / std::invalid_argument on a bad config,
  /// origin or wheel order.
  VehicleEkf(mapio::VehicleConfig vehicle, FilterConfig config, const geometry::GeoOrigin& origin,
             const std::vector<std::string>& wheel_order);

  /// Predicts to the message's time and applies it. Throws FilterInputError (filter unchanged).
  ProcessResult Process(const formats::SensorMessage& message);

  /// Initialises (or overrides) the pose (x, y, phi) with its covariance at time_s; velocities and
  /// the other states keep their values (zero and the initial sigmas when not yet initialised).
  void SetPose(double time_s, const Eigen::Vector3d& pose, const Eigen::Matrix3d& covariance);
  /// Uses ultrasonic echoes against this row map from now on (replacing any map attached before).
  /// The map may be in another local frame: it is re-expressed in the filter's (RowMapRanging).
  /// Throws std::invalid_argument for an invalid map (e.g. no rows), or when the vehicle has no
  /// ultrasonic sensor.
  void AttachRowMap(const geometry::RowMap& map);
  bool has_row_map() const { return map_aided_.has_row_map(); }
  /// The attached row map in the filter's frame, with its spatial index; null without a map.
  std::shared_ptr<const RowMapRanging> row_map_ranging() const { return map_aided_.shared_ranging(); }
  const MapAidedStats& map_aided_stats() const { return map_aided_.stats(); }
  /// The range sigma the echoes are weighted with now, m (estimated from their innovations unless
  /// map_aided.adaptive_range_sigma is off: range_noise_estimator.hpp).
  double map_aided_range_sigma_m() const { return map_aided_.range_sigma_m(); }
  /// The filter's cache of R-tree box queries of the row map (hits and misses since construction).
  const geometry::SegmentQueryCache& row_search_cache() const { return map_aided_.row_search_cache(); }
  /// Back to the uninitialised state (keeps configuration and time).
  void Reset();
  /// The R_w and kappa priors of every wheel, from a previous drive, used at every (re-)initialisation
  /// from now on, their sigmas widened by the filter file's change between drives
  /// (slip_aware_odometry.carried_*_change_sigma*; the kappas keep its correlation); an initialised
  /// filter keeps its states. One entry per wheel of the vehicle, by name, in any order. Throws
  /// std::invalid_argument without slip-aware states, for a missing, unknown or repeated wheel, or
  /// a value outside its domain (non-finite, R_w or a sigma <= 0, kappa < 0).
  void SetWheelCalibrationPrior(const std::vector<WheelCalibrationPrior>& wheels);

  /// Fixed-interval smoothing (fixed_interval_smoother.hpp, docs/localization-filter.md §6): from
  /// now on the filter records its pass, each (re-)initialisation starting a new chain.
  /// check_transitions: also check every recorded transition (costly; for tests).
  /// Throws std::logic_error when already enabled.
  void EnableSmoothing(bool check_transitions = false);
  /// Asks for the smoothed state at the filter's current time; returns the index of this mark in
  /// FinishSmoothing's result. std::logic_error unless smoothing is enabled and the filter initialised.
  std::size_t MarkForSmoothing();
  /// Ends the recording (smoothing is then disabled) and returns the smoothed state of every mark,
  /// with R_w and kappa kept in their domains as the filter keeps its own (ProjectStates: the
  /// smoother is linear and may cross kappa = 0 where kappa is weakly observable).
  /// std::logic_error unless enabled; std::runtime_error from the smoother (fixed_interval_smoother.hpp).
  std::vector<SmoothedState> FinishSmoothing();
  /// The recorder while smoothing is enabled, else null.
  const FixedIntervalSmoother* smoother() const { return smoothing_.smoother(); }

  bool initialised() const { return initialised_; }
  double time_s() const { return time_s_; }
  const Eigen::VectorXd& state() const { return x_; }
  const Eigen::MatrixXd& covariance() const { return p_; }
  const StateLayout& layout() const { return layout_; }
  const mapio::VehicleConfig& vehicle() const { return vehicle_; }
  const FilterConfig& config() const { return config_; }

  /// SAE slip per wheel (vehicle order) from the state and the last raw encoder speeds; empty before
  /// the first wheels message or initialisation.
  std::vector<double> WheelSlip() const;
  /// The raw encoder speeds of the last wheels message (vehicle order); empty before the first.
  const std::vector<double>& last_wheel_speeds_radps() const { return last_speed_radps_; }
  /// Health of every sensor seen (sensor_health.hpp): by the message's sensor name (gps, imu, vio,
  /// ultrasonic), "wheels.<wheel>" for one encoder, or the update's name ("wheels", "nonholonomic",
  /// "steering", "torque", "wheel_angles").
  const SensorHealthMonitor& health() const { return health_; }
  /// The terrain-change detector's reports per wheel since construction (vehicle order; all 0
  /// unless slip_aware_odometry.terrain_change.enabled), including those not acted on because the
  /// wheel's speed was outside 0.5-2 times its prediction: terrain_change_detector.hpp.
  const std::vector<std::size_t>& terrain_changes() const { return terrain_change_.alarms(); }
  /// Prediction steps made since construction (at most kMaxPredictionSteps per message).
  std::size_t prediction_steps() const { return prediction_steps_; }
  /// Prediction steps per message at most, whatever max_prediction_step_s and the gap: the step
  /// grows when a span needs more.
  static constexpr long kMaxPredictionSteps = 100000;
  /// Messages refused because their time stamp jumped beyond max_time_jump_s from the filter's.
  std::size_t time_jumps_refused() const { return time_jumps_refused_; }

 private:
  void Validate(const formats::SensorMessage& message) const;
  /// Refuses (FilterInputError) a message more than max_time_jump_s from the filter's time, unless
  /// it ends a run of kTimeBaseRunMessages such messages: then the filter moves to the new time base
  /// (Reset; the notice says so).
  void CheckTimeJump(const formats::SensorMessage& message, std::optional<std::string>& notice);
  /// Feeds the message's raw readings to the health monitor (stuck sensors).
  void ObserveReadings(const formats::SensorMessage& message);
  /// Collects the health changes into the result's notice; a newly excluded sensor drops the state
  /// (it may have dragged it away) and the filter re-initialises from GNSS without it.
  void ApplyHealthChanges(ProcessResult& result);
  /// True, counted as skipped, when `sensor` is excluded: its update is not made.
  bool SkipExcluded(const std::string& sensor);
  void PredictTo(double time_s);
  ProcessResult Apply(const formats::GpsMessage& gps);
  ProcessResult Apply(const formats::ImuMessage& imu);
  ProcessResult Apply(const formats::WheelsMessage& wheels);
  /// The wheel-angle update of a wheels message with angles (wheel_angle_model.hpp); anchors the
  /// angle states to the message instead when they are not anchored yet or the update is gated out.
  /// Returns false, and the caller uses the speeds, when no wheel ticked since the last message
  /// (the vehicle is at rest; nothing else done) or when a predicted angle's sigma exceeds
  /// wheels.angle_max_prediction_sigma_rad (the angles re-anchored).
  bool ApplyWheelAngles(const formats::WheelsMessage& wheels, ProcessResult& result);
  /// The iterations after the first of the wheel-speed update (wheels.speed_update_iterations).
  void IterateWheelSpeedUpdate(const VectorRef& measured_radps);
  /// Before the wheel-speed update (its innovation and noise in update_buffers_): feeds the terrain
  /// change detector and widens the R_w variance of each wheel it reports (terrain_change_detector.hpp),
  /// unless the wheel's speed is outside 0.5-2 times its prediction (a dead encoder). Not in a turn
  /// (|yaw rate| above max_yaw_rate_radps) nor within kImuDisagreementHoldS of a gated IMU update:
  /// the sums restart. Returns the notice naming the widened wheels, if any.
  std::optional<std::string> WidenRadiiOnTerrainChange();
  /// The torque update of the traction states (the last torques, vehicle order; `torque`); a step
  /// beyond the gate re-anchors them to the torques instead.
  void ApplyTorques(double time_s, ProcessResult& result);
  /// State `index` set to `value` with `variance`, uncorrelated with the others (wheel angles and
  /// traction states anchored to their measurement).
  void Reanchor(int index, double value, double variance);
  /// Sets every wheel-angle state to the last planned angles (wheel_angles_.measured(), vehicle
  /// order) with the quantization variance, uncorrelated with the other states.
  void AnchorWheelAngles();
  ProcessResult Apply(const formats::SteeringMessage& steering);
  ProcessResult Apply(const formats::VioMessage& vio);
  ProcessResult Apply(const formats::UltrasonicMessage& ping);
  std::optional<std::string> TryInitialise(const formats::GpsMessage& gps, const Eigen::Vector2d& antenna_enu);
  /// A fix waiting for the initialisation, with the distance the wheels rolled until it.
  struct PendingFix {
    double time_s = 0.0;
    Eigen::Vector2d antenna_enu = Eigen::Vector2d::Zero();
    double sigma_m = 0.0;
    double travelled_m = 0.0;
  };
  /// The oldest pending fix at least baseline_m from `current` that agrees with it and with some
  /// pending fix between them (the consensus), or null.
  const PendingFix* FindAnchor(const PendingFix& current, double baseline_m) const;
  /// The mean steering angle of the last steering message (0 without one), rad.
  double MeanSteering() const;
  /// The heading a GNSS displacement gives: its course, reversed when the wheels turn backwards,
  /// minus the mean steering angle.
  double CourseToHeading(const Eigen::Vector2d& moved) const;
  /// Map-aided initialisation (vehicle_ekf_initialisation.cpp): the heading along the lane the
  /// pending fixes and `current` lie in, its direction from their regression on the distance
  /// rolled; none until that is certain.
  std::optional<double> LaneHeading(const PendingFix& current) const;
  /// Two pending fixes agree with each other and with the odometry between them.
  bool FixesAgree(const PendingFix& a, const PendingFix& b) const;
  /// Before initialisation: the wheel-centre distance rolled since the last wheels message.
  void AccumulateOdometry(double time_s);
  /// position_from_gnss: the pose's position is a fix's, so it carries the GNSS bias (if estimated).
  void InitialiseState(double time_s, const Eigen::Vector3d& pose, const Eigen::Matrix3d& pose_covariance,
                       bool position_from_gnss = false);
  /// Keeps the states in their domains: steering angles wrapped to (-pi, pi]; R_w within
  /// [0.5, 1.5] x nominal; the slip compliance kappa >= 0 and, for a traction coefficient mu > 0,
  /// kappa mu <= max_model_slip (so that 1 - kappa mu > 0). mu: the last wheels message's torques;
  /// without torques, with before_wheel_model and traction_from_acceleration, the motion's
  /// (WheelTractionCoefficient); else none. A crossed limit is projected with the covariance
  /// (state_bound.hpp: the correlated states move with it; docs/notes/2026-12-02-localization-filter.md §5.8).
  void ProjectStates(bool before_wheel_model = false);
  /// Wheel `wheel`'s R_w within [0.5, 1.5] x nominal and kappa >= 0 (the part of ProjectStates
  /// that needs no mu; applied to smoothed states too). The layout must be slip-aware.
  void ClampWheelCalibration(Eigen::VectorXd& x, std::size_t wheel) const;
  UpdateRecord Update(double time_s, const std::string& sensor, const VectorRef& innovation,
                      const MatrixRef& jacobian, const MatrixRef& noise, double gate);

  mapio::VehicleConfig vehicle_;
  FilterConfig config_;
  StateLayout layout_;
  mapio::LocalFrame frame_;
  std::vector<std::size_t> wheel_index_;  ///< message wheel j -> vehicle wheel wheel_index_[j]
  double gate_gps_, gate_imu_, gate_vio_;
  std::vector<double> wheel_gates_;     ///< index m - 1: gate of an m-dimensional wheel/lateral update
  std::vector<double> steering_gates_;  ///< index m - 1: gate of m steering angles

  bool initialised_ = false;
  double time_s_ = -std::numeric_limits<double>::infinity();
  Eigen::VectorXd x_;
  Eigen::MatrixXd p_;
  std::optional<double> gps_gated_since_s_;   ///< first gated fix since the last accepted one
  std::vector<PendingFix> pending_fixes_;  ///< fixes while waiting for the initialisation (consensus)
  double travelled_m_ = 0.0;                ///< odometry before initialisation, m
  std::optional<double> odometry_time_s_;   ///< time of the last wheels message before initialisation
  SensorHealthMonitor health_;
  std::size_t exclusions_seen_ = 0;          ///< sensors excluded so far (ApplyHealthChanges)
  std::string last_gnss_sensor_;             ///< the sensor name of the last GNSS fix
  std::size_t time_jump_run_ = 0;            ///< consecutive messages refused for a time jump
  std::size_t time_jumps_refused_ = 0;
  std::size_t prediction_steps_ = 0;
  std::vector<double> last_speed_radps_;       ///< vehicle order; empty before the first wheels message
  /// The last wheels message's torques (last_torque_nm()) and the torque update of the traction states.
  TractionUpdater traction_;
  /// When and how the encoders' angles update the wheel-angle states (anchoring).
  WheelAngleUpdater wheel_angles_;
  /// A change of terrain under a wheel from its speed innovations (if enabled).
  TerrainChangeDetector terrain_change_;
  /// When an IMU update was last gated out, s (-inf: none since the last reset).
  double imu_gated_s_ = -std::numeric_limits<double>::infinity();
  std::vector<std::optional<double>> last_steering_rad_;
  /// The echoes' map-aided measurement (row map, rangers, counts, map agreement); the filter
  /// applies what it returns to the full state.
  MapAidedUpdater map_aided_;
  /// The GNSS-bias states' process, measurement columns and initialisation (if estimated).
  GnssBiasModel gnss_bias_;
  /// Reused by every update (no state: scratch), so that a message allocates nothing for its
  /// linearization, innovation and noise once their sizes repeat: one linearization per kind of
  /// message, whose size never changes (the wheel speeds and the non-holonomic rows share one).
  struct UpdateBuffers {
    LinearizedMeasurement gnss, imu, wheels, steering, vio;
    WheelAngleScratch wheel_rates;      ///< the wheel-angle prediction's omega(x), J and products
    Eigen::VectorXd innovation;
    Eigen::VectorXd normalized;  ///< the wheel speeds' innovations over their sigmas (terrain change)
    Eigen::MatrixXd noise;
    std::vector<std::size_t> steered_wheels;  ///< the vehicle wheels with a steering angle
    std::vector<double> steered_angles;       ///< their angles
    std::vector<double> max_slip_compliance;  ///< ProjectStates: max_model_slip / mu per wheel
    Eigen::VectorXd prior_state;              ///< the iterated wheel-speed update: x0, P0, x0 - x_i
    Eigen::MatrixXd prior_covariance;
    Eigen::VectorXd step;
  };
  UpdateBuffers update_buffers_;
  /// Records the pass for the fixed-interval smoother while smoothing is enabled (every hook a no-op
  /// otherwise).
  SmoothingRecorder smoothing_;
  std::vector<WheelCalibrationPrior> calibration_prior_;  ///< vehicle order, sigmas widened; or empty: the filter file's
};

}  // namespace rowloc::localization
