#include "rowloc/localization/vehicle_ekf.hpp"

#include "rowloc/localization/measurement_models.hpp"
#include "rowloc/localization/process_model.hpp"
#include "rowloc/localization/state_bound.hpp"
#include "rowloc/localization/wheel_angle_model.hpp"
#include "rowloc/localization/wheel_slip_estimate.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

namespace rowloc::localization {

using L = StateLayout;

/// R_w's domain, a factor of the nominal radius (ProjectStates, ClampWheelCalibration).
constexpr double kMinRadiusFactor = 0.5;
constexpr double kMaxRadiusFactor = 1.5;
/// Measurement variance of an excluded encoder's row: its reading then moves nothing (rad/s)^2.
constexpr double kExcludedVariance = 1e12;
/// Ground changes are not looked for this long after an IMU update was gated out, s.
constexpr double kImuDisagreementHoldS = 1.0;

namespace {

std::vector<std::size_t> WheelIndex(const mapio::VehicleConfig& vehicle, const std::vector<std::string>& order) {
  if (order.size() != vehicle.wheels.size()) {
    throw std::invalid_argument("wheel order: " + std::to_string(order.size()) + " wheels, the vehicle '" +
                                vehicle.name + "' has " + std::to_string(vehicle.wheels.size()));
  }
  std::vector<std::size_t> index(order.size());
  std::vector<bool> used(order.size(), false);
  for (std::size_t j = 0; j < order.size(); ++j) {
    const auto it = std::find_if(vehicle.wheels.begin(), vehicle.wheels.end(),
                                 [&](const mapio::WheelGeometry& w) { return w.name == order[j]; });
    if (it == vehicle.wheels.end()) {
      throw std::invalid_argument("wheel order: '" + order[j] + "' is not a wheel of the vehicle '" + vehicle.name + "'");
    }
    index[j] = static_cast<std::size_t>(it - vehicle.wheels.begin());
    if (used[index[j]]) throw std::invalid_argument("wheel order: '" + order[j] + "' appears twice");
    used[index[j]] = true;
  }
  return index;
}

FilterConfig Checked(FilterConfig config) {
  if (const auto problem = FilterConfigProblem(config)) throw FilterConfigError("filter config: " + *problem);
  return config;
}

mapio::VehicleConfig Checked(mapio::VehicleConfig vehicle) {
  if (const auto problem = mapio::VehicleConfigProblem(vehicle)) {
    throw std::invalid_argument("vehicle config: " + *problem);
  }
  return vehicle;
}

Eigen::Matrix2d Rotation(double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return (Eigen::Matrix2d() << c, -s, s, c).finished();
}

}  // namespace

VehicleEkf::VehicleEkf(mapio::VehicleConfig vehicle, FilterConfig config, const geometry::GeoOrigin& origin,
                       const std::vector<std::string>& wheel_order)
    : vehicle_(Checked(std::move(vehicle))),
      config_(Checked(std::move(config))),
      layout_(StateLayout::For(vehicle_, {.slip_aware_odometry = config_.slip_aware_odometry.enabled,
                                          .accel_bias = config_.imu.estimate_accel_bias,
                                          .wheel_angles = config_.wheels.angle_measurement,
                                          .traction = config_.slip_aware_odometry.torque_sigma_nm > 0.0,
                                          .gnss_bias = config_.gps.estimate_bias})),
      frame_(origin),
      wheel_index_(WheelIndex(vehicle_, wheel_order)),
      gate_gps_(ChiSquareGate(2, config_.gps.gate_probability)),
      gate_imu_(ChiSquareGate(3, config_.imu.gate_probability)),
      gate_vio_(ChiSquareGate(2, config_.vio.gate_probability)),
      traction_(vehicle_, config_, layout_),
      wheel_angles_(config_.wheels, layout_),
      terrain_change_(vehicle_.wheels.size(), config_.slip_aware_odometry.terrain_change),
      map_aided_(vehicle_, config_.map_aided, frame_.origin()),
      gnss_bias_(config_.gps, layout_),
      smoothing_(layout_) {
  // Quantiles are costly (Boost.Math root finding): computed once per dimension, not per message.
  for (int m = 1; m <= static_cast<int>(vehicle_.wheels.size()); ++m) {
    wheel_gates_.push_back(ChiSquareGate(m, config_.wheels.gate_probability));
    steering_gates_.push_back(ChiSquareGate(m, config_.steering.gate_probability));
  }
  Reset();
}

void VehicleEkf::Reset() {
  if (initialised_) smoothing_.End(x_, p_);
  initialised_ = false;
  pending_fixes_.clear();
  travelled_m_ = 0.0;
  odometry_time_s_.reset();
  wheel_angles_.Unanchor();
  terrain_change_.Reset();
  imu_gated_s_ = -std::numeric_limits<double>::infinity();
  x_ = Eigen::VectorXd::Zero(layout_.size);
  p_ = Eigen::MatrixXd::Zero(layout_.size, layout_.size);
}

ProcessResult VehicleEkf::Process(const formats::SensorMessage& message) {
  std::optional<std::string> gap_notice;
  CheckTimeJump(message, gap_notice);  // a moved time base resets the filter first
  try {
    Validate(message);
  } catch (const FilterInputError& e) {
    health_.ObserveRefusal(HealthSensorName(message), e.what());
    throw;
  }
  const double t = formats::TimeOf(message);
  if (initialised_ && t - time_s_ > config_.max_prediction_gap_s) {
    std::ostringstream notice;
    notice << "no message for " << t - time_s_ << " s (> max_prediction_gap_s " << config_.max_prediction_gap_s
           << "): state dropped, re-initialising from GNSS";
    Reset();
    gap_notice = notice.str();
  }
  health_.ObserveAccepted(HealthSensorName(message));
  ObserveReadings(message);
  if (initialised_) PredictTo(t);
  time_s_ = t;
  ProcessResult result = std::visit([this](const auto& m) { return Apply(m); }, message);
  if (gap_notice) {  // the re-initialisation comes first
    result.notice = result.notice ? *gap_notice + "; " + *result.notice : std::move(gap_notice);
  }
  ProjectStates();
  ApplyHealthChanges(result);
  return result;
}

void VehicleEkf::PredictTo(double t) {
  const double span = t - time_s_;
  if (!(span > 0.0)) return;
  // At most kMaxPredictionSteps steps per message, whatever the configuration: the step grows
  // when the span needs more (a prediction step of 1e-300 s once made no progress at all).
  const double step = std::max(config_.max_prediction_step_s, span / static_cast<double>(kMaxPredictionSteps));
  double remaining = span;
  for (long steps = 0; remaining > 0.0 && steps <= kMaxPredictionSteps; ++steps) {
    const double dt = steps == kMaxPredictionSteps ? remaining : std::min(remaining, step);
    smoothing_.BeginTransition(x_, p_);
    if (layout_.has_wheel_angles()) {  // before the base step: F = F_base (I + dt E J), wheel_angle_model.hpp
      ProjectStates(true);              // kappa mu <= max_model_slip before linearizing 1 / (1 - kappa mu)
      PropagateWheelAngles(vehicle_, layout_, config_, traction_.last_torque_nm(), x_, p_, dt, update_buffers_.wheel_rates);
      smoothing_.TransitionAddRows(layout_.wheel_angle, dt, update_buffers_.wheel_rates.rates.jacobian);
    }
    if (smoothing_.enabled()) {  // the base Jacobian only for the smoother
      BaseJacobian f;
      PredictStep(vehicle_, layout_, config_, x_, p_, dt, &f);
      smoothing_.TransitionBlock(0, f);
      if (gnss_bias_.estimated()) smoothing_.TransitionBlock(gnss_bias_.index(), gnss_bias_.Transition(dt));
    } else {
      PredictStep(vehicle_, layout_, config_, x_, p_, dt);
    }
    remaining -= dt;
    ++prediction_steps_;
  }
}

UpdateRecord VehicleEkf::Update(double t, const std::string& sensor, const VectorRef& innovation,
                                const MatrixRef& jacobian, const MatrixRef& noise, double gate) {
  if (!(innovation.allFinite() && jacobian.allFinite() && noise.allFinite())) {
    // The inputs were checked, so this is the state or a model gone wrong: name the update.
    std::ostringstream text;
    text << "the " << sensor << " update at t=" << t << " s has a non-finite "
         << (!innovation.allFinite() ? "innovation" : !jacobian.allFinite() ? "Jacobian" : "noise")
         << ": message refused";
    health_.ObserveRefusal(sensor, "non-finite update");
    throw FilterInputError(text.str());
  }
  smoothing_.BeginUpdate(x_, p_);
  UpdateRecord record{t, sensor, KalmanUpdate(x_, p_, innovation, jacobian, noise, gate, L::kPhi)};
  health_.ObserveUpdate(sensor, record.outcome.accepted);
  return record;
}

ProcessResult VehicleEkf::Apply(const formats::GpsMessage& gps) {
  ProcessResult result;
  if (!gps.position) return result;  // no fix: nothing measured
  if (last_gnss_sensor_ != gps.sensor) last_gnss_sensor_ = gps.sensor;
  if (SkipExcluded(gps.sensor)) return result;  // a frozen receiver (sensor_health.hpp)
  const formats::GpsPosition& fix = *gps.position;
  const Eigen::Vector2d antenna = frame_.ToEnu(fix.latitude_deg, fix.longitude_deg, fix.altitude_m).head<2>();
  if (!initialised_) {
    result.notice = TryInitialise(gps, antenna);
    return result;
  }
  const double sigma = GpsSigma(config_.gps, gps.fix, fix.sigma_horizontal_m);
  LinearizedMeasurement& h = update_buffers_.gnss;
  gnss_bias_.MeasureAntenna(x_, vehicle_.gnss_antenna.position_m.head<2>(), h);
  const Eigen::Matrix2d noise = Eigen::Matrix2d::Identity() * sigma * sigma;
  const Eigen::Vector2d innovation = antenna - h.predicted;
  double gate = gate_gps_;
  if (gps_gated_since_s_ && gps.time_s - *gps_gated_since_s_ > config_.gps.reacquire_after_s) {
    smoothing_.BeginTransition(x_, p_);  // added noise: no change of the transition
    p_.topLeftCorner<2, 2>() += innovation * innovation.transpose();
    gate = std::numeric_limits<double>::infinity();
    std::ostringstream notice;
    notice << "GNSS re-acquired at t=" << gps.time_s << " s: every fix gated out for "
           << gps.time_s - *gps_gated_since_s_ << " s (innovation " << innovation.norm() << " m)";
    result.notice = notice.str();
  }
  result.updates.push_back(Update(gps.time_s, gps.sensor, innovation, h.jacobian, noise, gate));
  if (result.updates.back().outcome.accepted) {
    gps_gated_since_s_.reset();
  } else if (!gps_gated_since_s_) {
    gps_gated_since_s_ = gps.time_s;
  }
  return result;
}

ProcessResult VehicleEkf::Apply(const formats::ImuMessage& imu) {
  ProcessResult result;
  if (!initialised_ || SkipExcluded(imu.sensor)) return result;
  // Specific force in the IMU's axes rotated into the body frame by the mount's yaw.
  const Eigen::Vector2d force = Rotation(vehicle_.imu.yaw_rad) * Eigen::Vector2d(imu.accel_x_mps2, imu.accel_y_mps2);
  const Eigen::Vector3d z(force.x(), force.y(), imu.gyro_z_radps);
  LinearizedMeasurement& h = update_buffers_.imu;
  ImuModel(x_, vehicle_.imu.position_m.head<2>(), layout_.accel_bias, h);
  const double a = config_.imu.accel_sigma_mps2 * config_.imu.accel_sigma_mps2;
  const double g = config_.imu.gyro_sigma_radps * config_.imu.gyro_sigma_radps;
  const Eigen::Matrix3d noise = Eigen::Vector3d(a, a, g).asDiagonal();
  const Eigen::Vector3d innovation = z - h.predicted;
  result.updates.push_back(Update(imu.time_s, imu.sensor, innovation, h.jacobian, noise, gate_imu_));
  if (!result.updates.back().outcome.accepted) imu_gated_s_ = imu.time_s;
  return result;
}

ProcessResult VehicleEkf::Apply(const formats::WheelsMessage& wheels) {
  const std::size_t n = vehicle_.wheels.size();
  if (!initialised_) AccumulateOdometry(wheels.time_s);  // with the previous message's speeds
  last_speed_radps_.assign(n, 0.0);
  for (std::size_t j = 0; j < n; ++j) last_speed_radps_[wheel_index_[j]] = wheels.speed_radps[j];
  traction_.ObserveTorques(wheels, wheel_index_);
  ProcessResult result;
  if (!initialised_) return result;
  UpdateBuffers& b = update_buffers_;
  const auto m = static_cast<Eigen::Index>(n);
  const double gate = wheel_gates_[n - 1];
  if (layout_.has_traction() && wheels.torque_nm) ApplyTorques(wheels.time_s, result);
  if (!(layout_.has_wheel_angles() && wheels.angle_rad && ApplyWheelAngles(wheels, result))) {
    ProjectStates(true);  // kappa mu <= max_model_slip before linearizing 1 / (1 - kappa mu)
    WheelSpeedModel(x_, vehicle_, layout_, traction_.last_torque_nm(), config_.wheels.encoder_low_pass_time_constant_s,
                    config_.slip_aware_odometry.traction_from_acceleration, b.wheels);
    const Eigen::Map<const Eigen::VectorXd> z(last_speed_radps_.data(), m);
    const double s = config_.wheels.speed_sigma_radps, f = config_.wheels.speed_sigma_fraction;
    b.noise.setZero(m, m);
    b.noise.diagonal() = (s * s + (f * z.array()).square()).matrix();
    if (health_.exclusions() > 0) {  // an excluded encoder (stuck) carries no information
      for (std::size_t i = 0; i < n; ++i) {
        if (health_.Excluded("wheels." + vehicle_.wheels[i].name)) b.noise(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i)) = kExcludedVariance;
      }
    }
    b.innovation = z - b.wheels.predicted;
    if (auto notice = WidenRadiiOnTerrainChange()) result.notice = result.notice ? *result.notice + "; " + *notice : *notice;
    const bool iterated = config_.wheels.speed_update_iterations > 1;
    if (iterated) {
      b.prior_state = x_;
      b.prior_covariance = p_;
    }
    result.updates.push_back(Update(wheels.time_s, "wheels", b.innovation, b.wheels.jacobian, b.noise, gate));
    if (iterated && result.updates.back().outcome.accepted) IterateWheelSpeedUpdate(z);
  }
  // Non-holonomic constraint: no sideways wheel velocity (pseudo-measurement z = 0).
  WheelLateralVelocityModel(x_, vehicle_, layout_, b.wheels);
  const double l = config_.wheels.lateral_velocity_sigma_mps;
  b.noise.setZero(m, m);
  b.noise.diagonal().setConstant(l * l);
  b.innovation = -b.wheels.predicted;
  result.updates.push_back(Update(wheels.time_s, "nonholonomic", b.innovation, b.wheels.jacobian, b.noise, gate));
  return result;
}

std::optional<std::string> VehicleEkf::WidenRadiiOnTerrainChange() {
  const TerrainChangeConfig& c = config_.slip_aware_odometry.terrain_change;
  if (!c.enabled || !layout_.slip_aware()) return std::nullopt;
  // In a turn the slips change and come back; within a second of an IMU update gated out the IMU,
  // not the ground, may be what changed (a dead IMU reads zeros: two updates are gated, then the
  // filter follows it and the wheels disagree with the state it dragged). Either way the sums
  // restart.
  if (std::abs(x_(L::kYawRate)) > c.max_yaw_rate_radps || time_s_ - imu_gated_s_ < kImuDisagreementHoldS) {
    terrain_change_.Reset();
    return std::nullopt;
  }
  UpdateBuffers& b = update_buffers_;
  const Eigen::Index m = b.innovation.size();
  b.normalized.resize(m);
  for (Eigen::Index i = 0; i < m; ++i) {
    const double s = b.wheels.jacobian.row(i) * p_ * b.wheels.jacobian.row(i).transpose() + b.noise(i, i);
    b.normalized(i) = b.noise(i, i) >= kExcludedVariance ? std::numeric_limits<double>::quiet_NaN()
                                                          : b.innovation(i) / std::sqrt(s);
  }
  const std::vector<std::size_t>& fired = terrain_change_.Observe(b.normalized);
  std::string wheels;
  std::vector<std::size_t> widened;
  for (const std::size_t i : fired) {
    // Ground halves or doubles a wheel's speed at most; a stuck or dead encoder (0 rad/s) is left
    // to the sensor health, not learnt as a radius.
    const double ratio = last_speed_radps_[i] / b.wheels.predicted(static_cast<Eigen::Index>(i));
    if (ratio >= 0.5 && ratio <= 2.0) widened.push_back(i);
  }
  if (widened.empty()) return std::nullopt;
  smoothing_.BeginTransition(x_, p_);
  for (const std::size_t i : widened) {
    const double sigma = c.radius_sigma_fraction * vehicle_.wheels[i].nominal_radius_m;
    const int r = layout_.rolling_radius[i];
    p_(r, r) += sigma * sigma;
    wheels += (wheels.empty() ? "" : ", ") + vehicle_.wheels[i].name;
  }
  return "ground change under " + wheels + ": the wheel speed left the rolling radius's prediction, its sigma widened";
}

void VehicleEkf::IterateWheelSpeedUpdate(const VectorRef& measured_radps) {
  // Iterated EKF (filter_config.hpp, wheels.speed_update_iterations): from the prior (x0, P0),
  // x_{i+1} = x0 + K_i (z - h(x_i) - H_i (x0 - x_i)), H_i and K_i at x_i; P from the last one.
  // The gate was passed at the first linearization; the record keeps that update's NIS.
  UpdateBuffers& b = update_buffers_;
  for (int i = 1; i < config_.wheels.speed_update_iterations; ++i) {
    ProjectStates(true);  // the linearization point inside the model's domain
    WheelSpeedModel(x_, vehicle_, layout_, traction_.last_torque_nm(), config_.wheels.encoder_low_pass_time_constant_s,
                    config_.slip_aware_odometry.traction_from_acceleration, b.wheels);
    b.step = b.prior_state - x_;
    b.step(L::kPhi) = WrapAngle(b.step(L::kPhi));
    b.innovation = measured_radps - b.wheels.predicted - b.wheels.jacobian * b.step;
    x_ = b.prior_state;
    p_ = b.prior_covariance;
    KalmanUpdate(x_, p_, b.innovation, b.wheels.jacobian, b.noise, std::numeric_limits<double>::infinity(), L::kPhi);
  }
}

void VehicleEkf::ApplyTorques(double time_s, ProcessResult& result) {
  const TractionMeasurement& m = traction_.Measure(x_);  // mu = T / (N r) per wheel
  result.updates.push_back(Update(time_s, "torque", m.innovation, m.model.jacobian, m.noise, m.gate));
  if (result.updates.back().outcome.accepted) return;
  // A torque step (the drive changed its command): the traction states jump to the measurement,
  // uncorrelated with the rest; the smoothing starts again from there.
  for (std::size_t i = 0; i < layout_.traction.size(); ++i) {
    const auto row = static_cast<Eigen::Index>(i);
    Reanchor(layout_.traction[i], m.measured(row), m.noise(row, row));
  }
}

void VehicleEkf::Reanchor(int index, double value, double variance) {
  smoothing_.BeginTransition(x_, p_, {index});
  p_.row(index).setZero();
  p_.col(index).setZero();
  p_(index, index) = variance;
  x_(index) = value;
}

bool VehicleEkf::ApplyWheelAngles(const formats::WheelsMessage& wheels, ProcessResult& result) {
  switch (wheel_angles_.Plan(wheels, wheel_index_, p_)) {  // wheel_angle_updater.hpp says when
    case WheelAngleStep::kUseSpeeds: return false;
    case WheelAngleStep::kAnchorAndUseSpeeds: AnchorWheelAngles(); return false;
    case WheelAngleStep::kAnchor: AnchorWheelAngles(); return true;
    case WheelAngleStep::kUpdate: break;
  }
  const WheelAngleMeasurement& m = wheel_angles_.Measure(x_);
  result.updates.push_back(Update(wheels.time_s, "wheel_angles", m.innovation, m.model.jacobian, m.noise, m.gate));
  if (result.updates.back().outcome.accepted) return true;
  result.notice = "wheel angles gated out at t=" + std::to_string(wheels.time_s) + " s: re-anchored to the encoders";
  AnchorWheelAngles();  // only the angle's offset is lost
  return true;
}

void VehicleEkf::AnchorWheelAngles() {
  const Eigen::VectorXd& z = wheel_angles_.measured();
  for (std::size_t i = 0; i < layout_.wheel_angle.size(); ++i) {
    Reanchor(layout_.wheel_angle[i], z(static_cast<Eigen::Index>(i)), wheel_angles_.anchor_variance());
  }
  wheel_angles_.MarkAnchored();
}

ProcessResult VehicleEkf::Apply(const formats::SteeringMessage& steering) {
  last_steering_rad_.assign(vehicle_.wheels.size(), std::nullopt);
  UpdateBuffers& b = update_buffers_;
  std::vector<std::size_t>& wheels = b.steered_wheels;
  std::vector<double>& angles = b.steered_angles;
  wheels.clear();
  angles.clear();
  for (std::size_t j = 0; j < steering.angle_rad.size(); ++j) {
    const std::size_t i = wheel_index_[j];
    last_steering_rad_[i] = steering.angle_rad[j];
    if (steering.angle_rad[j] && layout_.steering[i] >= 0) {
      wheels.push_back(i);
      angles.push_back(*steering.angle_rad[j]);
    }
  }
  ProcessResult result;
  if (!initialised_ || wheels.empty()) return result;
  SteeringModel(x_, layout_, wheels, b.steering);
  const auto m = static_cast<Eigen::Index>(wheels.size());
  const Eigen::Map<const Eigen::VectorXd> z(angles.data(), m);
  const double s = config_.steering.angle_sigma_rad;
  b.noise.setZero(m, m);
  b.noise.diagonal().setConstant(s * s);
  const double gate = steering_gates_[static_cast<std::size_t>(m) - 1];
  // Swerve modules turn through +-pi: the innovation is an angle difference.
  b.innovation = (z - b.steering.predicted).unaryExpr([](double d) { return WrapAngle(d); });
  result.updates.push_back(Update(steering.time_s, "steering", b.innovation, b.steering.jacobian, b.noise, gate));
  return result;
}

ProcessResult VehicleEkf::Apply(const formats::VioMessage& vio) {
  ProcessResult result;
  if (!initialised_) return result;
  LinearizedMeasurement& h = update_buffers_.vio;
  VioModel(x_, config_.vio.position_m, h);
  const double s = config_.vio.sigma_scale * vio.sigma_mps;
  const Eigen::Matrix2d noise = Eigen::Matrix2d::Identity() * s * s;
  const Eigen::Vector2d z(vio.velocity_x_mps, vio.velocity_y_mps);
  const Eigen::Vector2d innovation = z - h.predicted;
  result.updates.push_back(Update(vio.time_s, vio.sensor, innovation, h.jacobian, noise, gate_vio_));
  return result;
}

std::vector<double> VehicleEkf::WheelSlip() const {
  if (!initialised_ || last_speed_radps_.empty()) return {};
  return EstimateWheelSlip(x_, vehicle_, layout_, last_speed_radps_, config_.slip_aware_odometry.slip_with_rolling_radius);
}

void VehicleEkf::ProjectStates(bool before_wheel_model) {
  if (!initialised_) return;
  const auto wrap_steering = [this] {
    for (const int d : layout_.steering) {
      if (d >= 0) x_(d) = WrapAngle(x_(d));
    }
  };
  wrap_steering();
  if (!layout_.slip_aware()) return;
  const SlipAwareOdometryConfig& slip = config_.slip_aware_odometry;
  // The traction from the acceleration (a sine and cosine per wheel) only matters where the wheel
  // model linearizes 1 / (1 - kappa mu): checked there, not after every message.
  const bool from_acceleration = before_wheel_model && slip.traction_from_acceleration;
  std::vector<double>& max_kappa = update_buffers_.max_slip_compliance;
  max_kappa.resize(layout_.wheel_count());
  bool projected = false;
  const auto project = [&](int index, double bound) {
    ProjectOntoBound(x_, p_, index, bound);
    projected = true;
  };
  for (std::size_t i = 0; i < layout_.wheel_count(); ++i) {
    const double nominal = vehicle_.wheels[i].nominal_radius_m;
    const int radius = layout_.rolling_radius[i], kappa = layout_.slip_compliance[i];
    if (x_(radius) < kMinRadiusFactor * nominal) project(radius, kMinRadiusFactor * nominal);
    if (x_(radius) > kMaxRadiusFactor * nominal) project(radius, kMaxRadiusFactor * nominal);
    if (x_(kappa) < 0.0) project(kappa, 0.0);
    const double mu = WheelTractionCoefficient(x_, vehicle_, layout_, i, traction_.last_torque_nm(), from_acceleration);
    max_kappa[i] = mu > 0.0 ? slip.max_model_slip / mu : std::numeric_limits<double>::infinity();
    if (x_(kappa) > max_kappa[i]) project(kappa, max_kappa[i]);
  }
  if (!projected) return;
  // A projection moves every correlated state, the heading and steering angles too: wrapped again.
  // A later wheel's projection moves the earlier wheels' correlated states, by little: the limits
  // themselves are then kept exactly.
  x_(L::kPhi) = WrapAngle(x_(L::kPhi));
  wrap_steering();
  for (std::size_t i = 0; i < layout_.wheel_count(); ++i) {
    ClampWheelCalibration(x_, i);
    double& kappa = x_(layout_.slip_compliance[i]);
    kappa = std::min(kappa, max_kappa[i]);
  }
}

void VehicleEkf::ClampWheelCalibration(Eigen::VectorXd& x, std::size_t wheel) const {
  const double nominal = vehicle_.wheels[wheel].nominal_radius_m;
  double& radius = x(layout_.rolling_radius[wheel]);
  radius = std::clamp(radius, kMinRadiusFactor * nominal, kMaxRadiusFactor * nominal);
  double& kappa = x(layout_.slip_compliance[wheel]);
  kappa = std::max(kappa, 0.0);
}

}  // namespace rowloc::localization
