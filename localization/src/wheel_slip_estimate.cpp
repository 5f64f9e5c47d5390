#include "rowloc/localization/wheel_slip_estimate.hpp"

#include "rowloc/localization/measurement_models.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rowloc::localization {

double SaeSlip(double wheel_speed_radps, double rolling_radius_m, double longitudinal_velocity_mps) {
  if (!std::isfinite(wheel_speed_radps) || !std::isfinite(longitudinal_velocity_mps)) {
    throw std::invalid_argument("SAE slip: wheel speed and velocity must be finite");
  }
  if (!(std::isfinite(rolling_radius_m) && rolling_radius_m > 0.0)) {
    throw std::invalid_argument("SAE slip: rolling radius must be finite and > 0");
  }
  const double wheel = wheel_speed_radps * rolling_radius_m;
  const double denominator = std::max(std::abs(wheel), std::abs(longitudinal_velocity_mps));
  if (denominator < kSlipDeadbandMps) return 0.0;
  return std::clamp((wheel - longitudinal_velocity_mps) / denominator, -1.0, 1.0);
}

std::vector<double> EstimateWheelSlip(const Eigen::VectorXd& x, const mapio::VehicleConfig& vehicle,
                                      const StateLayout& layout, const std::vector<double>& raw_speed_radps,
                                      bool with_rolling_radius) {
  if (raw_speed_radps.size() != vehicle.wheels.size()) {
    throw std::invalid_argument("wheel slip: one encoder speed per wheel expected");
  }
  std::vector<double> slip(raw_speed_radps.size());
  for (std::size_t i = 0; i < slip.size(); ++i) {
    const bool state_radius = with_rolling_radius && layout.slip_aware();
    const double radius = state_radius ? x(layout.rolling_radius[i]) : vehicle.wheels[i].nominal_radius_m;
    slip[i] = SaeSlip(raw_speed_radps[i], radius, WheelLongitudinalVelocity(x, vehicle, layout, i));
  }
  return slip;
}

}  // namespace rowloc::localization
