// Wheel-angle states: propagation and measurement (see wheel_angle_model.hpp).
#include "rowloc/localization/wheel_angle_model.hpp"

#include <stdexcept>

namespace rowloc::localization {

void PropagateWheelAngles(const mapio::VehicleConfig& vehicle, const StateLayout& layout, const FilterConfig& config,
                          const std::optional<std::vector<double>>& torque_nm, Eigen::VectorXd& x,
                          Eigen::MatrixXd& p, double dt_s, WheelAngleScratch& scratch) {
  if (!layout.has_wheel_angles()) return;
  WheelSpeedModel(x, vehicle, layout, torque_nm, /*encoder_lag_s=*/0.0,
                  config.slip_aware_odometry.traction_from_acceleration, scratch.rates);
  const Eigen::MatrixXd& j = scratch.rates.jacobian;
  const std::vector<int>& theta = layout.wheel_angle;
  Eigen::MatrixXd& m = scratch.m;
  m.noalias() = j * p;  // wheels x states
  m *= dt_s;
  Eigen::MatrixXd& corner = scratch.corner;
  corner.noalias() = m * j.transpose();
  corner *= dt_s;
  const auto n = static_cast<Eigen::Index>(layout.wheel_count());
  // The angle block: P_ab + M(a, theta_b) + M(b, theta_a) + dt (M J^T)(a, b), written to both
  // triangles from one sum so that P stays exactly symmetric.
  Eigen::MatrixXd& block = scratch.block;
  block.resize(n, n);
  const double q2 = config.wheels.angle_rate_noise_radps_per_sqrt_hz * config.wheels.angle_rate_noise_radps_per_sqrt_hz;
  for (Eigen::Index a = 0; a < n; ++a) {
    for (Eigen::Index b = 0; b <= a; ++b) {
      const int ta = theta[static_cast<std::size_t>(a)], tb = theta[static_cast<std::size_t>(b)];
      block(a, b) = block(b, a) = p(ta, tb) + (m(a, tb) + m(b, ta)) + 0.5 * (corner(a, b) + corner(b, a));
    }
    block(a, a) += q2 * dt_s;
  }
  // The other entries of the angle rows and columns: + M (rows) and + M^T (columns); the angle
  // block is then overwritten.
  for (Eigen::Index a = 0; a < n; ++a) {
    const int ta = theta[static_cast<std::size_t>(a)];
    p.row(ta) += m.row(a);
    p.col(ta) += m.row(a).transpose();
  }
  for (Eigen::Index a = 0; a < n; ++a) {
    for (Eigen::Index b = 0; b < n; ++b) p(theta[static_cast<std::size_t>(a)], theta[static_cast<std::size_t>(b)]) = block(a, b);
    x(theta[static_cast<std::size_t>(a)]) += dt_s * scratch.rates.predicted(a);
  }
}

void WheelAngleModel(const Eigen::VectorXd& x, const StateLayout& layout, LinearizedMeasurement& out) {
  if (!layout.has_wheel_angles()) throw std::invalid_argument("wheel angle model: the layout has no wheel-angle states");
  SelectedStatesModel(x, layout.wheel_angle, out);
}

}  // namespace rowloc::localization
