// Measurement models of the vehicle EKF: predicted measurement h(x) and its Jacobian H = dh/dx,
// analytic, tested against central differences (Danzi 2026 ch. 6; Lindgren et al. 2002 eqs. (32)-(38)).
// x is laid out by StateLayout; R(phi) is the planar rotation by the heading; l a lever arm
// (body frame, metres); r the yaw rate.
//
// GPS antenna (position, local ENU):  h = [X, Y] + R(phi) l_gnss (+ [b_E, b_N], the GNSS bias
//   states when the layout has them, process_model.hpp)
// IMU (specific force at the IMU, yaw rate), l = l_imu:
//   h = [ax - r^2 l_x, ay - r^2 l_y, r + b_g]
//   (the centripetal term of a rigid body; the tangential term r' x l is not modelled since r' is
//   not a state: it is part of the IMU noise)
// Wheel i at l_i with steering delta_i (0 for a fixed wheel or track):
//   v_i   = cos(delta_i) (vx - r l_iy) + sin(delta_i) (vy + r l_ix)   (wheel-centre velocity along
//                                                                       the wheel heading)
//   h_i   = v_i / R_i                                                  (no slip model; R_i nominal)
//   h_i   = v_i / (R_i (1 - kappa_i mu_i)),  mu_i = T_i / (N_i r_i)    (slip-aware, Lindgren et al. 2002 eqs. 32-37:
//           the odometer speed v_m = R_w omega = v_a k_s / (k_s - T), T the measured wheel torque,
//           written with the slip compliance kappa = N r / k_s: the modelled slip T / k_s is
//           kappa mu, mu the traction coefficient, N_i = m g / (wheel count) the static load and
//           r_i the nominal radius. Same model; the filter holds kappa instead of k_s because the
//           modelled slip kappa mu is linear in kappa, while T / k_s is not in k_s: its derivative
//           -T/k^2 vanishes for a stiff prior, which made R_w absorb the slip with a false
//           confidence (docs/notes/2026-12-02-localization-filter.md §5.2); kappa is dimensionless, so one prior
//           fits every vehicle.
//           A message without torques has mu_i = 0, or (traction_from_acceleration) the part the
//           acceleration demands, mu_i = (cos(delta_i) a_x + sin(delta_i) a_y) / g: then R_i absorbs
//           the constant rolling-resistance part and kappa_i mu_i models the slip change when the
//           vehicle speeds up or brakes (docs/notes/2026-12-02-localization-filter.md §5.3); a skid steer's tracks
//           add the turning resistance's part, TurningResistanceTraction (§5.8))
//   with an encoder low-pass filter of time constant tau, v_i is replaced by its value tau earlier,
//   to first order v_i - tau dv_i/dt, where dv_i/dt = cos(delta_i) (ax + r vy) + sin(delta_i)
//   (ay - r vx) (the body-frame velocity derivatives of the motion model; yaw acceleration,
//   steering rate and torque changes not modelled). A braking at 1 m/s^2 with tau = 0.02 s makes
//   the encoder read 0.02 m/s high; without the term the filter took that as along-track motion.
// Non-holonomic constraint of wheel i (a pseudo-measurement z = 0: wheels and tracks do not slide
// sideways, up to a side-slip noise; it is what makes the heading observable from GNSS positions):
//   h_i   = -sin(delta_i) (vx - r l_iy) + cos(delta_i) (vy + r l_ix)   (wheel-centre velocity across
//                                                                      the wheel heading)
// Steering encoder of wheel i:   h = delta_i
// Visual odometry at the camera l_c:   h = [vx - r l_cy, vy + r l_cx]
#pragma once

#include "rowloc/localization/state_layout.hpp"
#include "rowloc/mapio/vehicle_config.hpp"

#include <Eigen/Core>

#include <optional>
#include <vector>

namespace rowloc::localization {

struct LinearizedMeasurement {
  Eigen::VectorXd predicted;  ///< h(x)
  Eigen::MatrixXd jacobian;   ///< dh/dx, rows = measurement dimension, cols = state size
};

// Every model comes in two forms: one returns the linearization, the other writes it into `out`,
// resizing it only when the sizes change, so that a filter reusing `out` allocates nothing per
// message (VehicleEkf does). On an exception `out` is unspecified.

/// gnss_bias_index: StateLayout::gnss_bias (b_E, b_N added to the antenna position), or -1.
LinearizedMeasurement GpsAntennaModel(const Eigen::VectorXd& x, const Eigen::Vector2d& lever_arm_m,
                                      int gnss_bias_index = -1);
void GpsAntennaModel(const Eigen::VectorXd& x, const Eigen::Vector2d& lever_arm_m, int gnss_bias_index,
                     LinearizedMeasurement& out);

/// accel_bias_index: StateLayout::accel_bias (b_ax, b_ay added to the specific force), or -1.
LinearizedMeasurement ImuModel(const Eigen::VectorXd& x, const Eigen::Vector2d& lever_arm_m, int accel_bias_index = -1);
void ImuModel(const Eigen::VectorXd& x, const Eigen::Vector2d& lever_arm_m, int accel_bias_index,
              LinearizedMeasurement& out);

/// Longitudinal wheel-centre velocity v_i (m/s) of wheel `index` (see the header comment).
double WheelLongitudinalVelocity(const Eigen::VectorXd& x, const mapio::VehicleConfig& vehicle,
                                 const StateLayout& layout, std::size_t index);

/// Standard gravity (m/s^2), for the static wheel loads.
inline constexpr double kStandardGravityMps2 = 9.80665;

/// N r of wheel `index` (N m): its static load m g / (wheel count), the vehicle carrying its mass
/// equally (mapio::VehicleConfig::mass_kg), times its nominal radius. A torque divided by it is
/// the traction coefficient mu of the slip-aware model.
double WheelTractionScaleNm(const mapio::VehicleConfig& vehicle, std::size_t index);

/// Skid steer: the traction coefficient the turning-resistance moment demands of track `index`,
/// and its derivative by the yaw rate r (rad/s). Wong, Theory of Ground Vehicles (4th ed.) §7.2:
/// a turn slides the tracks sideways against the moment M_r = mu_t m g l / 4 (l the contact
/// length, mu_t the lateral resistance coefficient; mapio::TrackParameters), which the tracks
/// resist with the longitudinal forces +-M_r / B (B the gauge): the outer track pushes forward,
/// the inner one holds back. Over a track's static load m g / 2:
///   tau_i = -sign(l_iy) mu_t l / (2 B) s(r),
///   s(r)  = sign(r) clamp((|r| - d r_0) / ((1 - d) r_0), 0, 1),   r_0 = 2 v_0 / B,
/// s the direction of the turn: full from r_0, the yaw rate at which a track's speed differs from
/// the centre's by the slip deadband v_0 (kSlipDeadbandMps), and 0 below d r_0 (d =
/// kTurningTractionDeadZone). The dead zone is this filter's choice, not physics: without it the
/// yaw rate's excursions on a straight drive made tau a regressor of noise for the slip
/// compliance, which fell from 0.6 to 0 over the cruise and mispredicted the stop
/// (docs/notes/2026-12-02-localization-filter.md §5.8). 0 (and 0) for other vehicles and for a skid steer without
/// track data; mu_t = 0 in the vehicle file turns the term off.
inline constexpr double kTurningTractionDeadZone = 0.5;
struct TurningTraction {
  double value = 0.0;
  double d_yaw_rate = 0.0;  ///< d tau_i / d r, s
};
TurningTraction TurningResistanceTraction(const mapio::VehicleConfig& vehicle, std::size_t index,
                                          double yaw_rate_radps);

/// Traction coefficient mu of wheel `index` in the slip-aware odometer model: with torques,
/// T / (N r) (WheelTractionScaleNm); without, if from_acceleration, the part the body motion
/// demands: the acceleration's, (cos(delta) a_x + sin(delta) a_y) / g (the wheels carry the mass
/// equally; the rolling-resistance part is constant on one terrain and R_w absorbs it), plus for a
/// skid steer the turning resistance's (TurningResistanceTraction; without it a tracked vehicle's
/// speeds were gated out in every turn, docs/notes/2026-12-02-localization-filter.md §5.8), else 0. Throws
/// std::invalid_argument for an index beyond the wheels or a torque count other than the wheel count.
double WheelTractionCoefficient(const Eigen::VectorXd& x, const mapio::VehicleConfig& vehicle, const StateLayout& layout,
                                std::size_t index, const std::optional<std::vector<double>>& torque_nm,
                                bool from_acceleration);

/// Rolling radius used for wheel `index`: the state R_i with slip-aware odometry, else nominal.
double WheelRollingRadius(const Eigen::VectorXd& x, const mapio::VehicleConfig& vehicle,
                          const StateLayout& layout, std::size_t index);

/// All wheels in vehicle order (rad/s). torque_nm: one per wheel, used by the slip-aware model
/// only; without it the traction coefficient is 0 (the odometer model reduces to v / R) or, with
/// traction_from_acceleration, the acceleration's (WheelTractionCoefficient). encoder_lag_s: the
/// encoders' low-pass time constant tau (>= 0; 0: none). Throws std::invalid_argument for a torque
/// count other than the wheel count or a negative or non-finite lag.
LinearizedMeasurement WheelSpeedModel(const Eigen::VectorXd& x, const mapio::VehicleConfig& vehicle,
                                      const StateLayout& layout,
                                      const std::optional<std::vector<double>>& torque_nm,
                                      double encoder_lag_s = 0.0, bool traction_from_acceleration = false);
void WheelSpeedModel(const Eigen::VectorXd& x, const mapio::VehicleConfig& vehicle, const StateLayout& layout,
                     const std::optional<std::vector<double>>& torque_nm, double encoder_lag_s,
                     bool traction_from_acceleration, LinearizedMeasurement& out);

/// Lateral wheel-centre velocities of all wheels (vehicle order), m/s (the non-holonomic rows).
LinearizedMeasurement WheelLateralVelocityModel(const Eigen::VectorXd& x, const mapio::VehicleConfig& vehicle,
                                                const StateLayout& layout);
void WheelLateralVelocityModel(const Eigen::VectorXd& x, const mapio::VehicleConfig& vehicle,
                               const StateLayout& layout, LinearizedMeasurement& out);

/// States measured directly: h = (x(indices[0]), x(indices[1]), ...), H the matching unit rows
/// (the steering angles, the wheel angles, the traction states). Each index must be a state of x,
/// else std::invalid_argument.
void SelectedStatesModel(const Eigen::VectorXd& x, const std::vector<int>& indices, LinearizedMeasurement& out);

/// Steering angles of the given wheels (indices into the vehicle's wheels; each must be steerable,
/// else std::invalid_argument).
LinearizedMeasurement SteeringModel(const Eigen::VectorXd& x, const StateLayout& layout,
                                    const std::vector<std::size_t>& wheels);
void SteeringModel(const Eigen::VectorXd& x, const StateLayout& layout, const std::vector<std::size_t>& wheels,
                   LinearizedMeasurement& out);

LinearizedMeasurement VioModel(const Eigen::VectorXd& x, const Eigen::Vector2d& lever_arm_m);
void VioModel(const Eigen::VectorXd& x, const Eigen::Vector2d& lever_arm_m, LinearizedMeasurement& out);

}  // namespace rowloc::localization
