// Per-wheel SAE slip from the filtered state and raw encoder speeds (wheel_slip_estimate.hpp).
#include "rowloc/localization/wheel_slip_estimate.hpp"

#include "rowloc/localization/measurement_models.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

namespace rowloc::localization {
namespace {

using L = StateLayout;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(SaeSlip, FollowsTheFormula) {
  // Driving (wheel faster than the ground): positive, divided by |omega R|.
  EXPECT_DOUBLE_EQ(SaeSlip(10.0, 0.2, 1.5), (2.0 - 1.5) / 2.0);
  // Braking (wheel slower): negative, divided by |v|.
  EXPECT_DOUBLE_EQ(SaeSlip(5.0, 0.2, 1.5), (1.0 - 1.5) / 1.5);
  // Reversing: same formula with negative speeds, divided by the larger magnitude.
  EXPECT_DOUBLE_EQ(SaeSlip(-10.0, 0.2, -1.5), (-2.0 + 1.5) / 2.0);
  EXPECT_DOUBLE_EQ(SaeSlip(-5.0, 0.2, -1.5), (-1.0 + 1.5) / 1.5);
  // No slip.
  EXPECT_DOUBLE_EQ(SaeSlip(7.5, 0.2, 1.5), 0.0);
  // Locked wheel: -1; spinning wheel on a standing vehicle: +1.
  EXPECT_DOUBLE_EQ(SaeSlip(0.0, 0.2, 1.5), -1.0);
  EXPECT_DOUBLE_EQ(SaeSlip(10.0, 0.2, 0.0), 1.0);
}

TEST(SaeSlip, DenominatorIsTheLargerMagnitudeOnRandomInputs) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> speed(-30.0, 30.0), radius(0.1, 0.4), velocity(-5.0, 5.0);
  for (int i = 0; i < 5000; ++i) {
    const double w = speed(rng), r = radius(rng), v = velocity(rng);
    const double wheel = w * r;
    const double denominator = std::max(std::abs(wheel), std::abs(v));
    const double slip = SaeSlip(w, r, v);
    if (denominator < kSlipDeadbandMps) {
      EXPECT_EQ(slip, 0.0);
    } else {
      const double raw = (wheel - v) / denominator;
      EXPECT_NEAR(slip, std::clamp(raw, -1.0, 1.0), 1e-15) << w << " " << r << " " << v;
      if (wheel * v >= 0.0) {
        EXPECT_NEAR(slip, raw, 1e-15);  // same signs: |raw| <= 1 already
      }
    }
    EXPECT_GE(slip, -1.0);
    EXPECT_LE(slip, 1.0);
  }
}

TEST(SaeSlip, DeadbandBelowFiveCentimetresPerSecond) {
  EXPECT_EQ(kSlipDeadbandMps, 0.05);
  // Both speeds below 0.05 m/s: 0, even with a large relative difference.
  EXPECT_EQ(SaeSlip(0.049 / 0.2, 0.2, 0.0), 0.0);
  EXPECT_EQ(SaeSlip(0.0, 0.2, 0.049), 0.0);
  EXPECT_EQ(SaeSlip(-0.04 / 0.2, 0.2, 0.04), 0.0);
  EXPECT_EQ(SaeSlip(0.0, 0.2, -0.0499), 0.0);
  // Either speed above: the formula applies.
  EXPECT_DOUBLE_EQ(SaeSlip(0.0, 0.2, 0.06), -1.0);
  EXPECT_DOUBLE_EQ(SaeSlip(0.06 / 0.2, 0.2, 0.0), 1.0);
  EXPECT_NEAR(SaeSlip(0.051 / 0.2, 0.2, 0.04), (0.051 - 0.04) / 0.051, 1e-12);
  EXPECT_NEAR(SaeSlip(0.04 / 0.2, 0.2, -0.051), 1.0, 1e-12);  // opposite signs: 1.78, saturated
}

TEST(SaeSlip, OppositeSignsSaturate) {
  // Raw values would be +-2 and +-1.5: saturated to [-1, 1].
  EXPECT_DOUBLE_EQ(SaeSlip(5.0, 0.2, -1.0), 1.0);
  EXPECT_DOUBLE_EQ(SaeSlip(-5.0, 0.2, 1.0), -1.0);
  EXPECT_DOUBLE_EQ(SaeSlip(2.5, 0.2, -1.0), 1.0);
  EXPECT_DOUBLE_EQ(SaeSlip(-10.0, 0.2, 1.0), -1.0);
}

TEST(SaeSlip, RejectsInvalidInputs) {
  for (const double bad : {kNaN, kInf, -kInf}) {
    EXPECT_THROW(SaeSlip(bad, 0.2, 1.0), std::invalid_argument);
    EXPECT_THROW(SaeSlip(5.0, bad, 1.0), std::invalid_argument);
    EXPECT_THROW(SaeSlip(5.0, 0.2, bad), std::invalid_argument);
  }
  EXPECT_THROW(SaeSlip(5.0, 0.0, 1.0), std::invalid_argument);
  EXPECT_THROW(SaeSlip(5.0, -0.2, 1.0), std::invalid_argument);
  // Non-finite inputs are errors even inside the deadband.
  EXPECT_THROW(SaeSlip(kNaN, 0.2, 0.0), std::invalid_argument);
}

// A random state of the layout: base states, steering angles, R and k when slip-aware.
Eigen::VectorXd RandomState(const StateLayout& layout, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd x(layout.size);
  for (Eigen::Index i = 0; i < x.size(); ++i) x(i) = u(rng);
  x(L::kVx) = 2.0 * u(rng);
  for (std::size_t i = 0; i < layout.wheel_count(); ++i) {
    if (layout.rolling_radius[i] >= 0) x(layout.rolling_radius[i]) = 0.2 + 0.05 * u(rng);
    if (layout.slip_compliance[i] >= 0) x(layout.slip_compliance[i]) = 0.5 + 0.2 * u(rng);
  }
  return x;
}

TEST(EstimateWheelSlip, IsSaeSlipOfEveryWheelOnTheNominalRadius) {
  // wheel_slip_estimate.hpp: v_long from the state, R the vehicle file's nominal radius (not R_w).
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> speed(-15.0, 15.0);
  for (const mapio::VehicleConfig& vehicle : {mapio::AgrimaroSwerveConfig(), mapio::VineyardUgv4wsConfig(),
                                              mapio::DifferentialDriveConfig(), mapio::TrackedVehicleConfig()}) {
    for (bool slip_aware : {false, true}) {
      SCOPED_TRACE(vehicle.name + (slip_aware ? " slip-aware" : ""));
      const StateLayout layout = StateLayout::For(vehicle, slip_aware);
      for (int trial = 0; trial < 50; ++trial) {
        const Eigen::VectorXd x = RandomState(layout, rng);
        std::vector<double> omega(vehicle.wheels.size());
        for (double& w : omega) w = speed(rng);
        const std::vector<double> slip = EstimateWheelSlip(x, vehicle, layout, omega);
        ASSERT_EQ(slip.size(), vehicle.wheels.size());
        for (std::size_t i = 0; i < slip.size(); ++i) {
          const double v_long = WheelLongitudinalVelocity(x, vehicle, layout, i);
          EXPECT_EQ(slip[i], SaeSlip(omega[i], vehicle.wheels[i].nominal_radius_m, v_long)) << i;
        }
      }
    }
  }
}

TEST(EstimateWheelSlip, IgnoresTheEstimatedRollingRadiusUnlessAskedTo) {
  // At constant torque only R_w (1 - kappa mu) is observable, so R_w absorbs the slip: by default
  // the slip estimate does not use it (wheel_slip_estimate.hpp).
  const mapio::VehicleConfig vehicle = mapio::VineyardUgv4wsConfig();
  const StateLayout layout = StateLayout::For(vehicle, true);
  std::mt19937 rng(10);
  Eigen::VectorXd x = RandomState(layout, rng);
  const std::vector<double> omega = {4.0, 4.5, 5.0, 5.5};
  const std::vector<double> before = EstimateWheelSlip(x, vehicle, layout, omega);
  for (int index : layout.rolling_radius) x(index) *= 1.2;
  EXPECT_EQ(EstimateWheelSlip(x, vehicle, layout, omega), before);
  // with_rolling_radius: SAE slip on each wheel's R_w state.
  const std::vector<double> on_state = EstimateWheelSlip(x, vehicle, layout, omega, true);
  for (std::size_t i = 0; i < omega.size(); ++i) {
    EXPECT_DOUBLE_EQ(on_state[i], SaeSlip(omega[i], x(layout.rolling_radius[i]),
                                          WheelLongitudinalVelocity(x, vehicle, layout, i)));
    EXPECT_NE(on_state[i], before[i]);
  }
  // Without slip-aware states the flag changes nothing.
  const StateLayout plain = StateLayout::For(vehicle, false);
  const Eigen::VectorXd y = x.head(plain.size);
  EXPECT_EQ(EstimateWheelSlip(y, vehicle, plain, omega, true), EstimateWheelSlip(y, vehicle, plain, omega));
}

TEST(EstimateWheelSlip, ZeroWhenTheEncodersMatchTheState) {
  // The encoders reading exactly v_i / R_i (the no-slip wheel model, nominal radius): every slip is 0.
  std::mt19937 rng(9);
  for (bool slip_aware : {false, true}) {
    const mapio::VehicleConfig vehicle = mapio::VineyardUgv4wsConfig();
    const StateLayout layout = StateLayout::For(vehicle, slip_aware);
    for (int trial = 0; trial < 50; ++trial) {
      const Eigen::VectorXd x = RandomState(layout, rng);
      std::vector<double> omega;
      for (std::size_t i = 0; i < vehicle.wheels.size(); ++i) {
        omega.push_back(WheelLongitudinalVelocity(x, vehicle, layout, i) / vehicle.wheels[i].nominal_radius_m);
      }
      for (double s : EstimateWheelSlip(x, vehicle, layout, omega)) EXPECT_NEAR(s, 0.0, 1e-14);
    }
  }
}

TEST(EstimateWheelSlip, StraightDriveWithSpinningWheels) {
  // Differential drive at 1 m/s, wheels turning 10 % too fast: slip 1 - 1/1.1 on both.
  const mapio::VehicleConfig vehicle = mapio::DifferentialDriveConfig();
  const StateLayout layout = StateLayout::For(vehicle, false);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(layout.size);
  x(L::kVx) = 1.0;
  const double omega = 1.1 / vehicle.wheels[0].nominal_radius_m;
  for (double s : EstimateWheelSlip(x, vehicle, layout, {omega, omega})) EXPECT_NEAR(s, 1.0 - 1.0 / 1.1, 1e-12);
}

TEST(EstimateWheelSlip, RejectsAWrongSpeedCount) {
  const mapio::VehicleConfig vehicle = mapio::AgrimaroSwerveConfig();
  const StateLayout layout = StateLayout::For(vehicle, false);
  const Eigen::VectorXd x = Eigen::VectorXd::Zero(layout.size);
  EXPECT_THROW(EstimateWheelSlip(x, vehicle, layout, {1.0, 2.0}), std::invalid_argument);
  EXPECT_THROW(EstimateWheelSlip(x, vehicle, layout, {1.0, 2.0, 3.0, 4.0}), std::invalid_argument);
  EXPECT_THROW(EstimateWheelSlip(x, vehicle, layout, {}), std::invalid_argument);
  EXPECT_NO_THROW(EstimateWheelSlip(x, vehicle, layout, {1.0, 2.0, 3.0}));
  EXPECT_THROW(EstimateWheelSlip(x, vehicle, layout, {1.0, kNaN, 3.0}), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::localization
