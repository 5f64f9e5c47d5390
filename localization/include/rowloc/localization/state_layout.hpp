// Layout of the vehicle EKF state (Danzi 2026 ch. 4 and 6, the 12-state AgriMaRo
// design, extended per vehicle kind and with the slip-aware augmented states of Lindgren et al. 2002).
//
// Index  name         unit     meaning
//   0    x_m          m        reference point, local ENU east
//   1    y_m          m        reference point, local ENU north
//   2    phi_rad      rad      heading from +east, counter-clockwise, wrapped to (-pi, pi]
//   3    vx_mps       m/s      body-frame velocity of the reference point, forward (v_Bx)
//   4    vy_mps       m/s      body-frame velocity, left (v_By)
//   5    r_radps      rad/s    yaw rate (phi_dot)
//   6    ax_mps2      m/s^2    body-frame acceleration (a_Bx) = IMU specific force at the reference point
//   7    ay_mps2      m/s^2    body-frame acceleration (a_By)
//   8    bg_radps     rad/s    gyro bias (b_g)
//   then, per steerable wheel in vehicle-config order:        delta_<wheel> (rad)
//   then, with slip-aware odometry, per wheel in config order: R_<wheel> (m), kappa_<wheel> (slip
//   per unit traction coefficient, dimensionless)
//   then, with accelerometer-bias estimation: bax_mps2, bay_mps2 (m/s^2): what the IMU reads on top
//   of the body acceleration, chiefly gravity on sloped ground (the planar filter has no attitude)
//   then, with wheel-angle measurements, per wheel in config order: theta_<wheel> (rad), the
//   wheel's cumulative rotation (wheel_angle_model.hpp)
//   then, with traction states (slip-aware odometry with a torque noise), per wheel in config
//   order: mu_<wheel>, the traction coefficient T / (N r) that the torques measure
//   then, with GNSS-bias estimation: gnss_bias_east_m, gnss_bias_north_m (m), the slowly varying
//   part of the receiver's position error (multipath under canopy), a first-order Gauss-Markov
//   process (process_model.hpp)
// Danzi 2026 orders the 12 states (X, Y, phi, v_Bx, v_By, phi_dot, a_Bx, a_By, delta_1..3, b_g); the
// gyro bias is moved before the steering angles here so that the base block has the same indices
// for every vehicle kind (a swerve robot has 3 steering states, a 4WS vehicle 4, the others none).
#pragma once

#include "rowloc/mapio/vehicle_config.hpp"

#include <cstddef>
#include <string>
#include <vector>

namespace rowloc::localization {

/// Index of each state; -1 where a wheel has no such state.
struct StateLayout {
  static constexpr int kX = 0, kY = 1, kPhi = 2, kVx = 3, kVy = 4, kYawRate = 5, kAx = 6, kAy = 7,
                       kGyroBias = 8, kBaseSize = 9;

  std::vector<int> steering;        ///< per wheel: index of delta, or -1 (not steerable)
  std::vector<int> rolling_radius;  ///< per wheel: index of R_w, or -1 (no slip-aware odometry)
  std::vector<int> slip_compliance;  ///< per wheel: index of kappa (slip per unit traction), or -1
  int accel_bias = -1;              ///< index of b_ax (b_ay follows), or -1 (not estimated)
  std::vector<int> wheel_angle;     ///< per wheel: index of theta, or -1 (no wheel-angle measurement)
  std::vector<int> traction;        ///< per wheel: index of mu, or -1 (torques taken as exact)
  int gnss_bias = -1;               ///< index of the east GNSS bias (north follows), or -1 (not estimated)
  int size = kBaseSize;

  /// Which optional state blocks a layout has (each false by default), e.g.
  /// StateLayout::For(vehicle, {.slip_aware_odometry = true, .gnss_bias = true}).
  struct Options {
    bool slip_aware_odometry = false;  ///< R_w and kappa per wheel (or track)
    bool accel_bias = false;           ///< b_ax, b_ay
    bool wheel_angles = false;         ///< theta per wheel
    bool traction = false;             ///< mu per wheel; only with slip_aware_odometry
    bool gnss_bias = false;            ///< b_E, b_N
  };

  /// The layout of a vehicle: one steering state per steerable wheel; with slip_aware_odometry
  /// a rolling radius and a slip compliance per wheel (or track).
  /// With accel_bias, two accelerometer-bias states; then with wheel_angles one angle per wheel;
  /// then, with traction and slip_aware_odometry, one traction coefficient per wheel; then, with
  /// gnss_bias, the two GNSS-bias states.
  static StateLayout For(const mapio::VehicleConfig& vehicle, const Options& options);
  /// The layout with only the slip-aware states optional (the other blocks off).
  static StateLayout For(const mapio::VehicleConfig& vehicle, bool slip_aware_odometry) {
    return For(vehicle, Options{.slip_aware_odometry = slip_aware_odometry});
  }

  /// Names of the states in index order, e.g. "x_m", "delta_front", "R_rear_left" (for messages).
  std::vector<std::string> Names(const mapio::VehicleConfig& vehicle) const;
  std::size_t wheel_count() const { return steering.size(); }
  bool slip_aware() const { return !rolling_radius.empty() && rolling_radius.front() >= 0; }
  bool has_wheel_angles() const { return !wheel_angle.empty() && wheel_angle.front() >= 0; }
  bool has_traction() const { return !traction.empty() && traction.front() >= 0; }
};

}  // namespace rowloc::localization
