// Process model of the vehicle EKF (Danzi 2026 ch. 4 and 6, the AgriMaRo constant-acceleration
// model; docs/localization-filter.md).
//
// Continuous time, body-frame velocity v_B = (vx, vy), yaw rate r, body acceleration a_B:
//   X'   = vx cos(phi) - vy sin(phi)        Y' = vx sin(phi) + vy cos(phi)        phi' = r
//   vx'  = ax + r vy                          vy' = ay - r vx
//   r', ax', ay', delta_i', b_g', R_w', kappa' = white noise (random walks; kappa the slip compliance)
// Danzi 2026 writes the velocity step as v_Bx + T (a_Bx - phi_dot v_By); with a_B the IMU's
// acceleration the body-frame velocity obeys the signs above (an erratum of the source; fixed here).
// Danzi 2026's discrete model also uses the step T of its own loop; here every step uses the
// actual time since the previous measurement (a correction of the source, docs/references.md).
//
// Discretization over dt (split by the caller into steps <= FilterConfig::max_prediction_step_s):
// explicit Euler for the velocities, and the mid-step heading phi + r dt / 2 for the position (exact
// for a constant-speed arc to O(dt^3)). F = df/dx is analytic (tested against central differences).
// Process noise: Q = diag(q_v^2, q_v^2, q_r^2, q_a^2, q_a^2, q_b^2, q_delta^2 ...) dt on
// (vx, vy, r, ax, ay, b_g, delta_i), and for the slip-aware states (Lindgren et al. 2002, after eq. (41)) a variance
// growing with the distance d_i = |v_i| dt wheel i rolled in the step: q_R^2 d_i, q_k^2 d_i, the
// kappas of wheels i != j sharing rho q_k^2 sqrt(d_i d_j) (slip_compliance_wheel_correlation rho: one
// terrain under all wheels). The wheel-angle states, when the layout has them, are propagated by
// wheel_angle_model.hpp before this step.
// GNSS bias (gps.estimate_bias), per horizontal axis a first-order Gauss-Markov process
// b' = -b / tau + w, discretized exactly (gnss_bias_model.hpp states it and its sources).
// F is the identity outside the 9 base states and the GNSS bias, and sparse inside the base states
// (15 off-diagonal entries): P <- F P F^T is computed as column then row operations on the coupled
// states only, O(nnz n); the bias rows and columns of P are scaled by a = exp(-dt / tau).
#pragma once

#include "rowloc/localization/filter_config.hpp"
#include "rowloc/localization/state_layout.hpp"
#include "rowloc/mapio/vehicle_config.hpp"

#include <Eigen/Core>

namespace rowloc::localization {

using BaseJacobian = Eigen::Matrix<double, StateLayout::kBaseSize, StateLayout::kBaseSize>;

/// One step of the noise-free model: state <- f(state, dt); returns F restricted to the base states
/// (F is the identity elsewhere). dt >= 0, finite (checked by the caller).
BaseJacobian PropagateState(Eigen::VectorXd& state, double dt_s);

/// a = exp(-dt / tau), the GNSS bias's factor over one step (1 without bias states).
double GnssBiasDecay(const StateLayout& layout, const GpsNoise& gps, double dt_s);

/// The full prediction step: propagates state and covariance by dt_s (one step, no splitting) and
/// adds the process noise. The heading is wrapped. base_jacobian: if given, receives F restricted to
/// the base states (for the smoother, fixed_interval_smoother.hpp).
void PredictStep(const mapio::VehicleConfig& vehicle, const StateLayout& layout, const FilterConfig& config,
                 Eigen::VectorXd& state, Eigen::MatrixXd& covariance, double dt_s,
                 BaseJacobian* base_jacobian = nullptr);

}  // namespace rowloc::localization
