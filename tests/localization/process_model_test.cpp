// Process model of the vehicle EKF (process_model.hpp): Jacobian, exact motions, covariance step.
#include "rowloc/localization/process_model.hpp"

#include "rowloc/localization/kalman_update.hpp"
#include "random_spd.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace rowloc::localization {
namespace {

using L = StateLayout;
constexpr double kPi = std::numbers::pi;

std::vector<mapio::VehicleConfig> ShippedVehicles() {
  return {mapio::AgrimaroSwerveConfig(), mapio::VineyardUgv4wsConfig(), mapio::DifferentialDriveConfig(),
          mapio::TrackedVehicleConfig()};
}

Eigen::VectorXd RandomState(Eigen::Index size, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd x(size);
  for (Eigen::Index i = 0; i < size; ++i) x(i) = u(rng);
  x(L::kX) = 100.0 * u(rng);
  x(L::kY) = 100.0 * u(rng);
  x(L::kPhi) = 3.0 * u(rng);
  x(L::kVx) = 3.0 * u(rng);
  x(L::kYawRate) = 1.5 * u(rng);
  x(L::kAx) = 2.0 * u(rng);
  x(L::kAy) = 2.0 * u(rng);
  return x;
}

TEST(PropagateState, JacobianMatchesCentralDifferences) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> step(0.0, 0.05);
  for (int trial = 0; trial < 500; ++trial) {
    const Eigen::VectorXd x0 = RandomState(L::kBaseSize, rng);
    const double dt = trial == 0 ? 0.0 : step(rng);
    Eigen::VectorXd x = x0;
    const BaseJacobian f = PropagateState(x, dt);
    for (int j = 0; j < L::kBaseSize; ++j) {
      const double h = 1e-6 * std::max(1.0, std::abs(x0(j)));
      Eigen::VectorXd plus = x0, minus = x0;
      plus(j) += h;
      minus(j) -= h;
      PropagateState(plus, dt);
      PropagateState(minus, dt);
      Eigen::VectorXd diff = plus - minus;
      diff(L::kPhi) = WrapAngle(diff(L::kPhi));
      const Eigen::VectorXd numeric = diff / (2.0 * h);
      for (int i = 0; i < L::kBaseSize; ++i) {
        EXPECT_NEAR(f(i, j), numeric(i), 1e-6 * std::max(1.0, std::abs(numeric(i))))
            << "dF(" << i << ", " << j << ") dt " << dt << " trial " << trial;
      }
    }
  }
}

TEST(PropagateState, ZeroStepIsTheIdentity) {
  std::mt19937 rng(32);
  const Eigen::VectorXd x0 = RandomState(L::kBaseSize, rng);
  Eigen::VectorXd x = x0;
  const BaseJacobian f = PropagateState(x, 0.0);
  EXPECT_TRUE(f.isIdentity(0.0));
  EXPECT_TRUE(x.isApprox(x0, 1e-15));
}

TEST(PropagateState, LeavesTheAugmentedStatesAlone) {
  std::mt19937 rng(33);
  const Eigen::VectorXd x0 = RandomState(L::kBaseSize + 7, rng);
  Eigen::VectorXd x = x0;
  PropagateState(x, 0.02);
  EXPECT_EQ(x.tail(7), x0.tail(7));
  EXPECT_EQ(x(L::kAx), x0(L::kAx));
  EXPECT_EQ(x(L::kGyroBias), x0(L::kGyroBias));
}

TEST(PropagateState, StraightConstantVelocityMotionIsExact) {
  std::mt19937 rng(34);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::VectorXd x = Eigen::VectorXd::Zero(L::kBaseSize);
    x << 10 * u(rng), 10 * u(rng), 3 * u(rng), 2 * u(rng), 0.3 * u(rng), 0, 0, 0, 0.01;
    const Eigen::VectorXd x0 = x;
    const double dt = 0.01 + 0.04 * (u(rng) + 1) / 2;
    const int steps = 500;
    for (int k = 0; k < steps; ++k) PropagateState(x, dt);
    const double t = dt * steps;
    const double c = std::cos(x0(L::kPhi)), s = std::sin(x0(L::kPhi));
    EXPECT_NEAR(x(L::kX), x0(L::kX) + t * (c * x0(L::kVx) - s * x0(L::kVy)), 1e-10);
    EXPECT_NEAR(x(L::kY), x0(L::kY) + t * (s * x0(L::kVx) + c * x0(L::kVy)), 1e-10);
    EXPECT_EQ(x.tail(7), x0.tail(7));  // heading, velocities, rates unchanged
  }
}

TEST(PropagateState, ConstantAccelerationIntegratesTheVelocityExactly) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(L::kBaseSize);
  x(L::kVx) = 0.5;
  x(L::kAx) = 0.8;
  x(L::kAy) = -0.3;
  for (int k = 0; k < 100; ++k) PropagateState(x, 0.01);
  EXPECT_NEAR(x(L::kVx), 0.5 + 0.8, 1e-12);
  EXPECT_NEAR(x(L::kVy), -0.3, 1e-12);
}

// The exact pose after dt on a circle of speed v and yaw rate r (chord along the mid-step heading).
Eigen::Vector3d ExactArc(const Eigen::Vector3d& pose, double v, double r, double dt) {
  const double half = 0.5 * r * dt;
  const double chord = 2.0 * v / r * std::sin(half);
  const double mid = pose.z() + half;
  return {pose.x() + chord * std::cos(mid), pose.y() + chord * std::sin(mid), pose.z() + r * dt};
}

// vx, r constant, vy = ax = 0: the centripetal acceleration a_By = r vx keeps vy at 0 (vy' = ay - r vx).
Eigen::VectorXd CircleState(double v, double r) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(L::kBaseSize);
  x << 3.0, -2.0, 0.4, v, 0.0, r, 0.0, r * v, 0.0;
  return x;
}

double OneStepArcError(double v, double r, double dt) {
  Eigen::VectorXd x = CircleState(v, r);
  const Eigen::Vector3d exact = ExactArc(x.head<3>(), v, r, dt);
  PropagateState(x, dt);
  return (x.head<2>() - exact.head<2>()).norm();
}

TEST(PropagateState, ConstantSpeedCircleHasThirdOrderStepError) {
  for (const double r : {0.3, -0.8, 1.5}) {
    const double v = 2.0;
    for (const double dt : {0.05, 0.02, 0.01}) {
      const double error = OneStepArcError(v, r, dt);
      // Step of length v dt instead of the chord: v dt (r dt)^2 / 24 to leading order.
      EXPECT_NEAR(error, std::abs(v) * dt * r * r * dt * dt / 24.0, 0.01 * std::abs(v) * dt * r * r * dt * dt / 24.0)
          << "r " << r << " dt " << dt;
      EXPECT_NEAR(OneStepArcError(v, r, dt) / OneStepArcError(v, r, dt / 2), 8.0, 0.05) << "r " << r;
    }
  }
}

TEST(PropagateState, ConstantSpeedCircleKeepsTheSpeedAndFollowsTheArc) {
  const double v = 1.5, r = 0.25, dt = 0.02;
  Eigen::VectorXd x = CircleState(v, r);
  Eigen::Vector3d exact = x.head<3>();
  const int steps = static_cast<int>(std::round(2 * kPi / r / dt));  // about one full circle
  double max_error = 0.0;
  for (int k = 0; k < steps; ++k) {
    PropagateState(x, dt);
    exact = ExactArc(exact, v, r, dt);
    max_error = std::max(max_error, (x.head<2>() - exact.head<2>()).norm());
    ASSERT_NEAR(WrapAngle(x(L::kPhi) - exact.z()), 0.0, 1e-9);
    ASSERT_GT(x(L::kPhi), -kPi);
    ASSERT_LE(x(L::kPhi), kPi);
  }
  EXPECT_DOUBLE_EQ(x(L::kVx), v);
  EXPECT_DOUBLE_EQ(x(L::kVy), 0.0);
  // The steps have length v dt instead of the chord 2 v / r sin(r dt / 2): the polygon is the exact
  // one scaled by 1 + (r dt)^2 / 24 about the start, so the error peaks at the far side of the circle.
  const double scale_error = (r * dt) * (r * dt) / 24.0;
  EXPECT_NEAR(max_error, scale_error * 2.0 * v / r, 0.02 * scale_error * 2.0 * v / r);
  // Back near the start after a full circle (radius v / r = 6 m).
  EXPECT_NEAR((x.head<2>() - Eigen::Vector2d(3.0, -2.0)).norm(), 0.0, v * dt);
}

// Diagonal of Q over dt for the layout (distance-driven terms left out: callers check them).
Eigen::VectorXd ExpectedBaseNoise(const StateLayout& layout, const FilterConfig& c, double dt) {
  const ProcessNoise& q = c.process_noise;
  Eigen::VectorXd d = Eigen::VectorXd::Zero(layout.size);
  d(L::kVx) = d(L::kVy) = q.velocity_mps_per_sqrt_hz * q.velocity_mps_per_sqrt_hz * dt;
  d(L::kYawRate) = q.yaw_acceleration_radps2_per_sqrt_hz * q.yaw_acceleration_radps2_per_sqrt_hz * dt;
  d(L::kAx) = d(L::kAy) = q.jerk_mps3_per_sqrt_hz * q.jerk_mps3_per_sqrt_hz * dt;
  d(L::kGyroBias) = q.gyro_bias_radps_per_sqrt_hz * q.gyro_bias_radps_per_sqrt_hz * dt;
  for (int index : layout.steering) {
    if (index >= 0) d(index) = q.steering_rate_radps_per_sqrt_hz * q.steering_rate_radps_per_sqrt_hz * dt;
  }
  return d;
}

TEST(PredictStep, CovarianceIsFPFtPlusQWithIdentityOutsideTheBase) {
  std::mt19937 rng(41);
  std::mt19937_64 spd_rng(42);
  const FilterConfig config;
  for (const mapio::VehicleConfig& vehicle : ShippedVehicles()) {
    for (bool slip : {false, true}) {
      SCOPED_TRACE(vehicle.name + (slip ? " slip-aware" : ""));
      const StateLayout layout = StateLayout::For(vehicle, slip);
      const Eigen::Index n = layout.size;
      Eigen::VectorXd x = RandomState(n, rng);
      Eigen::MatrixXd p0 = test::RandomSpd(n, spd_rng, 0.1);
      p0 = (0.5 * (p0 + p0.transpose())).eval();  // exactly symmetric input
      Eigen::MatrixXd p = p0;
      Eigen::VectorXd x_model = x;
      const BaseJacobian fb = PropagateState(x_model, 0.02);
      Eigen::MatrixXd f = Eigen::MatrixXd::Identity(n, n);
      f.topLeftCorner<L::kBaseSize, L::kBaseSize>() = fb;
      PredictStep(vehicle, layout, config, x, p, 0.02);
      EXPECT_EQ(x, x_model);
      Eigen::MatrixXd delta = p - f * p0 * f.transpose();
      // The increment is diagonal: the documented Q (plus the distance terms of R_w and kappa).
      const Eigen::VectorXd q = ExpectedBaseNoise(layout, config, 0.02);
      for (Eigen::Index i = 0; i < n; ++i) {
        for (Eigen::Index j = 0; j < n; ++j) {
          const bool distance_term = i == j && slip && i >= n - 2 * static_cast<Eigen::Index>(vehicle.wheels.size());
          if (distance_term) continue;
          EXPECT_NEAR(delta(i, j), i == j ? q(i) : 0.0, 1e-12 * p0.norm()) << i << ", " << j;
        }
      }
      // Cross-covariances of the augmented states propagate as F P; their own block only gains Q.
      const Eigen::Index rest = n - L::kBaseSize;
      if (rest > 0) {
        EXPECT_TRUE(p.topRightCorner(L::kBaseSize, rest).isApprox(fb * p0.topRightCorner(L::kBaseSize, rest), 1e-14));
        Eigen::MatrixXd own = p.bottomRightCorner(rest, rest) - p0.bottomRightCorner(rest, rest);
        own.diagonal().setZero();
        EXPECT_EQ(own.cwiseAbs().maxCoeff(), 0.0);
      }
      EXPECT_EQ(p, p.transpose());
    }
  }
}

TEST(PredictStep, StaysPositiveDefiniteOverManyStepsForEveryVehicle) {
  std::mt19937 rng(43);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  FilterConfig config;
  for (const mapio::VehicleConfig& vehicle : ShippedVehicles()) {
    for (bool slip : {false, true}) {
      SCOPED_TRACE(vehicle.name + (slip ? " slip-aware" : ""));
      const StateLayout layout = StateLayout::For(vehicle, slip);
      Eigen::VectorXd x = RandomState(layout.size, rng);
      // A realistic initial covariance: small, diagonal, some states nearly certain.
      Eigen::MatrixXd p = Eigen::MatrixXd::Identity(layout.size, layout.size) * 1e-6;
      p(L::kPhi, L::kPhi) = 0.04;
      p(L::kVx, L::kVx) = 0.09;
      for (int step = 0; step < 3000; ++step) {
        x(L::kAx) = 0.5 * u(rng);  // keep the speed bounded
        x(L::kAy) = 0.5 * u(rng);
        x(L::kVx) = std::clamp(x(L::kVx), -2.0, 2.0);
        PredictStep(vehicle, layout, config, x, p, 0.001 + 0.049 * (u(rng) + 1) / 2);
        if (step % 100 == 99) {
          ASSERT_EQ(p, p.transpose()) << step;
          const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(p);
          ASSERT_GT(eig.eigenvalues().minCoeff(), 0.0) << step;
          ASSERT_TRUE(p.allFinite());
          ASSERT_GT(x(L::kPhi), -kPi);
          ASSERT_LE(x(L::kPhi), kPi);
        }
      }
    }
  }
}

TEST(PredictStep, AccelerometerBiasIsARandomWalkInTime) {
  const FilterConfig config;
  const double q = config.process_noise.accel_bias_mps2_per_sqrt_hz;
  for (const mapio::VehicleConfig& vehicle : ShippedVehicles()) {
    SCOPED_TRACE(vehicle.name);
    const StateLayout layout = StateLayout::For(vehicle, {.slip_aware_odometry = true, .accel_bias = true});
    Eigen::VectorXd x = Eigen::VectorXd::Zero(layout.size);
    x(L::kVx) = 1.0;
    x(layout.accel_bias) = 0.3;
    x(layout.accel_bias + 1) = -0.1;
    Eigen::MatrixXd p = Eigen::MatrixXd::Zero(layout.size, layout.size);  // the increment is Q
    PredictStep(vehicle, layout, config, x, p, 0.02);
    EXPECT_EQ(x(layout.accel_bias), 0.3);  // constant in the mean
    EXPECT_EQ(x(layout.accel_bias + 1), -0.1);
    EXPECT_NEAR(p(layout.accel_bias, layout.accel_bias), q * q * 0.02, 1e-15);
    EXPECT_NEAR(p(layout.accel_bias + 1, layout.accel_bias + 1), q * q * 0.02, 1e-15);
    EXPECT_EQ(p(layout.accel_bias, layout.accel_bias + 1), 0.0);
  }
}

TEST(PredictStep, GnssBiasIsAnExactGaussMarkovProcess) {
  FilterConfig config;
  config.gps.estimate_bias = true;
  config.gps.bias_sigma_m = 0.3;
  config.gps.bias_time_constant_s = 4.0;
  const double s2 = 0.09, tau = 4.0;
  std::mt19937_64 spd_rng(44);
  for (const mapio::VehicleConfig& vehicle : ShippedVehicles()) {
    SCOPED_TRACE(vehicle.name);
    const StateLayout layout =
        StateLayout::For(vehicle, {.slip_aware_odometry = true, .accel_bias = true, .gnss_bias = true});
    const int b = layout.gnss_bias;
    ASSERT_EQ(b, layout.size - 2);
    // The mean decays by a = exp(-dt / tau); the rest of the state moves as without the bias.
    Eigen::VectorXd x = Eigen::VectorXd::Zero(layout.size);
    x(L::kVx) = 1.0;
    x(b) = 0.8;
    x(b + 1) = -0.4;
    Eigen::VectorXd x_without = x.head(b);
    Eigen::MatrixXd p0 = test::RandomSpd(layout.size, spd_rng, 0.1);
    p0 = (0.5 * (p0 + p0.transpose())).eval();
    Eigen::MatrixXd p = p0, p_without = p0.topLeftCorner(b, b);
    const StateLayout plain = StateLayout::For(vehicle, {.slip_aware_odometry = true, .accel_bias = true});
    PredictStep(vehicle, layout, config, x, p, 0.02);
    PredictStep(vehicle, plain, config, x_without, p_without, 0.02);
    const double a = std::exp(-0.02 / tau);
    EXPECT_DOUBLE_EQ(GnssBiasDecay(layout, config.gps, 0.02), a);
    EXPECT_DOUBLE_EQ(GnssBiasDecay(plain, config.gps, 0.02), 1.0);
    EXPECT_NEAR(x(b), 0.8 * a, 1e-15);
    EXPECT_NEAR(x(b + 1), -0.4 * a, 1e-15);
    EXPECT_EQ(x.head(b), x_without);
    EXPECT_EQ(p.topLeftCorner(b, b), p_without);
    // Its rows of P are scaled by a (F is diagonal there), its own block by a^2 plus Q_b; the
    // augmented states' rows (F the identity) show the scaling alone.
    EXPECT_NEAR(p(b, b), a * a * p0(b, b) + s2 * (1.0 - a * a), 1e-14 * p0.norm());
    EXPECT_NEAR(p(b, b + 1), a * a * p0(b, b + 1), 1e-14 * p0.norm());
    EXPECT_NEAR(p(b + 1, b + 1), a * a * p0(b + 1, b + 1) + s2 * (1.0 - a * a), 1e-14 * p0.norm());
    for (int k = L::kBaseSize; k < b; ++k) EXPECT_NEAR(p(k, b), a * p0(k, b), 1e-14 * p0.norm()) << k;
    EXPECT_EQ(p, p.transpose());
  }
}

TEST(PredictStep, GnssBiasVarianceIsStationaryAndIndependentOfTheStepSplit) {
  FilterConfig config;
  config.gps.estimate_bias = true;
  const double s2 = config.gps.bias_sigma_m * config.gps.bias_sigma_m, tau = config.gps.bias_time_constant_s;
  const mapio::VehicleConfig vehicle = ShippedVehicles().front();
  const StateLayout layout = StateLayout::For(vehicle, {.gnss_bias = true});
  const int b = layout.gnss_bias;
  const auto run = [&](double variance0, double dt, int steps) {
    Eigen::VectorXd x = Eigen::VectorXd::Zero(layout.size);
    x(b) = 1.0;
    Eigen::MatrixXd p = Eigen::MatrixXd::Identity(layout.size, layout.size) * 1e-4;
    p(b, b) = variance0;
    for (int k = 0; k < steps; ++k) PredictStep(vehicle, layout, config, x, p, dt);
    return std::pair{x(b), p(b, b)};
  };
  // From the stationary variance it stays there; from zero it follows s^2 (1 - exp(-2 t / tau)),
  // and the mean exp(-t / tau), whatever the step (the discretization is exact).
  for (const auto& [dt, steps] : {std::pair{0.02, 500}, std::pair{0.1, 100}, std::pair{10.0, 1}}) {
    SCOPED_TRACE(dt);
    EXPECT_NEAR(run(s2, dt, steps).second, s2, 1e-12);
    const auto [mean, variance] = run(0.0, dt, steps);
    EXPECT_NEAR(variance, s2 * (1.0 - std::exp(-2.0 * 10.0 / tau)), 1e-12);
    EXPECT_NEAR(mean, std::exp(-10.0 / tau), 1e-12);
  }
}

TEST(PredictStep, SlipStateNoiseGrowsWithTheDistanceRolled) {
  const FilterConfig config;
  const SlipAwareOdometryConfig& s = config.slip_aware_odometry;
  for (const mapio::VehicleConfig& vehicle : ShippedVehicles()) {
    SCOPED_TRACE(vehicle.name);
    const StateLayout layout = StateLayout::For(vehicle, true);
    // Wheel-centre speeds for a body twist (vx, vy, r) (constant over the step: ax = ay = 0, vy = 0 or r = 0).
    const auto increments = [&](double vx, double vy, double r, double dt) {
      Eigen::VectorXd x = Eigen::VectorXd::Zero(layout.size);
      x(L::kVx) = vx;
      x(L::kVy) = vy;
      x(L::kYawRate) = r;
      Eigen::MatrixXd p = Eigen::MatrixXd::Zero(layout.size, layout.size);  // the increment is Q
      PredictStep(vehicle, layout, config, x, p, dt);
      return Eigen::VectorXd(p.diagonal());
    };
    // Standing still: no growth at all.
    const Eigen::VectorXd still = increments(0.0, 0.0, 0.0, 0.05);
    for (std::size_t i = 0; i < vehicle.wheels.size(); ++i) {
      EXPECT_EQ(still(layout.rolling_radius[i]), 0.0);
      EXPECT_EQ(still(layout.slip_compliance[i]), 0.0);
    }
    // Straight at v: every wheel rolls v dt.
    for (const double v : {0.5, 1.0, -2.0}) {
      const Eigen::VectorXd d = increments(v, 0.0, 0.0, 0.04);
      for (std::size_t i = 0; i < vehicle.wheels.size(); ++i) {
        const double distance = std::abs(v) * 0.04;
        const double radius_var = s.rolling_radius_noise_m_per_sqrt_m * s.rolling_radius_noise_m_per_sqrt_m * distance;
        const double compliance_var =
            s.slip_compliance_noise_per_sqrt_m * s.slip_compliance_noise_per_sqrt_m * distance;
        EXPECT_NEAR(d(layout.rolling_radius[i]), radius_var, 1e-12 * radius_var);
        EXPECT_NEAR(d(layout.slip_compliance[i]), compliance_var, 1e-12 * compliance_var);
      }
    }
    // Turning on the spot at r: wheel i rolls |r| |l_i| dt (0 for a wheel at the reference point).
    const double r = 0.7, dt = 0.03;
    const Eigen::VectorXd turn = increments(0.0, 0.0, r, dt);
    for (std::size_t i = 0; i < vehicle.wheels.size(); ++i) {
      const double distance = r * vehicle.wheels[i].position_m.norm() * dt;
      EXPECT_NEAR(turn(layout.slip_compliance[i]),
                  s.slip_compliance_noise_per_sqrt_m * s.slip_compliance_noise_per_sqrt_m * distance, 1e-12)
          << vehicle.wheels[i].name;
    }
  }
}

// The block of Q over one state per wheel (R_w or kappa), wheels in vehicle order.
Eigen::MatrixXd WheelBlock(const Eigen::MatrixXd& q, const std::vector<int>& states) {
  const auto n = static_cast<Eigen::Index>(states.size());
  Eigen::MatrixXd block(n, n);
  for (Eigen::Index a = 0; a < n; ++a) {
    for (Eigen::Index b = 0; b < n; ++b) block(a, b) = q(states[a], states[b]);
  }
  return block;
}

// A random walk per metre rolled shared rho between wheels: Q_ij = rho q^2 sqrt(d_i d_j) (q^2 d_i on
// the diagonal), symmetric and positive semi-definite; rho = 0 leaves the wheels independent.
void ExpectCorrelatedWalk(const Eigen::MatrixXd& block, double q, double rho) {
  const double q2 = q * q;
  for (Eigen::Index a = 0; a < block.rows(); ++a) {
    const double da = block(a, a) / q2;  // the distance wheel a rolled
    EXPECT_GT(da, 0.0);
    for (Eigen::Index b = 0; b < block.rows(); ++b) {
      if (a == b) continue;
      const double db = block(b, b) / q2;
      EXPECT_NEAR(block(a, b), rho * q2 * std::sqrt(da * db), 1e-12 * q2 * std::sqrt(da * db)) << rho;
      EXPECT_EQ(block(a, b), block(b, a));
    }
  }
  EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(block).eigenvalues().minCoeff(), -1e-12 * block.norm());
}

// slip_compliance_wheel_correlation and rolling_radius_noise_wheel_correlation: each correlates
// its own state's walk across the wheels and nothing else (R_w and kappa stay uncorrelated).
TEST(PredictStep, CorrelatedWheelRandomWalks) {
  const mapio::VehicleConfig vehicle = mapio::AgrimaroSwerveConfig();
  const StateLayout layout = StateLayout::For(vehicle, true);
  for (const double rho_kappa : {0.0, 0.5, 0.9999}) {
    for (const double rho_radius : {0.0, 0.9, 0.99}) {
      FilterConfig config;
      SlipAwareOdometryConfig& s = config.slip_aware_odometry;
      s.slip_compliance_wheel_correlation = rho_kappa;
      s.rolling_radius_noise_wheel_correlation = rho_radius;
      Eigen::VectorXd x = Eigen::VectorXd::Zero(layout.size);
      x(L::kVx) = 1.2;
      x(L::kYawRate) = 0.4;  // the wheels roll different distances
      Eigen::MatrixXd p = Eigen::MatrixXd::Zero(layout.size, layout.size);  // the increment is Q
      PredictStep(vehicle, layout, config, x, p, 0.05);
      ExpectCorrelatedWalk(WheelBlock(p, layout.slip_compliance), s.slip_compliance_noise_per_sqrt_m, rho_kappa);
      ExpectCorrelatedWalk(WheelBlock(p, layout.rolling_radius), s.rolling_radius_noise_m_per_sqrt_m, rho_radius);
      for (std::size_t a = 0; a < vehicle.wheels.size(); ++a) {
        for (std::size_t b = 0; b < vehicle.wheels.size(); ++b) {
          EXPECT_EQ(p(layout.rolling_radius[a], layout.slip_compliance[b]), 0.0);
        }
      }
    }
  }
}

// What the radius correlation is for: driving straight (equal distances d), the difference of two
// wheels' radii, which turns the vehicle, walks with 2 (1 - rho) q^2 d, and their mean with
// (1 + rho) q^2 d / 2.
TEST(PredictStep, CorrelatedRadiusWalkShrinksTheRadiusDifference) {
  const mapio::VehicleConfig vehicle = mapio::DifferentialDriveConfig();
  const StateLayout layout = StateLayout::For(vehicle, true);
  for (const double rho : {0.0, 0.99}) {
    FilterConfig config;
    config.slip_aware_odometry.rolling_radius_noise_wheel_correlation = rho;
    Eigen::VectorXd x = Eigen::VectorXd::Zero(layout.size);
    x(L::kVx) = 0.5;
    Eigen::MatrixXd p = Eigen::MatrixXd::Zero(layout.size, layout.size);
    const double dt = 0.02;
    PredictStep(vehicle, layout, config, x, p, dt);
    const double q2d = config.slip_aware_odometry.rolling_radius_noise_m_per_sqrt_m *
                       config.slip_aware_odometry.rolling_radius_noise_m_per_sqrt_m * 0.5 * dt;
    Eigen::VectorXd difference = Eigen::VectorXd::Zero(layout.size);
    difference(layout.rolling_radius[0]) = 1.0;
    difference(layout.rolling_radius[1]) = -1.0;
    Eigen::VectorXd mean = Eigen::VectorXd::Zero(layout.size);
    mean(layout.rolling_radius[0]) = mean(layout.rolling_radius[1]) = 0.5;
    EXPECT_NEAR(difference.dot(p * difference), 2.0 * (1.0 - rho) * q2d, 1e-9 * q2d) << rho;
    EXPECT_NEAR(mean.dot(p * mean), 0.5 * (1.0 + rho) * q2d, 1e-9 * q2d) << rho;
  }
}

TEST(PredictStep, WrapsTheHeading) {
  const mapio::VehicleConfig vehicle = mapio::DifferentialDriveConfig();
  const StateLayout layout = StateLayout::For(vehicle, false);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(layout.size);
  x(L::kPhi) = kPi - 0.001;
  x(L::kYawRate) = 1.0;
  Eigen::MatrixXd p = Eigen::MatrixXd::Identity(layout.size, layout.size);
  PredictStep(vehicle, layout, FilterConfig{}, x, p, 0.01);
  EXPECT_NEAR(x(L::kPhi), -kPi + 0.009, 1e-12);
  x(L::kPhi) = -kPi + 0.001;
  x(L::kYawRate) = -1.0;
  PredictStep(vehicle, layout, FilterConfig{}, x, p, 0.01);
  EXPECT_NEAR(x(L::kPhi), kPi - 0.009, 1e-12);
}

}  // namespace
}  // namespace rowloc::localization
