#include "rowloc/localization/process_model.hpp"

#include "rowloc/localization/kalman_update.hpp"

#include <cmath>

namespace rowloc::localization {

using L = StateLayout;

BaseJacobian PropagateState(Eigen::VectorXd& x, double dt) {
  const double phi = x(L::kPhi), vx = x(L::kVx), vy = x(L::kVy), r = x(L::kYawRate);
  const double mid = phi + 0.5 * r * dt;
  const double c = std::cos(mid), s = std::sin(mid);
  const double east_rate = vx * c - vy * s;   // X' at mid-step heading
  const double north_rate = vx * s + vy * c;  // Y'
  BaseJacobian f = BaseJacobian::Identity();
  f(L::kX, L::kPhi) = -dt * north_rate;
  f(L::kX, L::kYawRate) = -0.5 * dt * dt * north_rate;
  f(L::kX, L::kVx) = dt * c;
  f(L::kX, L::kVy) = -dt * s;
  f(L::kY, L::kPhi) = dt * east_rate;
  f(L::kY, L::kYawRate) = 0.5 * dt * dt * east_rate;
  f(L::kY, L::kVx) = dt * s;
  f(L::kY, L::kVy) = dt * c;
  f(L::kPhi, L::kYawRate) = dt;
  f(L::kVx, L::kVy) = dt * r;
  f(L::kVx, L::kYawRate) = dt * vy;
  f(L::kVx, L::kAx) = dt;
  f(L::kVy, L::kVx) = -dt * r;
  f(L::kVy, L::kYawRate) = -dt * vx;
  f(L::kVy, L::kAy) = dt;

  x(L::kX) += dt * east_rate;
  x(L::kY) += dt * north_rate;
  x(L::kPhi) = WrapAngle(phi + dt * r);
  x(L::kVx) = vx + dt * (x(L::kAx) + r * vy);
  x(L::kVy) = vy + dt * (x(L::kAy) - r * vx);
  return f;
}

namespace {

/// Distance (m) the centre of wheel i travels in dt at the current body twist.
double WheelDistance(const mapio::WheelGeometry& wheel, const Eigen::VectorXd& x, double dt) {
  const double r = x(L::kYawRate);
  const double wx = x(L::kVx) - r * wheel.position_m.y();
  const double wy = x(L::kVy) + r * wheel.position_m.x();
  return std::hypot(wx, wy) * dt;
}

void AddProcessNoise(const mapio::VehicleConfig& vehicle, const StateLayout& layout, const FilterConfig& config,
                     const Eigen::VectorXd& x, Eigen::MatrixXd& p, double dt) {
  const ProcessNoise& q = config.process_noise;
  const double velocity = q.velocity_mps_per_sqrt_hz * q.velocity_mps_per_sqrt_hz * dt;
  const double accel = q.jerk_mps3_per_sqrt_hz * q.jerk_mps3_per_sqrt_hz * dt;
  p(L::kVx, L::kVx) += velocity;
  p(L::kVy, L::kVy) += velocity;
  p(L::kYawRate, L::kYawRate) += q.yaw_acceleration_radps2_per_sqrt_hz * q.yaw_acceleration_radps2_per_sqrt_hz * dt;
  p(L::kAx, L::kAx) += accel;
  p(L::kAy, L::kAy) += accel;
  p(L::kGyroBias, L::kGyroBias) += q.gyro_bias_radps_per_sqrt_hz * q.gyro_bias_radps_per_sqrt_hz * dt;
  if (layout.accel_bias >= 0) {
    const double bias = q.accel_bias_mps2_per_sqrt_hz * q.accel_bias_mps2_per_sqrt_hz * dt;
    p(layout.accel_bias, layout.accel_bias) += bias;
    p(layout.accel_bias + 1, layout.accel_bias + 1) += bias;
  }
  const double steering = q.steering_rate_radps_per_sqrt_hz * q.steering_rate_radps_per_sqrt_hz * dt;
  const SlipAwareOdometryConfig& s = config.slip_aware_odometry;
  for (std::size_t i = 0; i < layout.wheel_count(); ++i) {
    if (layout.steering[i] >= 0) p(layout.steering[i], layout.steering[i]) += steering;
    if (layout.rolling_radius[i] < 0) continue;
    const double distance = WheelDistance(vehicle.wheels[i], x, dt);
    p(layout.rolling_radius[i], layout.rolling_radius[i]) +=
        s.rolling_radius_noise_m_per_sqrt_m * s.rolling_radius_noise_m_per_sqrt_m * distance;
    p(layout.slip_gradient[i], layout.slip_gradient[i]) +=
        s.slip_gradient_noise_nm_per_sqrt_m * s.slip_gradient_noise_nm_per_sqrt_m * distance;
  }
}

}  // namespace

void PredictStep(const mapio::VehicleConfig& vehicle, const StateLayout& layout, const FilterConfig& config,
                 Eigen::VectorXd& x, Eigen::MatrixXd& p, double dt) {
  constexpr int b = L::kBaseSize;
  const Eigen::Index rest = x.size() - b;
  const Eigen::VectorXd before = x;  // the distance rolled in the step uses the velocity at its start
  const BaseJacobian f = PropagateState(x, dt);
  // P = [Pbb Pba; Pab Paa] -> [F Pbb F^T, F Pba; (F Pba)^T, Paa]
  const BaseJacobian fp = f.lazyProduct(p.topLeftCorner<b, b>());
  const BaseJacobian pbb = fp.lazyProduct(f.transpose());
  p.topLeftCorner<b, b>() = 0.5 * (pbb + pbb.transpose());
  if (rest > 0) {
    const Eigen::MatrixXd pba = f.lazyProduct(p.topRightCorner(b, rest));
    p.topRightCorner(b, rest) = pba;
    p.bottomLeftCorner(rest, b) = pba.transpose();
  }
  AddProcessNoise(vehicle, layout, config, before, p, dt);
}

}  // namespace rowloc::localization
