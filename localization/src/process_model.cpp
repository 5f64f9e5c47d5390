#include "rowloc/localization/process_model.hpp"

#include "rowloc/localization/kalman_update.hpp"

#include <array>
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

/// The body twist (vx, vy, r) at the start of a step: the distance rolled in the step uses it.
struct Twist {
  double vx_mps, vy_mps, yaw_rate_radps;
};

/// Distance (m) the centre of wheel i travels in dt at the body twist.
double WheelDistance(const mapio::WheelGeometry& wheel, const Twist& twist, double dt) {
  const double wx = twist.vx_mps - twist.yaw_rate_radps * wheel.position_m.y();
  const double wy = twist.vy_mps + twist.yaw_rate_radps * wheel.position_m.x();
  return std::sqrt(wx * wx + wy * wy) * dt;  // speeds: no overflow to guard against (std::hypot is slower)
}

void AddProcessNoise(const mapio::VehicleConfig& vehicle, const StateLayout& layout, const FilterConfig& config,
                     const Twist& twist, Eigen::MatrixXd& p, double dt) {
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
    const double distance = WheelDistance(vehicle.wheels[i], twist, dt);
    p(layout.rolling_radius[i], layout.rolling_radius[i]) +=
        s.rolling_radius_noise_m_per_sqrt_m * s.rolling_radius_noise_m_per_sqrt_m * distance;
    p(layout.slip_gradient[i], layout.slip_gradient[i]) +=
        s.slip_gradient_noise_nm_per_sqrt_m * s.slip_gradient_noise_nm_per_sqrt_m * distance;
  }
}

constexpr int kBase = L::kBaseSize;

/// The rows of f other than the identity's (the states whose step depends on others), each as a
/// list of its non-zero entries.
struct CoupledRows {
  std::size_t count = 0;
  std::array<int, kBase> state{};                 ///< row of f
  std::array<std::size_t, kBase + 1> first{};     ///< entries of row k: [first[k], first[k + 1])
  std::array<int, kBase * kBase> column{};
  std::array<double, kBase * kBase> factor{};

  explicit CoupledRows(const BaseJacobian& f) {
    std::size_t entries = 0;
    for (int i = 0; i < kBase; ++i) {
      const std::size_t begin = entries;
      for (int j = 0; j < kBase; ++j) {
        if (f(i, j) == 0.0) continue;
        column[entries] = j;
        factor[entries++] = f(i, j);
      }
      if (entries == begin + 1 && column[begin] == i && factor[begin] == 1.0) {  // the identity's row
        entries = begin;
        continue;
      }
      state[count] = i;
      first[count++] = begin;
      first[count] = entries;
    }
  }
  /// sum_j f(state[k], j) v(j) over the non-zero entries.
  template <typename Vector>
  double Dot(std::size_t k, const Vector& v) const {
    double sum = 0.0;
    for (std::size_t e = first[k]; e < first[k + 1]; ++e) sum += factor[e] * v(column[e]);
    return sum;
  }
};

/// P <- F P F^T for F = diag(f, I) with a sparse f, from the columns c_i = sum_j f(i, j) P.col(j)
/// of P F^T for the coupled states i: since P is symmetric, row and column i of F P F^T are c_i
/// outside the coupled block, and the block is B(i, i') = sum_j f(i, j) c_i'(j). O(nnz(f - I) n)
/// on contiguous columns instead of O(9^2 n); P stays exactly symmetric (the block is averaged with
/// its transpose). Columns: an n x (up to 9) matrix type.
template <typename Columns>
void CongruenceWith(const BaseJacobian& f, Eigen::MatrixXd& p) {
  const Eigen::Index n = p.rows();
  const CoupledRows rows(f);
  const auto count = static_cast<Eigen::Index>(rows.count);
  Columns c = Columns::Zero(n, count);
  for (std::size_t k = 0; k < rows.count; ++k) {
    double* target = c.col(static_cast<Eigen::Index>(k)).data();
    for (std::size_t e = rows.first[k]; e < rows.first[k + 1]; ++e) {
      const double scale = rows.factor[e];
      const double* source = p.col(rows.column[e]).data();
      for (Eigen::Index r = 0; r < n; ++r) target[r] += scale * source[r];
    }
  }
  Eigen::Matrix<double, kBase, kBase> block;
  for (std::size_t a = 0; a < rows.count; ++a) {
    for (std::size_t b = 0; b < rows.count; ++b) {
      block(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) = rows.Dot(a, c.col(static_cast<Eigen::Index>(b)));
    }
  }
  for (std::size_t k = 0; k < rows.count; ++k) {
    p.col(rows.state[k]) = c.col(static_cast<Eigen::Index>(k));
    p.row(rows.state[k]) = c.col(static_cast<Eigen::Index>(k)).transpose();
  }
  for (Eigen::Index a = 0; a < count; ++a) {
    for (Eigen::Index b = a; b < count; ++b) {
      const int i = rows.state[static_cast<std::size_t>(a)], k = rows.state[static_cast<std::size_t>(b)];
      p(i, k) = p(k, i) = 0.5 * (block(a, b) + block(b, a));
    }
  }
}

/// Largest state served by stack temporaries (the shipped vehicles have at most 23 states).
constexpr int kStackStates = 64;

void Congruence(const BaseJacobian& f, Eigen::MatrixXd& p) {
  if (p.rows() <= kStackStates) {
    CongruenceWith<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kStackStates, kBase>>(f, p);
  } else {
    CongruenceWith<Eigen::MatrixXd>(f, p);
  }
}

}  // namespace

void PredictStep(const mapio::VehicleConfig& vehicle, const StateLayout& layout, const FilterConfig& config,
                 Eigen::VectorXd& x, Eigen::MatrixXd& p, double dt) {
  const Twist before{x(L::kVx), x(L::kVy), x(L::kYawRate)};
  Congruence(PropagateState(x, dt), p);
  AddProcessNoise(vehicle, layout, config, before, p, dt);
}

}  // namespace rowloc::localization
