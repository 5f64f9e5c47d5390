#include "rowloc/localization/process_model.hpp"

#include "rowloc/localization/gnss_bias_model.hpp"
#include "rowloc/localization/kalman_update.hpp"

#include "column_kernels.hpp"

#include <boost/container/small_vector.hpp>

#include <algorithm>
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
  BaseJacobian f = BaseJacobian::Zero();  // the identity, set as zeros and a diagonal (Identity() is not vectorized)
  f.diagonal().setOnes();
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

/// Per wheel, inline up to eight wheels: a prediction step allocates nothing on the heap.
using WheelDistances = boost::container::small_vector<double, 8>;

/// A random walk per metre rolled of one state per wheel (R_w or kappa), correlated rho between
/// wheels: Q = q^2 D^1/2 C D^1/2, D the wheels' distances this step and C the correlation matrix
/// (1 on its diagonal, rho off it).
void AddWheelRandomWalk(const std::vector<int>& states, const WheelDistances& distance_m, double q,
                        double rho, Eigen::MatrixXd& p) {
  const double q2 = q * q;
  for (std::size_t i = 0; i < states.size(); ++i) {
    p(states[i], states[i]) += q2 * distance_m[i];
    if (rho == 0.0) continue;
    for (std::size_t j = 0; j < i; ++j) {
      const double shared = rho * q2 * std::sqrt(distance_m[i] * distance_m[j]);
      p(states[i], states[j]) += shared;
      p(states[j], states[i]) += shared;
    }
  }
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
  }
  if (!layout.slip_aware()) return;
  if (layout.has_traction()) {
    const double traction = s.traction_noise_per_sqrt_s * s.traction_noise_per_sqrt_s * dt;
    for (const int k : layout.traction) p(k, k) += traction;
  }
  WheelDistances distance(layout.wheel_count());
  for (std::size_t i = 0; i < distance.size(); ++i) distance[i] = WheelDistance(vehicle.wheels[i], twist, dt);
  AddWheelRandomWalk(layout.rolling_radius, distance, s.rolling_radius_noise_m_per_sqrt_m,
                     s.rolling_radius_noise_wheel_correlation, p);
  AddWheelRandomWalk(layout.slip_compliance, distance, s.slip_compliance_noise_per_sqrt_m,
                     s.slip_compliance_wheel_correlation, p);
}

/// The rows of F other than the identity's (the states whose step depends on others) and the
/// columns of their non-zero entries, diagonal included: PropagateState's pattern (an entry of the
/// pattern may still be zero, e.g. f(vx, vy) = r dt at r = 0). Row k is state k: the coupled
/// states are the first five of the layout (static_assert), so their rows and columns of P are
/// its leading blocks.
struct CoupledRow {
  int count;  ///< 1 to 5
  std::array<int, 5> columns;
};
constexpr std::array<CoupledRow, 5> kCoupledRows{{
    {5, {L::kX, L::kPhi, L::kVx, L::kVy, L::kYawRate}},   // X
    {5, {L::kY, L::kPhi, L::kVx, L::kVy, L::kYawRate}},   // Y
    {2, {L::kPhi, L::kYawRate, 0, 0, 0}},                  // phi
    {4, {L::kVx, L::kVy, L::kYawRate, L::kAx, 0}},         // vx
    {4, {L::kVy, L::kVx, L::kYawRate, L::kAy, 0}},         // vy
}};
constexpr int kCoupled = static_cast<int>(kCoupledRows.size());
static_assert(L::kX == 0 && L::kY == 1 && L::kPhi == 2 && L::kVx == 3 && L::kVy == 4,
              "CongruenceWith writes the coupled rows and columns of P as leading blocks");

/// The columns c_k = sum_j f(k, j) P.col(j) of P F^T for the coupled states k, into c (n x
/// kCoupled, column-major) from the n x n column-major p, each in one pass (column_kernels.hpp).
ROWLOC_VECTOR_CLONES
void CoupledColumns(const BaseJacobian& f, const double* __restrict__ p, Eigen::Index n, double* __restrict__ c) {
  for (int k = 0; k < kCoupled; ++k) {
    const CoupledRow& row = kCoupledRows[static_cast<std::size_t>(k)];
    std::array<const double*, detail::kMaxCombinedColumns> sources{};
    std::array<double, detail::kMaxCombinedColumns> scales{};
    for (int e = 0; e < row.count; ++e) {
      const int j = row.columns[static_cast<std::size_t>(e)];
      sources[static_cast<std::size_t>(e)] = p + j * n;
      scales[static_cast<std::size_t>(e)] = f(k, j);
    }
    detail::CombineColumns<false>(sources.data(), scales.data(), row.count, n, c + k * n);
  }
}

/// P <- F P F^T for F = diag(f, I) with f of the pattern kCoupledRows, from the columns c_k of
/// P F^T (CoupledColumns): since P is symmetric, row and column k of F P F^T are c_k outside the
/// coupled block, and the block is B(a, b) = sum_j f(a, j) c_b(j), whose upper triangle (a <= b)
/// is written to both triangles (P stays exactly symmetric). O(nnz(f) n) on contiguous columns
/// instead of O(9^2 n). Columns: an n x kCoupled matrix type.
template <typename Columns>
void CongruenceWith(const BaseJacobian& f, Eigen::MatrixXd& p) {
  const Eigen::Index n = p.rows();
  Columns c(n, kCoupled);
  CoupledColumns(f, p.data(), n, c.data());
  // The coupled states' columns are c (the leading kCoupled columns of the column-major P: one
  // contiguous block) and their rows, by symmetry, c^T, written column by column (kCoupled
  // contiguous entries each; plain loops take fewer instructions than Eigen's block assignments
  // at these sizes). The block then overwrites the leading corner.
  double* const target = p.data();
  const double* const source = c.data();
  std::copy(source, source + kCoupled * n, target);
  for (Eigen::Index col = kCoupled; col < n; ++col) {
    for (Eigen::Index k = 0; k < kCoupled; ++k) target[col * n + k] = source[k * n + col];
  }
  // The block B = F_(coupled, :) C: row a of f reaches only the columns of its pattern (base states,
  // the leading rows of each c_b), so B(a, b) sums row.count products, 63 on the upper triangle
  // instead of a dense 5 x 9 by 9 x 5 product's 225. Written to both triangles.
#pragma GCC unroll 5
  for (int b = 0; b < kCoupled; ++b) {
    const double* const c_b = source + b * n;
#pragma GCC unroll 5
    for (int a = 0; a <= b; ++a) {
      const CoupledRow& row = kCoupledRows[static_cast<std::size_t>(a)];
      double sum = 0.0;
#pragma GCC unroll 5
      for (int e = 0; e < row.count; ++e) {
        const int j = row.columns[static_cast<std::size_t>(e)];
        sum += f(a, j) * c_b[j];
      }
      p(a, b) = p(b, a) = sum;
    }
  }
}

/// Largest state served by stack temporaries (the shipped vehicles have at most 23 states).
constexpr int kStackStates = 64;

void Congruence(const BaseJacobian& f, Eigen::MatrixXd& p) {
  if (p.rows() <= kStackStates) {
    CongruenceWith<Eigen::Matrix<double, Eigen::Dynamic, kCoupled, 0, kStackStates, kCoupled>>(f, p);
  } else {
    CongruenceWith<Eigen::Matrix<double, Eigen::Dynamic, kCoupled>>(f, p);
  }
}

}  // namespace

double GnssBiasDecay(const StateLayout& layout, const GpsNoise& gps, double dt_s) {
  return GnssBiasModel(gps, layout).Decay(dt_s);
}

void PredictStep(const mapio::VehicleConfig& vehicle, const StateLayout& layout, const FilterConfig& config,
                 Eigen::VectorXd& x, Eigen::MatrixXd& p, double dt, BaseJacobian* base_jacobian) {
  const Twist before{x(L::kVx), x(L::kVy), x(L::kYawRate)};
  const BaseJacobian f = PropagateState(x, dt);
  Congruence(f, p);
  if (base_jacobian != nullptr) *base_jacobian = f;
  AddProcessNoise(vehicle, layout, config, before, p, dt);
  if (layout.gnss_bias >= 0) GnssBiasModel(config.gps, layout).Propagate(x, p, dt);
}

}  // namespace rowloc::localization
