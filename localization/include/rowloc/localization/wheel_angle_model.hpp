// Wheel-angle states: the encoders' cumulative angle as the wheel measurement, instead of their
// speed (docs/notes/2026-12-02-localization-filter.md §5.4; FilterConfig wheels.angle_measurement).
//
// Why. An incremental encoder counts whole ticks of 2 pi / n rad. Its speed output,
// (c_k - c_{k-1}) 2 pi / (n dt), carries the difference e_{k-1} - e_k of the quantization errors of
// the cumulative count (e in [0, 1) tick): a moving-average error whose successive samples are
// correlated (lag-1 autocorrelation -1/2 before any low-pass filter), which a white speed noise
// misrepresents: the filter cannot average it down over a leg the way the count does, and it
// cannot tell it from slip. The cumulative angle carries e_k alone: bounded, and what the wheel
// rolled over a whole leg is known to one tick.
//
// Model. One state theta_i per wheel (rad; its offset is arbitrary: the filter anchors it to the
// first measured angle):
//   theta_i' = omega_i(x)    the wheel-speed model of measurement_models.hpp (slip-aware when the
//                            layout is), without the encoder's low-pass lag (the count has none)
// Discretized with explicit Euler over each prediction step: theta_i += dt omega_i(x), using the
// state at the start of the step. Its Jacobian is I + dt E J (J = d omega / dx, E the theta rows),
// applied before the base step of process_model.hpp: the full step's F is F_base (I + dt E J)
// because F_base is the identity on the theta rows and columns. So
//   P <- (I + dt E J) P (I + dt E J)^T = P + E M + M^T E^T + E (dt M J^T) E^T,   M = dt J P,
// plus the process noise q^2 dt on each theta_i (the wheel-rate model's error: slip transients,
// radius ripple; wheels.angle_rate_noise_radps_per_sqrt_hz).
// Measurement: z_i = theta_i + e_i with Var e_i = sigma^2 (wheels.angle_sigma_rad: the tick angle
// over sqrt(12) for a uniform quantization error).
#pragma once

#include "rowloc/localization/filter_config.hpp"
#include "rowloc/localization/measurement_models.hpp"
#include "rowloc/localization/state_layout.hpp"
#include "rowloc/mapio/vehicle_config.hpp"

#include <Eigen/Core>

#include <optional>
#include <vector>

namespace rowloc::localization {

/// Working memory of PropagateWheelAngles, reused so that a prediction step allocates nothing once
/// the sizes repeat (no state: its contents are scratch).
struct WheelAngleScratch {
  LinearizedMeasurement rates;  ///< omega(x) and J
  Eigen::MatrixXd m;            ///< dt J P, wheels x states
  Eigen::MatrixXd corner;       ///< dt M J^T, wheels x wheels
  Eigen::MatrixXd block;        ///< the new angle block of P
};

/// One prediction step of the wheel-angle states over dt_s >= 0 (state and covariance, with their
/// process noise), to be followed by PredictStep over the same dt_s. torque_nm: the last wheels
/// message's torques (vehicle order) or none, as for WheelSpeedModel. Does nothing when the layout
/// has no wheel-angle states.
void PropagateWheelAngles(const mapio::VehicleConfig& vehicle, const StateLayout& layout, const FilterConfig& config,
                          const std::optional<std::vector<double>>& torque_nm, Eigen::VectorXd& x,
                          Eigen::MatrixXd& p, double dt_s, WheelAngleScratch& scratch);

/// h = (theta_1, ..., theta_n) in vehicle order; H the matching unit rows. std::invalid_argument
/// when the layout has no wheel-angle states.
void WheelAngleModel(const Eigen::VectorXd& x, const StateLayout& layout, LinearizedMeasurement& out);

}  // namespace rowloc::localization
