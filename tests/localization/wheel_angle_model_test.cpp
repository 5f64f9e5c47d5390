// Wheel-angle states (wheel_angle_model.hpp): the propagation's covariance step against the
// Jacobian of the state step by central differences, alone and followed by the base step; the
// measurement model.
#include "rowloc/localization/wheel_angle_model.hpp"

#include "rowloc/localization/kalman_update.hpp"
#include "rowloc/localization/process_model.hpp"
#include "random_spd.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <stdexcept>
#include <vector>

namespace rowloc::localization {
namespace {

using L = StateLayout;

std::vector<mapio::VehicleConfig> ShippedVehicles() {
  return {mapio::AgrimaroSwerveConfig(), mapio::VineyardUgv4wsConfig(), mapio::DifferentialDriveConfig(),
          mapio::TrackedVehicleConfig()};
}

StateLayout AngleLayout(const mapio::VehicleConfig& vehicle, bool slip_aware) {
  return StateLayout::For(vehicle, {.slip_aware_odometry = slip_aware, .accel_bias = true, .wheel_angles = true});
}

/// A state inside every model's domain: moving forward, nominal radii, kappa mu well below 1.
Eigen::VectorXd RandomState(const mapio::VehicleConfig& vehicle, const StateLayout& layout, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(layout.size);
  x(L::kPhi) = 3.0 * u(rng);
  x(L::kVx) = 1.0 + 0.5 * u(rng);
  x(L::kVy) = 0.05 * u(rng);
  x(L::kYawRate) = 0.5 * u(rng);
  x(L::kAx) = 0.5 * u(rng);
  x(L::kAy) = 0.5 * u(rng);
  for (std::size_t i = 0; i < vehicle.wheels.size(); ++i) {
    if (layout.steering[i] >= 0) x(layout.steering[i]) = 0.3 * u(rng);
    if (layout.rolling_radius[i] >= 0) {
      x(layout.rolling_radius[i]) = vehicle.wheels[i].nominal_radius_m * (1.0 + 0.05 * u(rng));
      x(layout.slip_compliance[i]) = 1.0 + 0.5 * u(rng);
    }
    x(layout.wheel_angle[i]) = 100.0 * u(rng);
  }
  return x;
}

std::vector<double> RandomTorques(const mapio::VehicleConfig& vehicle, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> mu(-0.1, 0.2);
  std::vector<double> torques;
  for (std::size_t i = 0; i < vehicle.wheels.size(); ++i) torques.push_back(mu(rng) * WheelTractionScaleNm(vehicle, i));
  return torques;
}

/// d step(x) / dx by central differences, where step maps the state alone (zero covariance).
template <typename Step>
Eigen::MatrixXd NumericJacobian(const Eigen::VectorXd& x0, Step&& step) {
  const Eigen::Index n = x0.size();
  Eigen::MatrixXd f(n, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    const double h = 1e-6 * std::max(1.0, std::abs(x0(j)));
    Eigen::VectorXd plus = x0, minus = x0;
    plus(j) += h;
    minus(j) -= h;
    step(plus);
    step(minus);
    Eigen::VectorXd diff = plus - minus;
    diff(L::kPhi) = WrapAngle(diff(L::kPhi));
    f.col(j) = diff / (2.0 * h);
  }
  return f;
}

// P <- (I + dt E J) P (I + dt E J)^T + q^2 dt on the angles, and theta += dt omega(x): the step's
// Jacobian by central differences stands for I + dt E J.
TEST(PropagateWheelAngles, CovarianceStepIsTheCongruenceWithTheStepsJacobian) {
  std::mt19937_64 rng(17);
  const FilterConfig config;
  const double q2 = config.wheels.angle_rate_noise_radps_per_sqrt_hz * config.wheels.angle_rate_noise_radps_per_sqrt_hz;
  for (const mapio::VehicleConfig& vehicle : ShippedVehicles()) {
    for (const bool slip_aware : {false, true}) {
      SCOPED_TRACE(vehicle.name + (slip_aware ? " slip-aware" : ""));
      const StateLayout layout = AngleLayout(vehicle, slip_aware);
      for (int trial = 0; trial < 10; ++trial) {
        const Eigen::VectorXd x0 = RandomState(vehicle, layout, rng);
        const Eigen::MatrixXd p0 = test::RandomSpd(layout.size, rng, 1e-3) * 1e-2;
        const std::optional<std::vector<double>> torques =
            trial % 2 == 0 ? std::optional<std::vector<double>>(RandomTorques(vehicle, rng)) : std::nullopt;
        const double dt = 0.02;
        WheelAngleScratch scratch;
        const auto step = [&](Eigen::VectorXd& x) {
          Eigen::MatrixXd unused = Eigen::MatrixXd::Zero(layout.size, layout.size);
          PropagateWheelAngles(vehicle, layout, config, torques, x, unused, dt, scratch);
        };
        Eigen::VectorXd x = x0;
        Eigen::MatrixXd p = p0;
        PropagateWheelAngles(vehicle, layout, config, torques, x, p, dt, scratch);
        const Eigen::MatrixXd f = NumericJacobian(x0, step);
        Eigen::MatrixXd expected = f * p0 * f.transpose();
        for (const int k : layout.wheel_angle) expected(k, k) += q2 * dt;
        EXPECT_LT((p - expected).cwiseAbs().maxCoeff(), 1e-8 * p0.cwiseAbs().maxCoeff());
        EXPECT_EQ((p - p.transpose()).cwiseAbs().maxCoeff(), 0.0);
        // Only the angles move, by dt omega(x).
        const LinearizedMeasurement omega = WheelSpeedModel(x0, vehicle, layout, torques, 0.0,
                                                            config.slip_aware_odometry.traction_from_acceleration);
        for (Eigen::Index k = 0; k < layout.size; ++k) {
          const auto it = std::find(layout.wheel_angle.begin(), layout.wheel_angle.end(), static_cast<int>(k));
          if (it == layout.wheel_angle.end()) {
            EXPECT_EQ(x(k), x0(k)) << k;
          } else {
            const auto i = static_cast<Eigen::Index>(it - layout.wheel_angle.begin());
            EXPECT_NEAR(x(k), x0(k) + dt * omega.predicted(i), 1e-12 * std::abs(x0(k)) + 1e-15);
          }
        }
      }
    }
  }
}

// The whole prediction step (angles first, then PredictStep) has the covariance F P F^T + Q with F
// the Jacobian of the whole state step: F = F_base (I + dt E J), as wheel_angle_model.hpp claims.
TEST(PropagateWheelAngles, FollowedByTheBaseStepPropagatesWithTheFullJacobian) {
  std::mt19937_64 rng(5);
  const FilterConfig config;
  for (const mapio::VehicleConfig& vehicle : ShippedVehicles()) {
    SCOPED_TRACE(vehicle.name);
    const StateLayout layout = AngleLayout(vehicle, true);
    for (int trial = 0; trial < 10; ++trial) {
      const Eigen::VectorXd x0 = RandomState(vehicle, layout, rng);
      const std::optional<std::vector<double>> torques = RandomTorques(vehicle, rng);
      const double dt = 0.015;
      WheelAngleScratch scratch;
      const auto full_step = [&](Eigen::VectorXd& x, Eigen::MatrixXd& p) {
        PropagateWheelAngles(vehicle, layout, config, torques, x, p, dt, scratch);
        PredictStep(vehicle, layout, config, x, p, dt);
      };
      Eigen::VectorXd x = x0;
      Eigen::MatrixXd noise = Eigen::MatrixXd::Zero(layout.size, layout.size);
      full_step(x, noise);  // from P = 0: Q
      const Eigen::MatrixXd f = NumericJacobian(x0, [&](Eigen::VectorXd& s) {
        Eigen::MatrixXd unused = Eigen::MatrixXd::Zero(layout.size, layout.size);
        full_step(s, unused);
      });
      const Eigen::MatrixXd p0 = test::RandomSpd(layout.size, rng, 1e-3) * 1e-2;
      Eigen::MatrixXd p = p0;
      x = x0;
      full_step(x, p);
      const Eigen::MatrixXd expected = f * p0 * f.transpose() + noise;
      EXPECT_LT((p - expected).cwiseAbs().maxCoeff(), 1e-7 * p0.cwiseAbs().maxCoeff());
    }
  }
}

TEST(PropagateWheelAngles, DoesNothingWithoutAngleStates) {
  const mapio::VehicleConfig vehicle = mapio::DifferentialDriveConfig();
  const StateLayout layout = StateLayout::For(vehicle, true);
  std::mt19937_64 rng(3);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(layout.size);
  x(L::kVx) = 1.0;
  x(layout.rolling_radius[0]) = x(layout.rolling_radius[1]) = 0.165;
  const Eigen::VectorXd x0 = x;
  Eigen::MatrixXd p = test::RandomSpd(layout.size, rng, 1e-3);
  const Eigen::MatrixXd p0 = p;
  WheelAngleScratch scratch;
  PropagateWheelAngles(vehicle, layout, FilterConfig{}, std::nullopt, x, p, 0.02, scratch);
  EXPECT_EQ(x, x0);
  EXPECT_EQ(p, p0);
}

TEST(WheelAngleModel, PredictsTheAngleStates) {
  const mapio::VehicleConfig vehicle = mapio::AgrimaroSwerveConfig();
  const StateLayout layout = AngleLayout(vehicle, true);
  std::mt19937_64 rng(9);
  const Eigen::VectorXd x = RandomState(vehicle, layout, rng);
  LinearizedMeasurement m;
  WheelAngleModel(x, layout, m);
  ASSERT_EQ(m.predicted.size(), static_cast<Eigen::Index>(vehicle.wheels.size()));
  ASSERT_EQ(m.jacobian.cols(), layout.size);
  for (std::size_t i = 0; i < vehicle.wheels.size(); ++i) {
    const auto row = static_cast<Eigen::Index>(i);
    EXPECT_EQ(m.predicted(row), x(layout.wheel_angle[i]));
    EXPECT_EQ(m.jacobian(row, layout.wheel_angle[i]), 1.0);
    EXPECT_EQ(m.jacobian.row(row).cwiseAbs().sum(), 1.0);
  }
  EXPECT_THROW(WheelAngleModel(x, StateLayout::For(vehicle, true), m), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::localization
