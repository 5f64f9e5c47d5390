// Dead-reckoning baseline (issue 3; docs/simulation-scenarios.md, "baseline-odometry.ndjson"): the
// "no slip model" odometry the validation suite compares filters against. It integrates wheel
// encoder speeds, steering encoder angles and the raw gyro with the NOMINAL wheel radii
// (VehicleConfig::wheels[i].nominal_radius_m) and nothing else: no slip, no bias, no terrain.
//
// Twist from the wheels (Danzi 2026 eq. (2.2)/(2.3); docs/simulation-vehicles.md). Body frame x
// forward, y left; unknowns x = (v_x, v_y, r), r = yaw rate. Wheel i at p_i = (p_x, p_y) with
// heading angle d_i (the held steering encoder angle; 0 for a fixed wheel or track) has the centre
// velocity v_w = (v_x - r p_y, v_y + r p_x) and, rolling without slip along (cos d_i, sin d_i),
// measures the longitudinal speed
//   u_i = omega_i R_i = (v_x - r p_y) cos d_i + (v_y + r p_x) sin d_i
//       = [cos d_i, sin d_i, p_x sin d_i - p_y cos d_i] x.                                    (1)
// * swerve_drive, four_wheel_steer: the rows (1) of all wheels and, for each steered wheel, its
//   no-lateral-sliding row (the wheel points along its velocity, as VehicleModel steers it)
//     0 = -(v_x - r p_y) sin d_i + (v_y + r p_x) cos d_i = [-sin d_i, cos d_i, p_y sin d_i + p_x cos d_i] x,  (2)
//   stacked as A x = b. Without (2), v_y would rest on the tiny sin d_i of nearly parallel wheels,
//   and steering-encoder quantization would turn wheel-speed noise into large sideways speeds.
//     kGyro:   r = held gyro rate (0 before the first SetYawRate); (v_x, v_y) is the least-squares
//              solution of the first two columns with b - r * (third column).
//     kWheels: x is the least-squares solution of A x = b (3 unknowns).
//   Rank-deficient systems get the minimum-norm solution (Eigen's complete orthogonal
//   decomposition, relative rank threshold kDeadReckoningRankThreshold).
// * differential_drive, skid_steer (two fixed wheels/tracks, d_i = 0, on a common axle at x = a):
//   (1) reads u_i = v_x - r p_y,i, and the no-slip assumption adds no lateral sliding of the axle,
//   v_y + r a = 0 (VehicleModel's differential-drive constraint). Hence
//     kGyro:   r = gyro, v_x = mean_i(u_i + r p_y,i), v_y = -r a;
//     kWheels: r = (u_R - u_L) / (p_y,L - p_y,R), v_x and v_y as for kGyro.
//   For the shipped configurations (axle through the reference point, y = +-B/2) this is
//   v_x = mean_i(u_i), v_y = 0, r = (u_R - u_L)/B. The formula is symmetric in which wheel is called
//   left (the one at larger y), so names play no role. Implemented as the same least squares with
//   the row [0, 1, a] x = 0 appended.
//
// Integration, exact for the twist held constant over (t_prev, t], dt = t - t_prev, phi = r dt:
//   heading' = wrap(heading + phi)                                     (wrapped to (-pi, pi])
//   position' = position + Rot(heading) [S, -C; C, S] (v_x, v_y)^T,
//   S = dt sin(phi)/phi,  C = dt (1 - cos phi)/phi = dt sin(phi/2) sinc(phi/2)
// with sinc evaluated by its series near 0, so r = 0 gives exactly position + Rot(heading) v dt.
//
// Timing: the three inputs have their own clocks; each must be finite and not go backwards (equal
// times are allowed). Steering angles and the gyro rate are held (zero-order) until replaced.
// Wheel speeds are the mean rates over (t_prev, t]; the first AddWheelSpeeds only starts the clock
// (position and heading unchanged, pose time set to its time, which must be >= the initial pose
// time). Every invalid input throws std::invalid_argument naming the method and the reason, and
// leaves the estimator exactly as it was.
#pragma once

#include "rowloc/sim/vehicle_config.hpp"

#include <Eigen/Core>

#include <optional>
#include <span>
#include <vector>

namespace rowloc::sim {

/// Relative pivot threshold below which the wheel equations count as rank-deficient.
inline constexpr double kDeadReckoningRankThreshold = 1e-12;

struct PlanarPose {
  double time_s = 0.0;
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();  ///< world ENU
  double heading_rad = 0.0;                             ///< wrapped to (-pi, pi]
};

/// Planar body twist: velocity of the reference point (body frame) and yaw rate.
struct BodyTwist {
  double v_x_mps = 0, v_y_mps = 0, yaw_rate_radps = 0;
};

/// Where the yaw rate comes from: the raw gyro, or the wheel speeds and steering angles.
enum class YawSource { kGyro, kWheels };

class DeadReckoning {
 public:
  /// Throws std::invalid_argument if VehicleConfigProblem(config) is set or the pose is not finite.
  /// The initial heading is wrapped to (-pi, pi].
  DeadReckoning(const VehicleConfig& config, const PlanarPose& initial, YawSource yaw_source = YawSource::kGyro);

  /// Latest steering encoder angles, one per wheel in config order (non-steerable entries ignored,
  /// must still be finite). Held until the next call.
  void SetSteering(double time_s, std::span<const double> angle_rad_per_wheel);
  /// Latest raw gyro yaw rate (rad/s), held until the next call.
  void SetYawRate(double time_s, double yaw_rate_radps);
  /// Wheel encoder speeds (rad/s, config order) at time_s, each the mean rate over (t_prev, time_s].
  /// Computes the body twist from them (and the held steering and yaw rate) and integrates the pose
  /// from the previous wheel time to time_s with that twist held constant (exact arc integration,
  /// stable at zero yaw rate). The first call only starts the clock at that time (pose unchanged,
  /// provided time_s >= initial.time_s). Returns the new pose.
  PlanarPose AddWheelSpeeds(double time_s, std::span<const double> speed_radps);

  const PlanarPose& pose() const { return pose_; }
  const BodyTwist& twist() const { return twist_; }  ///< last twist used
  const VehicleConfig& config() const { return config_; }
  YawSource yaw_source() const { return yaw_source_; }

 private:
  VehicleConfig config_;
  YawSource yaw_source_;
  double initial_time_s_;
  PlanarPose pose_;
  BodyTwist twist_;
  std::vector<double> steering_rad_;
  double yaw_rate_radps_ = 0.0;
  std::optional<double> steering_time_s_;
  std::optional<double> yaw_rate_time_s_;
  std::optional<double> wheel_time_s_;
};

}  // namespace rowloc::sim
