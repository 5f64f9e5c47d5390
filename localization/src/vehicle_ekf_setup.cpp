// VehicleEkf: input checks and initialisation (vehicle_ekf.hpp; docs/localization-filter.md §2).
#include "rowloc/localization/vehicle_ekf.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

namespace rowloc::localization {

using L = StateLayout;

namespace {

[[noreturn]] void Reject(const formats::SensorMessage& message, const std::string& reason) {
  std::ostringstream text;
  text << formats::TypeOf(message) << " at t=" << formats::TimeOf(message) << " s: " << reason;
  throw FilterInputError(text.str());
}

/// "type.field" or "type.field.wheel": the key path of a message's value as the log writes it
/// (docs/protocol.md: per-wheel values are objects keyed by wheel name).
std::string KeyOf(const formats::SensorMessage& message, const char* field, const std::string& wheel = "") {
  std::string key = std::string(formats::TypeOf(message)) + "." + field;
  if (!wheel.empty()) key += "." + wheel;
  return key;
}

/// "key = value is outside [low, high]" with short numbers (6 significant digits).
std::string OutsideText(const std::string& key, double value, double low, double high, const char* why = "") {
  std::ostringstream text;
  text << std::setprecision(6) << key << " = " << value << " is outside [" << low << ", " << high << "]" << why;
  return text.str();
}

void RequireFinite(const formats::SensorMessage& message, double value, const char* field,
                   const std::string& wheel = "") {
  if (!std::isfinite(value)) Reject(message, KeyOf(message, field, wheel) + " must be finite");
}

void RequirePositive(const formats::SensorMessage& message, double value, const char* field) {
  if (!(std::isfinite(value) && value > 0.0)) Reject(message, KeyOf(message, field) + " must be finite and > 0");
}

/// A claimed 1-sigma must be positive and below kMaxSigma (its square must stay far from overflow;
/// a receiver claiming kilometres has no position worth fusing).
constexpr double kMaxSigma = 1e4;

void RequireSigma(const formats::SensorMessage& message, double value, const char* field) {
  RequirePositive(message, value, field);
  if (value > kMaxSigma) Reject(message, OutsideText(KeyOf(message, field), value, 0.0, kMaxSigma, " (out of range)"));
}

/// Magnitudes no sensor of a ground robot produces: a value beyond one is a fault, refused like a
/// non-finite one (a torque of 1e300 once passed the finiteness check and made the covariance NaN).
constexpr double kMaxTorqueNm = 1e5;           ///< a tractor's wheel sees about 1e4 N m
constexpr double kMaxAccelerationMps2 = 1e4;   ///< 1000 g, beyond any MEMS range
constexpr double kMaxYawRateRadps = 100.0;     ///< 16 turns a second
constexpr double kMaxVelocityMps = 1e5;
constexpr double kMaxAltitudeM = 1e5;          ///< |altitude| above the ellipsoid
constexpr double kMaxRangeM = 1e3;
constexpr double kMaxWheelAngleRad = 1e12;     ///< a wheel turning at 100 rad/s for 300 years

void RequireWithin(const formats::SensorMessage& message, double value, double limit, const char* field,
                   const std::string& wheel = "") {
  RequireFinite(message, value, field, wheel);
  if (std::abs(value) > limit) {
    Reject(message, OutsideText(KeyOf(message, field, wheel), value, -limit, limit, " (no sensor produces it)"));
  }
}

}  // namespace

void VehicleEkf::Validate(const formats::SensorMessage& message) const {
  const double t = formats::TimeOf(message);
  RequireFinite(message, t, "t");
  // Beyond 1e12 s (31,700 years) a double's resolution exceeds 0.1 ms: stamps offset by 1e18 s all
  // round to the same instant, and the filter would stand still on them.
  if (std::abs(t) > kMaxTimeS) Reject(message, OutsideText(KeyOf(message, "t"), t, -kMaxTimeS, kMaxTimeS, " s (a clock fault)"));
  if (t < time_s_) {
    std::ostringstream reason;
    reason << "time goes backwards (previous message at t=" << time_s_ << " s)";
    Reject(message, reason.str());
  }
  const std::size_t n = vehicle_.wheels.size();
  const auto name = [this](std::size_t j) -> const std::string& { return vehicle_.wheels[wheel_index_[j]].name; };
  if (const auto* gps = std::get_if<formats::GpsMessage>(&message); gps && gps->position) {
    const formats::GpsPosition& p = *gps->position;
    RequireFinite(message, p.latitude_deg, "latitude_deg");
    RequireFinite(message, p.longitude_deg, "longitude_deg");
    RequireWithin(message, p.altitude_m, kMaxAltitudeM, "altitude_m");
    if (std::abs(p.latitude_deg) > 90.0) Reject(message, OutsideText(KeyOf(message, "latitude_deg"), p.latitude_deg, -90, 90));
    if (std::abs(p.longitude_deg) > 180.0) {
      Reject(message, OutsideText(KeyOf(message, "longitude_deg"), p.longitude_deg, -180, 180));
    }
    RequireSigma(message, p.sigma_horizontal_m, "sigma_horizontal_m");
    RequireSigma(message, p.sigma_vertical_m, "sigma_vertical_m");
  } else if (const auto* imu = std::get_if<formats::ImuMessage>(&message)) {
    RequireWithin(message, imu->accel_x_mps2, kMaxAccelerationMps2, "accel_x_mps2");
    RequireWithin(message, imu->accel_y_mps2, kMaxAccelerationMps2, "accel_y_mps2");
    RequireWithin(message, imu->gyro_z_radps, kMaxYawRateRadps, "gyro_z_radps");
  } else if (const auto* wheels = std::get_if<formats::WheelsMessage>(&message)) {
    if (wheels->speed_radps.size() != n) Reject(message, "expected " + std::to_string(n) + " wheel speeds");
    if (wheels->torque_nm && wheels->torque_nm->size() != n) Reject(message, "expected " + std::to_string(n) + " torques");
    for (std::size_t j = 0; j < n; ++j) {
      const double w = wheels->speed_radps[j];
      RequireFinite(message, w, "speed_radps", name(j));
      const double limit = config_.wheels.max_speed_radps;
      if (std::abs(w) > limit) {
        Reject(message, "|speed_radps| above wheels.max_speed_radps: " + OutsideText(KeyOf(message, "speed_radps", name(j)), w, -limit, limit));
      }
    }
    if (wheels->torque_nm) {
      for (std::size_t j = 0; j < n; ++j) RequireWithin(message, (*wheels->torque_nm)[j], kMaxTorqueNm, "torque_nm", name(j));
    }
    if (wheels->angle_rad && wheels->angle_rad->size() != n) Reject(message, "expected " + std::to_string(n) + " wheel angles");
    if (wheels->angle_rad) {
      for (std::size_t j = 0; j < n; ++j) RequireWithin(message, (*wheels->angle_rad)[j], kMaxWheelAngleRad, "angle_rad", name(j));
    }
  } else if (const auto* steering = std::get_if<formats::SteeringMessage>(&message)) {
    if (steering->angle_rad.size() != n) Reject(message, "expected " + std::to_string(n) + " steering entries");
    for (std::size_t j = 0; j < n; ++j) {
      const auto& angle = steering->angle_rad[j];
      if (!angle) continue;
      RequireFinite(message, *angle, "angle_rad", name(j));
      const double limit = vehicle_.max_steering_angle_rad + 0.1;
      if (std::abs(*angle) > limit) {
        Reject(message, "|angle_rad| above the steering limit: " + OutsideText(KeyOf(message, "angle_rad", name(j)), *angle, -limit, limit));
      }
    }
  } else if (const auto* vio = std::get_if<formats::VioMessage>(&message)) {
    RequireWithin(message, vio->velocity_x_mps, kMaxVelocityMps, "velocity_x_mps");
    RequireWithin(message, vio->velocity_y_mps, kMaxVelocityMps, "velocity_y_mps");
    RequireSigma(message, vio->sigma_mps, "sigma_mps");
  } else if (const auto* ping = std::get_if<formats::UltrasonicMessage>(&message)) {
    if (ping->range_m) {
      RequirePositive(message, *ping->range_m, "range_m");
      RequireWithin(message, *ping->range_m, kMaxRangeM, "range_m");
    }
    if (map_aided_.has_row_map() && !map_aided_.RangerIndex(ping->sensor, ping->sensor_index)) {
      Reject(message, "'" + ping->sensor + "' is not an ultrasonic sensor of the vehicle");
    }
  }
}

void VehicleEkf::InitialiseState(double t, const Eigen::Vector3d& pose, const Eigen::Matrix3d& pose_covariance,
                                 bool position_from_gnss) {
  const InitialisationConfig& init = config_.initialisation;
  x_.setZero();
  p_.setZero();
  Eigen::VectorXd variance = Eigen::VectorXd::Zero(layout_.size);
  variance(L::kVx) = variance(L::kVy) = init.velocity_sigma_mps * init.velocity_sigma_mps;
  variance(L::kYawRate) = init.yaw_rate_sigma_radps * init.yaw_rate_sigma_radps;
  variance(L::kAx) = variance(L::kAy) = init.acceleration_sigma_mps2 * init.acceleration_sigma_mps2;
  variance(L::kGyroBias) = init.gyro_bias_sigma_radps * init.gyro_bias_sigma_radps;
  const SlipAwareOdometryConfig& slip = config_.slip_aware_odometry;
  for (std::size_t i = 0; i < layout_.wheel_count(); ++i) {
    if (const int d = layout_.steering[i]; d >= 0) {
      variance(d) = init.steering_sigma_rad * init.steering_sigma_rad;
      if (i < last_steering_rad_.size() && last_steering_rad_[i]) x_(d) = *last_steering_rad_[i];
    }
    if (const int r = layout_.rolling_radius[i]; r >= 0) {
      const WheelCalibrationPrior* prior = calibration_prior_.empty() ? nullptr : &calibration_prior_[i];
      const double radius_sigma = prior ? prior->rolling_radius_sigma_m : slip.rolling_radius_sigma_m;
      const double kappa_sigma = prior ? prior->slip_compliance_sigma : slip.slip_compliance_sigma;
      x_(r) = prior ? prior->rolling_radius_m : vehicle_.wheels[i].nominal_radius_m;
      variance(r) = radius_sigma * radius_sigma;
      x_(layout_.slip_compliance[i]) = prior ? prior->slip_compliance : slip.slip_compliance_initial;
      variance(layout_.slip_compliance[i]) = kappa_sigma * kappa_sigma;
    }
  }
  if (layout_.accel_bias >= 0) {
    variance.segment<2>(layout_.accel_bias).setConstant(init.accel_bias_sigma_mps2 * init.accel_bias_sigma_mps2);
  }
  for (std::size_t i = 0; i < layout_.wheel_count(); ++i) {  // traction: the last torques, if any
    if (const int k = layout_.traction[i]; k >= 0) {
      const TractionPrior prior = traction_.Initial(i);
      x_(k) = prior.value;
      variance(k) = prior.variance;
    }
  }
  p_.diagonal() = variance;
  if (layout_.slip_aware()) {  // correlated kappas and radii (one terrain): rho sigma_a sigma_b
    const auto kappa_sigma = [&](std::size_t i) {
      return calibration_prior_.empty() ? slip.slip_compliance_sigma : calibration_prior_[i].slip_compliance_sigma;
    };
    const auto radius_sigma = [&](std::size_t i) {
      return calibration_prior_.empty() ? slip.rolling_radius_sigma_m : calibration_prior_[i].rolling_radius_sigma_m;
    };
    for (std::size_t a = 0; a < layout_.wheel_count(); ++a) {
      for (std::size_t b = 0; b < layout_.wheel_count(); ++b) {
        if (a == b) continue;
        p_(layout_.slip_compliance[a], layout_.slip_compliance[b]) =
            slip.slip_compliance_wheel_correlation * kappa_sigma(a) * kappa_sigma(b);
        p_(layout_.rolling_radius[a], layout_.rolling_radius[b]) =
            slip.rolling_radius_prior_wheel_correlation * radius_sigma(a) * radius_sigma(b);
      }
    }
  }
  x_.head<3>() = pose;
  x_(L::kPhi) = WrapAngle(pose.z());
  p_.topLeftCorner<3, 3>() = 0.5 * (pose_covariance + pose_covariance.transpose());
  gnss_bias_.Initialise(x_, p_, position_from_gnss);  // the bias states, if estimated
  time_s_ = t;
  gps_gated_since_s_.reset();
  initialised_ = true;
  pending_fixes_.clear();
  wheel_angles_.Unanchor();
  smoothing_.Start(x_, p_);
}

void VehicleEkf::SetPose(double t, const Eigen::Vector3d& pose, const Eigen::Matrix3d& covariance) {
  if (!std::isfinite(t) || t < time_s_) throw FilterInputError("SetPose: time must be finite and not before the filter's time");
  if (!pose.allFinite() || !covariance.allFinite()) throw FilterInputError("SetPose: pose and covariance must be finite");
  const Eigen::Matrix3d symmetric = 0.5 * (covariance + covariance.transpose());
  if (symmetric.llt().info() != Eigen::Success) throw FilterInputError("SetPose: covariance must be positive definite");
  if (!initialised_) {
    InitialiseState(t, pose, symmetric);
    return;
  }
  PredictTo(t);
  time_s_ = t;
  smoothing_.BeginTransition(x_, p_, {L::kX, L::kY, L::kPhi});  // the pose is set anew
  x_.head<3>() = pose;
  x_(L::kPhi) = WrapAngle(pose.z());
  p_.topRows<3>().setZero();
  p_.leftCols<3>().setZero();
  p_.topLeftCorner<3, 3>() = symmetric;
}

void VehicleEkf::SetWheelCalibrationPrior(const std::vector<WheelCalibrationPrior>& wheels) {
  if (!layout_.slip_aware()) {
    throw std::invalid_argument("wheel calibration prior: the filter has no slip-aware states (slip_aware_odometry.enabled)");
  }
  std::vector<std::optional<WheelCalibrationPrior>> ordered(vehicle_.wheels.size());
  for (const WheelCalibrationPrior& w : wheels) {
    const auto it = std::find_if(vehicle_.wheels.begin(), vehicle_.wheels.end(),
                                 [&](const mapio::WheelGeometry& g) { return g.name == w.wheel; });
    if (it == vehicle_.wheels.end()) {
      throw std::invalid_argument("wheel calibration prior: '" + w.wheel + "' is not a wheel of '" + vehicle_.name + "'");
    }
    auto& slot = ordered[static_cast<std::size_t>(it - vehicle_.wheels.begin())];
    if (slot) throw std::invalid_argument("wheel calibration prior: '" + w.wheel + "' appears twice");
    const bool valid = std::isfinite(w.rolling_radius_m) && w.rolling_radius_m > 0.0 &&
                       std::isfinite(w.rolling_radius_sigma_m) && w.rolling_radius_sigma_m > 0.0 &&
                       std::isfinite(w.slip_compliance) && w.slip_compliance >= 0.0 &&
                       std::isfinite(w.slip_compliance_sigma) && w.slip_compliance_sigma > 0.0;
    if (!valid) {
      throw std::invalid_argument("wheel calibration prior of '" + w.wheel +
                                  "': R_w and the sigmas must be finite and > 0, kappa finite and >= 0");
    }
    slot = w;
  }
  std::vector<WheelCalibrationPrior> prior;
  for (std::size_t i = 0; i < ordered.size(); ++i) {
    if (!ordered[i]) {
      throw std::invalid_argument("wheel calibration prior: no entry for '" + vehicle_.wheels[i].name + "'");
    }
    // What may have changed since that drive widens its sigmas (the filter file's change between
    // drives, in quadrature); calibration_prior_ holds the widened prior.
    WheelCalibrationPrior carried = *ordered[i];
    const SlipAwareOdometryConfig& slip = config_.slip_aware_odometry;
    carried.rolling_radius_sigma_m =
        std::hypot(carried.rolling_radius_sigma_m, slip.carried_rolling_radius_change_sigma_m);
    carried.slip_compliance_sigma = std::hypot(carried.slip_compliance_sigma, slip.carried_slip_compliance_change_sigma);
    prior.push_back(carried);
  }
  calibration_prior_ = std::move(prior);
}

void VehicleEkf::EnableSmoothing(bool check_transitions) {
  smoothing_.Enable(check_transitions);
  if (initialised_) smoothing_.Start(x_, p_);
}

std::size_t VehicleEkf::MarkForSmoothing() {
  if (smoothing_.enabled() && !initialised_) throw std::logic_error("MarkForSmoothing: the filter is not initialised");
  return smoothing_.Mark(time_s_, x_, p_);  // std::logic_error when not enabled
}

std::vector<SmoothedState> VehicleEkf::FinishSmoothing() {
  std::vector<SmoothedState> smoothed = smoothing_.Finish(x_, p_);
  for (SmoothedState& s : smoothed) {
    for (std::size_t i = 0; layout_.slip_aware() && i < layout_.wheel_count(); ++i) ClampWheelCalibration(s.state, i);
  }
  return smoothed;
}

}  // namespace rowloc::localization
