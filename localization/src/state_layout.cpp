#include "rowloc/localization/state_layout.hpp"

namespace rowloc::localization {

StateLayout StateLayout::For(const mapio::VehicleConfig& vehicle, const Options& options) {
  const auto& [slip_aware_odometry, accel_bias, wheel_angles, traction, gnss_bias] = options;
  StateLayout layout;
  const std::size_t n = vehicle.wheels.size();
  layout.steering.assign(n, -1);
  layout.rolling_radius.assign(n, -1);
  layout.slip_compliance.assign(n, -1);
  layout.wheel_angle.assign(n, -1);
  layout.traction.assign(n, -1);
  int next = kBaseSize;
  for (std::size_t i = 0; i < n; ++i) {
    if (vehicle.wheels[i].steerable) layout.steering[i] = next++;
  }
  if (slip_aware_odometry) {
    for (std::size_t i = 0; i < n; ++i) {
      layout.rolling_radius[i] = next++;
      layout.slip_compliance[i] = next++;
    }
  }
  if (accel_bias) {
    layout.accel_bias = next;
    next += 2;
  }
  if (wheel_angles) {
    for (std::size_t i = 0; i < n; ++i) layout.wheel_angle[i] = next++;
  }
  if (traction && slip_aware_odometry) {
    for (std::size_t i = 0; i < n; ++i) layout.traction[i] = next++;
  }
  if (gnss_bias) {
    layout.gnss_bias = next;
    next += 2;
  }
  layout.size = next;
  return layout;
}

std::vector<std::string> StateLayout::Names(const mapio::VehicleConfig& vehicle) const {
  std::vector<std::string> names = {"x_m",     "y_m",     "phi_rad", "vx_mps",  "vy_mps",
                                    "r_radps", "ax_mps2", "ay_mps2", "bg_radps"};
  names.resize(static_cast<std::size_t>(size));
  for (std::size_t i = 0; i < steering.size(); ++i) {
    const std::string& wheel = vehicle.wheels[i].name;
    if (steering[i] >= 0) names[static_cast<std::size_t>(steering[i])] = "delta_" + wheel;
    if (rolling_radius[i] >= 0) names[static_cast<std::size_t>(rolling_radius[i])] = "R_" + wheel;
    if (slip_compliance[i] >= 0) names[static_cast<std::size_t>(slip_compliance[i])] = "kappa_" + wheel;
    if (wheel_angle[i] >= 0) names[static_cast<std::size_t>(wheel_angle[i])] = "theta_" + wheel;
    if (traction[i] >= 0) names[static_cast<std::size_t>(traction[i])] = "mu_" + wheel;
  }
  if (accel_bias >= 0) {
    names[static_cast<std::size_t>(accel_bias)] = "bax_mps2";
    names[static_cast<std::size_t>(accel_bias) + 1] = "bay_mps2";
  }
  if (gnss_bias >= 0) {
    names[static_cast<std::size_t>(gnss_bias)] = "gnss_bias_east_m";
    names[static_cast<std::size_t>(gnss_bias) + 1] = "gnss_bias_north_m";
  }
  return names;
}

}  // namespace rowloc::localization
