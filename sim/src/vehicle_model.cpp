// Per-wheel ground truth of the vehicle kinds (math and sources in vehicle_model.hpp).
#include "rowloc/sim/vehicle_model.hpp"

#include "rowloc/sim/wheel_slip.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace rowloc::sim {
namespace {

/// Below this wheel-centre speed (m/s) a steered wheel's heading is undefined and set to 0.
constexpr double kSteeringSpeedFloorMps = 1e-9;
/// Relative tolerance of the feasibility checks.
constexpr double kFeasibilityTolerance = 1e-9;
/// Tolerance on the steering limit (rad), so that a wheel exactly at the limit is feasible.
constexpr double kSteeringLimitToleranceRad = 1e-12;

VehicleConfig Checked(VehicleConfig config) {
  if (const auto problem = VehicleConfigProblem(config)) {
    throw std::invalid_argument("VehicleModel: vehicle \"" + config.name + "\": " + *problem);
  }
  return config;
}

struct SteeredWheel {
  double steering_angle_rad = 0.0;
  double longitudinal_speed_mps = 0.0;
  bool within_limit = true;
};

/// Heading along the wheel-centre velocity, turned by pi (rolling backwards) beyond the limit.
SteeredWheel SteerAlong(const Eigen::Vector2d& velocity, double max_steering_angle_rad) {
  const double speed = velocity.norm();
  if (speed < kSteeringSpeedFloorMps) return {0.0, velocity.x(), true};
  SteeredWheel wheel{std::atan2(velocity.y(), velocity.x()), speed, true};
  if (std::abs(wheel.steering_angle_rad) > max_steering_angle_rad + kSteeringLimitToleranceRad) {
    wheel.steering_angle_rad -= std::copysign(std::numbers::pi, wheel.steering_angle_rad);
    wheel.longitudinal_speed_mps = -speed;
    wheel.within_limit =
        std::abs(wheel.steering_angle_rad) <= max_steering_angle_rad + kSteeringLimitToleranceRad;
  }
  return wheel;
}

bool IsSteeredKind(VehicleKind kind) {
  return kind == VehicleKind::kSwerveDrive || kind == VehicleKind::kFourWheelSteer;
}

std::string Format(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

/// omega * r_roll for the SAE slip s of a wheel moving at v (|v| >= deadband): inverse of
/// SaeLongitudinalSlip. A saturated driving wheel gets the finite stand-in of the header.
double SaePeripheralSpeed(double slip, double speed_mps) {
  const double magnitude = std::abs(slip);
  if (slip * speed_mps > 0.0) return speed_mps / (1.0 - (magnitude >= 1.0 ? kSpinningSlipForSpeed : magnitude));
  return speed_mps * (1.0 - magnitude);
}

/// omega * r for the track slip i of Tazzari et al. n.d. eq. (6): i = 1 - V/(omega r).
double TrackPeripheralSpeed(double track_slip, double speed_mps) {
  return speed_mps / (1.0 - (track_slip >= 1.0 ? kSpinningSlipForSpeed : track_slip));
}

}  // namespace

Eigen::Vector2d PointVelocity(const BodyMotion& motion, const Eigen::Vector2d& point_m) {
  return {motion.v_x_mps - motion.yaw_rate_radps * point_m.y(), motion.v_y_mps + motion.yaw_rate_radps * point_m.x()};
}

Eigen::Vector2d PointAcceleration(const BodyMotion& motion, const Eigen::Vector2d& point_m) {
  const double r = motion.yaw_rate_radps;
  const double dr = motion.yaw_accel_radps2;
  return {motion.dv_x_mps2 - r * motion.v_y_mps - dr * point_m.y() - r * r * point_m.x(),
          motion.dv_y_mps2 + r * motion.v_x_mps + dr * point_m.x() - r * r * point_m.y()};
}

VehicleModel::VehicleModel(VehicleConfig config, TerrainSlipTable terrains)
    : config_(Checked(std::move(config))), terrains_(std::move(terrains)) {}

Eigen::Vector2d VehicleModel::ImuSpecificForce(const BodyMotion& motion) const {
  return PointAcceleration(motion, config_.imu.position_m.head<2>());
}

std::optional<std::string> VehicleModel::MotionProblem(const BodyMotion& motion) const {
  for (const double value : {motion.v_x_mps, motion.v_y_mps, motion.yaw_rate_radps, motion.dv_x_mps2,
                             motion.dv_y_mps2, motion.yaw_accel_radps2}) {
    if (!std::isfinite(value)) return std::string("the body motion has a non-finite component");
  }
  for (const WheelGeometry& wheel : config_.wheels) {
    const Eigen::Vector2d velocity = PointVelocity(motion, wheel.position_m);
    if (config_.kind == VehicleKind::kDifferentialDrive) {
      const double scale = 1.0 + std::abs(motion.v_x_mps) + std::abs(motion.v_y_mps);
      const double lateral_accel = motion.dv_y_mps2 + motion.yaw_accel_radps2 * wheel.position_m.x();
      const double accel_scale = 1.0 + std::abs(motion.dv_x_mps2) + std::abs(motion.dv_y_mps2);
      if (std::abs(velocity.y()) > kFeasibilityTolerance * scale) {
        return "differential drive cannot move sideways: wheel \"" + wheel.name + "\" lateral speed " +
               Format(velocity.y()) + " m/s";
      }
      if (std::abs(lateral_accel) > kFeasibilityTolerance * accel_scale) {
        return "differential drive cannot accelerate sideways: wheel \"" + wheel.name +
               "\" d(lateral speed)/dt " + Format(lateral_accel) + " m/s^2";
      }
    } else if (IsSteeredKind(config_.kind) &&
               !SteerAlong(velocity, config_.max_steering_angle_rad).within_limit) {
      return "wheel \"" + wheel.name + "\" would need a steering angle beyond +-" +
             Format(config_.max_steering_angle_rad) + " rad";
    }
  }
  return std::nullopt;
}

std::vector<WheelTruth> VehicleModel::Wheels(const BodyMotion& motion,
                                             std::span<const TerrainClass> terrain_per_wheel) const {
  if (terrain_per_wheel.size() != config_.wheels.size()) {
    throw std::invalid_argument("VehicleModel::Wheels: " + std::to_string(terrain_per_wheel.size()) +
                                " terrain classes for " + std::to_string(config_.wheels.size()) + " wheels");
  }
  if (const auto problem = MotionProblem(motion)) {
    throw std::invalid_argument("VehicleModel::Wheels: vehicle \"" + config_.name + "\": " + *problem);
  }
  std::vector<WheelTruth> wheels;
  wheels.reserve(config_.wheels.size());
  for (std::size_t i = 0; i < config_.wheels.size(); ++i) wheels.push_back(WheelFor(i, motion, terrain_per_wheel[i]));
  return wheels;
}

double VehicleModel::TurningResistanceForceN(const BodyMotion& motion) const {
  if (config_.kind != VehicleKind::kSkidSteer) return 0.0;
  const double gauge_m = config_.wheels[0].position_m.y() - config_.wheels[1].position_m.y();
  const double gauge_abs_m = std::abs(gauge_m);
  const double moment_nm = config_.tracks->turning_resistance_coefficient * config_.mass_kg * kVehicleGravityMps2 *
                           config_.tracks->contact_length_m / 4.0;
  const double yaw_rate_floor = 2.0 * kSlipDeadbandSpeedMps / gauge_abs_m;
  const double smooth_sign = motion.yaw_rate_radps / std::max(std::abs(motion.yaw_rate_radps), yaw_rate_floor);
  return moment_nm / gauge_abs_m * smooth_sign;
}

WheelTruth VehicleModel::WheelFor(std::size_t index, const BodyMotion& motion, TerrainClass terrain) const {
  const WheelGeometry& geometry = config_.wheels[index];
  const TerrainSlipParams& params = terrains_.At(terrain);
  const Eigen::Vector2d velocity = PointVelocity(motion, geometry.position_m);
  const Eigen::Vector2d acceleration = PointAcceleration(motion, geometry.position_m);

  WheelTruth truth;
  truth.terrain = terrain;
  if (geometry.steerable) {
    const SteeredWheel steered = SteerAlong(velocity, config_.max_steering_angle_rad);
    truth.steering_angle_rad = steered.steering_angle_rad;
    truth.longitudinal_speed_mps = steered.longitudinal_speed_mps;
    truth.lateral_speed_mps = 0.0;
  } else {
    truth.longitudinal_speed_mps = velocity.x();
    truth.lateral_speed_mps = velocity.y();
  }
  const Eigen::Vector2d heading(std::cos(truth.steering_angle_rad), std::sin(truth.steering_angle_rad));
  const double mass_share_kg = config_.mass_kg / static_cast<double>(config_.wheels.size());
  const double v = truth.longitudinal_speed_mps;
  truth.normal_load_n = mass_share_kg * kVehicleGravityMps2;
  const double rolling_resistance_n = params.rolling_resistance_coefficient * truth.normal_load_n * v /
                                      std::max(std::abs(v), kSlipDeadbandSpeedMps);
  // Outer track (opposite side to the turn centre) pushes forward by M_r/B, inner one holds back.
  const double turning_n = -std::copysign(1.0, geometry.position_m.y()) * TurningResistanceForceN(motion);
  truth.longitudinal_force_n = mass_share_kg * acceleration.dot(heading) + rolling_resistance_n + turning_n;
  const bool track = config_.kind == VehicleKind::kSkidSteer;
  // A track runs on its sprocket radius; soil effects on a track are all in its slip i.
  truth.rolling_radius_m = geometry.nominal_radius_m * (track ? 1.0 : params.rolling_radius_factor);
  truth.torque_nm = truth.longitudinal_force_n * truth.rolling_radius_m;

  const JanosiHanamotoCurve curve(params);
  const double demand = truth.longitudinal_force_n / truth.normal_load_n;
  truth.traction_limited = std::abs(demand) > curve.MaxTractionCoefficient();
  if (std::abs(v) < kSlipDeadbandSpeedMps) {
    truth.slip = 0.0;
    truth.wheel_angular_speed_radps = v / truth.rolling_radius_m;
    return truth;
  }
  const double sae_slip = curve.SlipFor(demand).slip;
  double peripheral_speed_mps = 0.0;
  if (track) {
    truth.slip = std::copysign(1.0, v) * sae_slip;
    peripheral_speed_mps = TrackPeripheralSpeed(truth.slip, v);
  } else {
    truth.slip = sae_slip;
    peripheral_speed_mps = SaePeripheralSpeed(truth.slip, v);
  }
  truth.wheel_angular_speed_radps = peripheral_speed_mps / truth.rolling_radius_m;
  return truth;
}

}  // namespace rowloc::sim
