// Exact per-wheel ground truth of the four vehicle kinds for a commanded planar body motion
// (issue 3, "Vehicles and motion"; derivation in docs/simulation-vehicles.md).
//
// Kinematics (rigid body, Danzi 2026 eq. (2.2)/(4.19)): the wheel-centre velocity in the body frame is
//   v_w = v + yaw_rate x p_w = (v_x - r_z p_y,  v_y + r_z p_x)        (r_z = yaw rate)
// and its acceleration relative to the ground, in body components (corrects Danzi 2026's process-model signs),
//   a_w = (dv_x - r_z v_y - dr_z p_y - r_z^2 p_x,  dv_y + r_z v_x + dr_z p_x - r_z^2 p_y).
// * Steered wheels (swerve, 4WS) point along v_w: delta = atan2(v_wy, v_wx), longitudinal speed
//   |v_w|. If |delta| > max_steering_angle the wheel turns the other way (delta -+ pi) and rolls
//   backwards (longitudinal speed -|v_w|); if that still exceeds the limit (only when the limit is
//   below pi/2) the motion is infeasible. For |v_w| < 1e-9 m/s the heading is undefined: delta = 0.
//   The lateral speed of a steered wheel is 0.
// * Differential-drive wheels and tracks are fixed (delta = 0). A differential drive needs zero
//   lateral wheel speed (v_y + r_z p_x = 0) and zero lateral acceleration change (dv_y + dr_z p_x = 0);
//   otherwise MotionProblem() reports it. A track slides sideways: lateral_speed = v_y + r_z p_x.
//
// Quasi-static longitudinal slip (Lindgren et al. 2002 eq. (21); wheel_slip.hpp): wheel i carries the
// mass share m_i = m / n (centre of mass at the wheel centroid, equal static loads) and the normal
// load N_i = m_i g. It must deliver along its heading h_i the force
//   F_i = m_i (a_w . h_i) + c_rr N_i v_long / max(|v_long|, 0.05 m/s)
// (the smooth rolling-resistance law of wheel_slip.hpp; = c_rr N sign(v_long) above 0.05 m/s).
// The traction demand mu_i = F_i / N_i gives the slip s_i = JanosiHanamotoCurve::SlipFor(mu_i) on
// the wheel's terrain; r_roll = r_nominal * rolling_radius_factor for wheels, the sprocket radius
// for tracks (a track's soil effects are all in its slip i); torque = F_i r_roll.
// * Wheels (swerve/4WS/differential): s is the SAE slip (sign = sign of F along the heading) and
//   omega r_roll = v/(1 - |s|) when s v > 0 (driving), v (1 - |s|) when s v < 0 (braking), so that
//   SaeLongitudinalSlip(omega, r_roll, v) == s. At constant speed mu = c_rr: s equals
//   LongitudinalWheelDynamics::SteadyStateSlip().
// * Tracks (skid steer): s is the track slip i of Tazzari et al. n.d. eq. (6), i = 1 - V_t/(omega r), computed
//   from eq. (7) (F = F_max[1 - K/(il)(1 - e^{-il/K})], i.e. the same curve with B = K/l) and
//   signed like F v (i > 0: the track is driving in its direction of travel). omega r = V_t / (1 - i),
//   eta = 1 - i (eq. (4)), so eq. (3) holds exactly:
//     V = (eta_R r w_R + eta_L r w_L)/2,  yaw_rate = (eta_R r w_R - eta_L r w_L)/(2d),  2d = B.
//   Besides acceleration and rolling resistance the tracks overcome Wong's turning-resistance moment
//   M_r = mu_t m g l / 4 (Wong, Theory of Ground Vehicles, §7.2), applied against the yaw rate as
//   +-M_r/B on the outer/inner track, smoothed as sign(r_z) ~ r_z / max(|r_z|, 2 * 0.05 m/s / B).
// Deadband: for |v_long| < 0.05 m/s the slip is 0 and omega = v_long / r_roll (kSlipDeadbandSpeedMps).
// Saturation: if |mu_i| > mu(1) the terrain cannot carry the force: slip = sign(mu_i) (for tracks
// sign(F v)), traction_limited = true and torque = the demand (the wheel spins or locks). A locked
// wheel has omega = 0; a spinning one is reported at omega r = v / (1 - kSpinningSlipForSpeed), an
// arbitrary finite stand-in (the quasi-static model has no steady state there).
#pragma once

#include "rowloc/sim/terrain.hpp"
#include "rowloc/sim/vehicle_config.hpp"

#include <Eigen/Core>

#include <optional>
#include <span>
#include <string>
#include <vector>

namespace rowloc::sim {

/// Standard gravity used for the normal loads (m/s^2), as WheelDynamicsParams.
inline constexpr double kVehicleGravityMps2 = 9.80665;
/// Slip used only to give a spinning (traction-limited, driving) wheel a finite angular speed.
inline constexpr double kSpinningSlipForSpeed = 0.9;

/// Commanded (= true) planar motion of the body, from the route. Body-frame components.
struct BodyMotion {
  double v_x_mps = 0, v_y_mps = 0;      ///< velocity of the reference point
  double yaw_rate_radps = 0;
  double dv_x_mps2 = 0, dv_y_mps2 = 0;  ///< time derivatives of v_x, v_y (body-frame components)
  double yaw_accel_radps2 = 0;
};

struct WheelTruth {
  double steering_angle_rad = 0;        ///< wheel heading in the body frame (0 for fixed wheels/tracks)
  double wheel_angular_speed_radps = 0; ///< omega (sprocket speed for a track)
  double longitudinal_speed_mps = 0;    ///< ground speed of the wheel centre along the heading
  double lateral_speed_mps = 0;         ///< across the heading (0 for steered wheels)
  double slip = 0;                      ///< SAE slip (wheels) or track slip i of Tazzari et al. n.d. eq. (6) (tracks)
  double torque_nm = 0;                 ///< drive torque = longitudinal_force_n * rolling_radius_m
  double rolling_radius_m = 0;          ///< r_roll on the terrain under it
  TerrainClass terrain = TerrainClass::kTiles;
  double longitudinal_force_n = 0;      ///< F: ground force along the heading the wheel must deliver
  double normal_load_n = 0;             ///< N = m g / n
  bool traction_limited = false;        ///< |F/N| > mu(1): slip saturated at +-1, see header comment
};

class VehicleModel {
 public:
  /// Throws std::invalid_argument naming the problem if VehicleConfigProblem(config) is set.
  VehicleModel(VehicleConfig config, TerrainSlipTable terrains);

  const VehicleConfig& config() const { return config_; }
  const TerrainSlipTable& terrains() const { return terrains_; }

  /// Per-wheel truth (same order as config().wheels). Throws std::invalid_argument if
  /// terrain_per_wheel.size() != wheels.size() or MotionProblem(motion) is set.
  std::vector<WheelTruth> Wheels(const BodyMotion& motion, std::span<const TerrainClass> terrain_per_wheel) const;

  /// True specific force in the body frame at the IMU mount on flat ground:
  ///   (dv_x - r_z v_y - dr_z p_y - r_z^2 p_x,  dv_y + r_z v_x + dr_z p_x - r_z^2 p_y),  p = imu xy.
  Eigen::Vector2d ImuSpecificForce(const BodyMotion& motion) const;

  /// Why the motion cannot be driven by this kind (non-finite value, sideways motion of a
  /// differential drive, steering beyond the limit), or nullopt. Traction limits are not a
  /// "problem": they depend on the terrain and are flagged per wheel.
  std::optional<std::string> MotionProblem(const BodyMotion& motion) const;

 private:
  WheelTruth WheelFor(std::size_t index, const BodyMotion& motion, TerrainClass terrain) const;
  double TurningResistanceForceN(const BodyMotion& motion) const;

  VehicleConfig config_;
  TerrainSlipTable terrains_;
};

/// Velocity of the body point p (body frame): v + yaw_rate x p.
Eigen::Vector2d PointVelocity(const BodyMotion& motion, const Eigen::Vector2d& point_m);
/// Acceleration relative to the ground of the body point p, in body components (header comment).
Eigen::Vector2d PointAcceleration(const BodyMotion& motion, const Eigen::Vector2d& point_m);

}  // namespace rowloc::sim
