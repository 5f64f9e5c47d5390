// Per-wheel longitudinal slip (SAE) from the filtered state and the raw encoder speeds (issue 4,
// slip estimator 1; Danzi 2026 ch. 7):
//   s = (omega R - v_long) / max(|omega R|, |v_long|)
// with v_long the wheel-centre velocity along the wheel heading from the filtered body twist and
// steering angle (measurement_models.hpp), omega the *raw* encoder speed (not the filter's
// prediction), R the nominal wheel radius of the vehicle file (or, on request, the R_w state, below;
// Danzi 2026 ch. 7 uses the wheel radius:
// not the slip-aware state R_w, which at constant torque absorbs the slip itself, since only
// R_w (1 - kappa mu) = R_w (k_s - T) / k_s is observable then; a terrain's rolling radius R_a below the nominal R_m
// therefore reads as extra slip, s_a - s_m = (1 - s_a) (R_a / R_m - 1), Lindgren et al. 2002 eq. (29); see
// docs/localization-filter.md §4); s = 0 when both |omega R| and |v_long| are below 0.05 m/s; saturated to [-1, 1] (speeds
// of opposite signs would give up to 2 in magnitude).
#pragma once

#include "rowloc/localization/state_layout.hpp"
#include "rowloc/mapio/vehicle_config.hpp"

#include <Eigen/Core>

#include <vector>

namespace rowloc::localization {

/// Below this speed (m/s) of both the wheel and its centre the slip is defined as 0.
inline constexpr double kSlipDeadbandMps = 0.05;

/// SAE slip of one wheel; throws std::invalid_argument on non-finite input or radius <= 0.
double SaeSlip(double wheel_speed_radps, double rolling_radius_m, double longitudinal_velocity_mps);

/// SAE slip of every wheel (vehicle order) from the state x and raw encoder speeds (same order).
/// with_rolling_radius (FilterConfig slip_aware_odometry.slip_with_rolling_radius): R is the
/// wheel's R_w state where the layout has one, instead of the nominal radius.
/// Throws std::invalid_argument if the speed count differs from the wheel count.
std::vector<double> EstimateWheelSlip(const Eigen::VectorXd& x, const mapio::VehicleConfig& vehicle,
                                      const StateLayout& layout, const std::vector<double>& raw_speed_radps,
                                      bool with_rolling_radius = false);

}  // namespace rowloc::localization
