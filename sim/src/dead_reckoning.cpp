// Dead-reckoning baseline from encoders and the raw gyro (math and sources in dead_reckoning.hpp).
#include "rowloc/sim/dead_reckoning.hpp"

#include <Eigen/Geometry>
#include <Eigen/QR>

#include <charconv>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rowloc::sim {
namespace {

/// Below this |x|, sin(x)/x is its series 1 - x^2/6 (truncation error < x^4/120 < 1e-17).
constexpr double kSincSeriesBound = 1e-4;

void Require(bool ok, const char* who, const std::string& reason) {
  if (!ok) throw std::invalid_argument(std::string(who) + ": " + reason);
}

/// Shortest text that reads back as the same double.
std::string Format(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

double WrapAngle(double angle_rad) {
  const double wrapped = std::remainder(angle_rad, 2.0 * std::numbers::pi);
  return wrapped <= -std::numbers::pi ? std::numbers::pi : wrapped;
}

double Sinc(double x) { return std::abs(x) < kSincSeriesBound ? 1.0 - x * x / 6.0 : std::sin(x) / x; }

bool IsFixedAxleKind(VehicleKind kind) {
  return kind == VehicleKind::kDifferentialDrive || kind == VehicleKind::kSkidSteer;
}

void CheckTime(const char* who, const char* input, const std::optional<double>& previous_s, double time_s) {
  Require(std::isfinite(time_s), who, std::string(input) + " time_s is not finite");
  Require(!previous_s || time_s >= *previous_s, who,
          std::string(input) + " time " + Format(time_s) + " s goes backwards (previous " + input + " time " +
              Format(previous_s.value_or(0.0)) + " s)");
}

void CheckPerWheel(const char* who, const char* what, std::span<const double> values, std::size_t wheel_count) {
  Require(values.size() == wheel_count, who,
          std::to_string(values.size()) + " " + what + " for " + std::to_string(wheel_count) + " wheels");
  for (std::size_t i = 0; i < values.size(); ++i) {
    Require(std::isfinite(values[i]), who, std::string(what) + "[" + std::to_string(i) + "] is not finite");
  }
}

/// Equations (1) and (2) of the header: one row per wheel, one per steered wheel, plus the no-lateral-sliding row [0, 1, a] x = 0
/// of a fixed axle at x = a.
struct WheelEquations {
  Eigen::MatrixX3d a;
  Eigen::VectorXd u;
};

WheelEquations BuildEquations(const VehicleConfig& config, std::span<const double> steering_rad,
                              std::span<const double> speed_radps) {
  const auto wheel_count = static_cast<Eigen::Index>(config.wheels.size());
  const bool fixed_axle = IsFixedAxleKind(config.kind);
  Eigen::Index steered = 0;
  for (const WheelGeometry& wheel : config.wheels) steered += wheel.steerable ? 1 : 0;
  const Eigen::Index rows = wheel_count + steered + (fixed_axle ? 1 : 0);
  WheelEquations equations{Eigen::MatrixX3d::Zero(rows, 3), Eigen::VectorXd::Zero(rows)};
  Eigen::Index lateral_row = wheel_count;
  for (Eigen::Index i = 0; i < wheel_count; ++i) {
    const auto index = static_cast<std::size_t>(i);
    const WheelGeometry& wheel = config.wheels[index];
    const double angle = wheel.steerable ? steering_rad[index] : 0.0;
    const double c = std::cos(angle);
    const double s = std::sin(angle);
    equations.a.row(i) << c, s, wheel.position_m.x() * s - wheel.position_m.y() * c;
    equations.u(i) = speed_radps[index] * wheel.nominal_radius_m;
    // A steered wheel points along its velocity: no lateral speed, -s (v_x - r p_y) + c (v_y + r p_x) = 0.
    if (wheel.steerable) equations.a.row(lateral_row++) << -s, c, wheel.position_m.y() * s + wheel.position_m.x() * c;
  }
  if (fixed_axle) equations.a.row(lateral_row) << 0.0, 1.0, config.wheels.front().position_m.x();
  return equations;
}

/// Least squares, minimum norm when rank-deficient.
Eigen::VectorXd SolveMinimumNorm(const Eigen::MatrixXd& a, const Eigen::VectorXd& b) {
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> decomposition;
  decomposition.setThreshold(kDeadReckoningRankThreshold);
  decomposition.compute(a);
  return decomposition.solve(b);
}

BodyTwist TwistFrom(const VehicleConfig& config, YawSource yaw_source, std::span<const double> steering_rad,
                    double gyro_radps, std::span<const double> speed_radps) {
  const WheelEquations equations = BuildEquations(config, steering_rad, speed_radps);
  if (yaw_source == YawSource::kWheels) {
    const Eigen::VectorXd x = SolveMinimumNorm(equations.a, equations.u);
    return {x(0), x(1), x(2)};
  }
  const Eigen::VectorXd velocity =
      SolveMinimumNorm(equations.a.leftCols<2>(), equations.u - equations.a.col(2) * gyro_radps);
  return {velocity(0), velocity(1), gyro_radps};
}

/// Exact arc for the twist held constant over dt_s (header comment).
PlanarPose Integrate(const PlanarPose& start, const BodyTwist& twist, double dt_s, double time_s) {
  const double phi = twist.yaw_rate_radps * dt_s;
  const double along = dt_s * Sinc(phi);                                  // S = dt sin(phi)/phi
  const double across = dt_s * std::sin(0.5 * phi) * Sinc(0.5 * phi);     // C = dt (1 - cos phi)/phi
  const Eigen::Vector2d body_displacement(along * twist.v_x_mps - across * twist.v_y_mps,
                                          across * twist.v_x_mps + along * twist.v_y_mps);
  PlanarPose end;
  end.time_s = time_s;
  end.position_m = start.position_m + Eigen::Rotation2Dd(start.heading_rad) * body_displacement;
  end.heading_rad = WrapAngle(start.heading_rad + phi);
  return end;
}

bool IsFinite(const BodyTwist& twist) {
  return std::isfinite(twist.v_x_mps) && std::isfinite(twist.v_y_mps) && std::isfinite(twist.yaw_rate_radps);
}

bool IsFinite(const PlanarPose& pose) {
  return std::isfinite(pose.time_s) && pose.position_m.allFinite() && std::isfinite(pose.heading_rad);
}

const VehicleConfig& Checked(const VehicleConfig& config) {
  if (const auto problem = VehicleConfigProblem(config)) {
    throw std::invalid_argument("DeadReckoning: vehicle \"" + config.name + "\": " + *problem);
  }
  return config;
}

PlanarPose Checked(const PlanarPose& pose) {
  Require(IsFinite(pose), "DeadReckoning", "the initial pose is not finite");
  PlanarPose wrapped = pose;
  wrapped.heading_rad = WrapAngle(pose.heading_rad);
  return wrapped;
}

}  // namespace

DeadReckoning::DeadReckoning(const VehicleConfig& config, const PlanarPose& initial, YawSource yaw_source)
    : config_(Checked(config)),
      yaw_source_(yaw_source),
      initial_time_s_(initial.time_s),
      pose_(Checked(initial)),
      steering_rad_(config_.wheels.size(), 0.0) {}

void DeadReckoning::SetSteering(double time_s, std::span<const double> angle_rad_per_wheel) {
  constexpr const char* kWho = "DeadReckoning::SetSteering";
  CheckTime(kWho, "steering", steering_time_s_, time_s);
  CheckPerWheel(kWho, "steering angles", angle_rad_per_wheel, config_.wheels.size());
  steering_rad_.assign(angle_rad_per_wheel.begin(), angle_rad_per_wheel.end());
  steering_time_s_ = time_s;
}

void DeadReckoning::SetYawRate(double time_s, double yaw_rate_radps) {
  constexpr const char* kWho = "DeadReckoning::SetYawRate";
  CheckTime(kWho, "yaw rate", yaw_rate_time_s_, time_s);
  Require(std::isfinite(yaw_rate_radps), kWho, "yaw_rate_radps is not finite");
  yaw_rate_radps_ = yaw_rate_radps;
  yaw_rate_time_s_ = time_s;
}

PlanarPose DeadReckoning::AddWheelSpeeds(double time_s, std::span<const double> speed_radps) {
  constexpr const char* kWho = "DeadReckoning::AddWheelSpeeds";
  CheckTime(kWho, "wheel", wheel_time_s_, time_s);
  Require(time_s >= initial_time_s_, kWho,
          "wheel time " + Format(time_s) + " s is before the initial pose time " + Format(initial_time_s_) + " s");
  CheckPerWheel(kWho, "wheel speeds", speed_radps, config_.wheels.size());
  const BodyTwist twist = TwistFrom(config_, yaw_source_, steering_rad_, yaw_rate_radps_, speed_radps);
  Require(IsFinite(twist), kWho, "the readings give a non-finite body twist (values too large)");
  PlanarPose next = pose_;
  next.time_s = time_s;
  if (wheel_time_s_) next = Integrate(pose_, twist, time_s - *wheel_time_s_, time_s);
  Require(IsFinite(next), kWho, "the integrated pose is not finite (values too large)");
  pose_ = next;
  twist_ = twist;
  wheel_time_s_ = time_s;
  return pose_;
}

}  // namespace rowloc::sim
