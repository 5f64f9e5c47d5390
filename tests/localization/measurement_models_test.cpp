// Measurement models of the vehicle EKF (measurement_models.hpp): Jacobians against central
// differences for every shipped vehicle, and physical checks of each model.
#include "rowloc/localization/measurement_models.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace rowloc::localization {
namespace {

using L = StateLayout;
constexpr double kPi = std::numbers::pi;

std::vector<mapio::VehicleConfig> ShippedVehicles() {
  return {mapio::AgrimaroSwerveConfig(), mapio::VineyardUgv4wsConfig(), mapio::DifferentialDriveConfig(),
          mapio::TrackedVehicleConfig()};
}

Eigen::Vector2d Horizontal(const Eigen::Vector3d& p) { return p.head<2>(); }

Eigen::VectorXd RandomState(const StateLayout& layout, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd x(layout.size);
  for (Eigen::Index i = 0; i < x.size(); ++i) x(i) = u(rng);
  x(L::kX) = 50.0 * u(rng);
  x(L::kY) = 50.0 * u(rng);
  x(L::kPhi) = 3.0 * u(rng);
  x(L::kVx) = 3.0 * u(rng);
  x(L::kYawRate) = 1.5 * u(rng);
  for (std::size_t i = 0; i < layout.wheel_count(); ++i) {
    if (layout.steering[i] >= 0) x(layout.steering[i]) = 1.5 * u(rng);
    if (layout.rolling_radius[i] >= 0) x(layout.rolling_radius[i]) = 0.2 + 0.05 * u(rng);
    if (layout.slip_compliance[i] >= 0) x(layout.slip_compliance[i]) = 0.2 + 0.1 * u(rng);
  }
  return x;
}

using Model = std::function<LinearizedMeasurement(const Eigen::VectorXd&)>;

// Checks m(x).jacobian against central differences of m(x).predicted, all states.
void ExpectJacobianMatchesNumeric(const Model& model, const Eigen::VectorXd& x, const std::string& what) {
  const LinearizedMeasurement m = model(x);
  ASSERT_EQ(m.jacobian.rows(), m.predicted.size()) << what;
  ASSERT_EQ(m.jacobian.cols(), x.size()) << what;
  for (Eigen::Index j = 0; j < x.size(); ++j) {
    const double h = 1e-6 * std::max(1.0, std::abs(x(j)));
    Eigen::VectorXd plus = x, minus = x;
    plus(j) += h;
    minus(j) -= h;
    const Eigen::VectorXd numeric = (model(plus).predicted - model(minus).predicted) / (2.0 * h);
    for (Eigen::Index i = 0; i < numeric.size(); ++i) {
      EXPECT_NEAR(m.jacobian(i, j), numeric(i), 1e-6 * std::max(1.0, std::abs(numeric(i))))
          << what << ": dh" << i << "/dx" << j;
    }
  }
}

TEST(MeasurementModels, JacobiansMatchCentralDifferencesForEveryVehicle) {
  std::mt19937 rng(51);
  std::uniform_real_distribution<double> torque(-100.0, 100.0);
  for (const mapio::VehicleConfig& vehicle : ShippedVehicles()) {
    for (bool slip : {false, true}) {
      SCOPED_TRACE(vehicle.name + (slip ? " slip-aware" : ""));
      const StateLayout layout = StateLayout::For(vehicle, slip);
      std::vector<std::size_t> steerable;
      for (std::size_t i = 0; i < vehicle.wheels.size(); ++i) {
        if (vehicle.wheels[i].steerable) steerable.push_back(i);
      }
      for (int trial = 0; trial < 40; ++trial) {
        const Eigen::VectorXd x = RandomState(layout, rng);
        std::vector<double> torques(vehicle.wheels.size());
        for (double& t : torques) t = torque(rng);  // kappa |T| / (N r) <= 0.3 * 100 / 40 < 1
        const Eigen::Vector2d gnss = Horizontal(vehicle.gnss_antenna.position_m);
        const Eigen::Vector2d imu = Horizontal(vehicle.imu.position_m);
        const Eigen::Vector2d arm(0.3 * (trial % 5) - 0.6, 0.7 - 0.2 * (trial % 7));  // also non-shipped arms
        ExpectJacobianMatchesNumeric([&](const Eigen::VectorXd& s) { return GpsAntennaModel(s, gnss); }, x, "gps");
        ExpectJacobianMatchesNumeric([&](const Eigen::VectorXd& s) { return GpsAntennaModel(s, arm); }, x, "gps arm");
        ExpectJacobianMatchesNumeric([&](const Eigen::VectorXd& s) { return ImuModel(s, imu); }, x, "imu");
        ExpectJacobianMatchesNumeric([&](const Eigen::VectorXd& s) { return ImuModel(s, arm); }, x, "imu arm");
        {  // with the accelerometer-bias states appended (accel_bias)
          const StateLayout biased = StateLayout::For(vehicle, {.slip_aware_odometry = slip, .accel_bias = true});
          Eigen::VectorXd xb(biased.size);
          xb << x, 0.3, -0.2;
          ExpectJacobianMatchesNumeric([&](const Eigen::VectorXd& s) { return ImuModel(s, arm, biased.accel_bias); }, xb,
                                       "imu accel bias");
          const LinearizedMeasurement with = ImuModel(xb, arm, biased.accel_bias);
          const LinearizedMeasurement without = ImuModel(x, arm);
          EXPECT_NEAR(with.predicted(0) - without.predicted(0), 0.3, 1e-12);
          EXPECT_NEAR(with.predicted(1) - without.predicted(1), -0.2, 1e-12);
          EXPECT_EQ(with.predicted(2), without.predicted(2));
        }
        {  // with the GNSS-bias states appended (gnss_bias)
          const StateLayout biased = StateLayout::For(vehicle, {.slip_aware_odometry = slip, .gnss_bias = true});
          ASSERT_EQ(biased.gnss_bias, layout.size);
          Eigen::VectorXd xb(biased.size);
          xb << x, 0.7, -1.1;
          ExpectJacobianMatchesNumeric([&](const Eigen::VectorXd& s) { return GpsAntennaModel(s, arm, biased.gnss_bias); },
                                       xb, "gps bias");
          const LinearizedMeasurement with = GpsAntennaModel(xb, arm, biased.gnss_bias);
          const LinearizedMeasurement without = GpsAntennaModel(x, arm);
          EXPECT_NEAR(with.predicted(0) - without.predicted(0), 0.7, 1e-12);
          EXPECT_NEAR(with.predicted(1) - without.predicted(1), -1.1, 1e-12);
        }
        ExpectJacobianMatchesNumeric([&](const Eigen::VectorXd& s) { return VioModel(s, arm); }, x, "vio");
        ExpectJacobianMatchesNumeric(
            [&](const Eigen::VectorXd& s) { return WheelSpeedModel(s, vehicle, layout, std::nullopt); }, x, "wheels");
        ExpectJacobianMatchesNumeric(
            [&](const Eigen::VectorXd& s) { return WheelSpeedModel(s, vehicle, layout, torques); }, x,
            "wheels with torque");
        ExpectJacobianMatchesNumeric(
            [&](const Eigen::VectorXd& s) { return WheelSpeedModel(s, vehicle, layout, torques, 0.05); }, x,
            "wheels with torque and encoder lag");
        ExpectJacobianMatchesNumeric(
            [&](const Eigen::VectorXd& s) { return WheelSpeedModel(s, vehicle, layout, std::nullopt, 0.0, true); }, x,
            "wheels with the traction from the acceleration");
        ExpectJacobianMatchesNumeric(
            [&](const Eigen::VectorXd& s) { return WheelSpeedModel(s, vehicle, layout, std::nullopt, 0.05, true); }, x,
            "wheels with the traction from the acceleration and encoder lag");
        ExpectJacobianMatchesNumeric(
            [&](const Eigen::VectorXd& s) { return WheelLateralVelocityModel(s, vehicle, layout); }, x, "lateral");
        if (!steerable.empty()) {
          ExpectJacobianMatchesNumeric([&](const Eigen::VectorXd& s) { return SteeringModel(s, layout, steerable); },
                                       x, "steering");
        }
      }
    }
  }
}

// With traction states (torque noise: the torques measure mu), the wheel model takes mu from the
// state when a message has torques: its column is d h / d mu = v kappa / (R (1 - kappa mu)^2);
// without torques the acceleration's mu, as before.
TEST(MeasurementModels, WheelJacobianWithTractionStatesMatchesCentralDifferences) {
  std::mt19937 rng(52);
  std::uniform_real_distribution<double> mu(-0.3, 0.3);
  for (const mapio::VehicleConfig& vehicle : ShippedVehicles()) {
    SCOPED_TRACE(vehicle.name);
    const StateLayout layout =
        StateLayout::For(vehicle, {.slip_aware_odometry = true, .accel_bias = true, .traction = true});
    ASSERT_TRUE(layout.has_traction());
    for (int trial = 0; trial < 20; ++trial) {
      Eigen::VectorXd x = Eigen::VectorXd::Zero(layout.size);
      x.head(StateLayout::For(vehicle, true).size) = RandomState(StateLayout::For(vehicle, true), rng);
      for (const int k : layout.traction) x(k) = mu(rng);
      std::vector<double> torques(vehicle.wheels.size(), 1e6);  // ignored for mu: the states are used
      ExpectJacobianMatchesNumeric(
          [&](const Eigen::VectorXd& s) { return WheelSpeedModel(s, vehicle, layout, torques); }, x,
          "wheels with traction states");
      ExpectJacobianMatchesNumeric(
          [&](const Eigen::VectorXd& s) { return WheelSpeedModel(s, vehicle, layout, std::nullopt, 0.0, true); }, x,
          "no torques: the acceleration's mu");
      const LinearizedMeasurement m = WheelSpeedModel(x, vehicle, layout, torques);
      for (std::size_t i = 0; i < vehicle.wheels.size(); ++i) {
        EXPECT_NE(m.jacobian(static_cast<Eigen::Index>(i), layout.traction[i]), 0.0);
        EXPECT_EQ(WheelTractionCoefficient(x, vehicle, layout, i, torques, false), x(layout.traction[i]));
        EXPECT_EQ(WheelTractionCoefficient(x, vehicle, layout, i, std::nullopt, false), 0.0);
      }
      const LinearizedMeasurement without = WheelSpeedModel(x, vehicle, layout, std::nullopt, 0.0, false);
      for (std::size_t i = 0; i < vehicle.wheels.size(); ++i) {
        EXPECT_EQ(without.jacobian(static_cast<Eigen::Index>(i), layout.traction[i]), 0.0);
      }
    }
  }
}

TEST(MeasurementModels, SelectedStatesAreMeasuredDirectly) {
  Eigen::VectorXd x(6);
  x << 0.5, -1.0, 2.0, 3.5, -4.0, 7.0;
  LinearizedMeasurement m;
  SelectedStatesModel(x, {4, 1, 5}, m);
  EXPECT_EQ(m.predicted, Eigen::Vector3d(-4.0, -1.0, 7.0));
  Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(3, 6);
  expected(0, 4) = expected(1, 1) = expected(2, 5) = 1.0;
  EXPECT_EQ(m.jacobian, expected);
  EXPECT_THROW(SelectedStatesModel(x, {1, 6}, m), std::invalid_argument);
  EXPECT_THROW(SelectedStatesModel(x, {-1}, m), std::invalid_argument);
}

TEST(MeasurementModels, JacobianColumnsOfUnrelatedStatesAreZero) {
  // The wheel model of the swerve robot: wheel i depends on its own delta, R and k only.
  const mapio::VehicleConfig vehicle = mapio::AgrimaroSwerveConfig();
  const StateLayout layout = StateLayout::For(vehicle, true);
  std::mt19937 rng(52);
  const Eigen::VectorXd x = RandomState(layout, rng);
  const LinearizedMeasurement m = WheelSpeedModel(x, vehicle, layout, std::vector<double>{10.0, -20.0, 30.0});
  for (std::size_t i = 0; i < 3; ++i) {
    for (std::size_t other = 0; other < 3; ++other) {
      if (other == i) continue;
      const auto row = static_cast<Eigen::Index>(i);
      EXPECT_EQ(m.jacobian(row, layout.steering[other]), 0.0);
      EXPECT_EQ(m.jacobian(row, layout.rolling_radius[other]), 0.0);
      EXPECT_EQ(m.jacobian(row, layout.slip_compliance[other]), 0.0);
    }
    for (int base : {L::kX, L::kY, L::kPhi, L::kAx, L::kAy, L::kGyroBias}) {
      EXPECT_EQ(m.jacobian(static_cast<Eigen::Index>(i), base), 0.0);
    }
  }
}

// The out-parameter forms give the value forms' numbers bit for bit, whatever `out` held before
// (one buffer reused across models of different sizes, entries left from a previous model).
TEST(MeasurementModels, OutParameterFormsOverwriteAReusedBuffer) {
  std::mt19937 rng(5);
  const auto same = [](const LinearizedMeasurement& a, const LinearizedMeasurement& b) {
    return a.predicted.size() == b.predicted.size() && a.jacobian.rows() == b.jacobian.rows() &&
           a.jacobian.cols() == b.jacobian.cols() && (a.predicted.array() == b.predicted.array()).all() &&
           (a.jacobian.array() == b.jacobian.array()).all();
  };
  for (const mapio::VehicleConfig& v : ShippedVehicles()) {
    const StateLayout layout = StateLayout::For(v, {.slip_aware_odometry = true, .accel_bias = true});
    const Eigen::VectorXd x = RandomState(layout, rng);
    const std::optional<std::vector<double>> torque = std::vector<double>(v.wheels.size(), 30.0);
    std::vector<std::size_t> steered;
    for (std::size_t i = 0; i < v.wheels.size(); ++i) {
      if (layout.steering[i] >= 0) steered.push_back(i);
    }
    LinearizedMeasurement out;
    out.predicted = Eigen::VectorXd::Constant(7, 9.0);  // stale content of another size
    out.jacobian = Eigen::MatrixXd::Constant(7, x.size(), 9.0);
    WheelSpeedModel(x, v, layout, torque, 0.02, false, out);
    EXPECT_TRUE(same(out, WheelSpeedModel(x, v, layout, torque, 0.02))) << v.name;
    WheelLateralVelocityModel(x, v, layout, out);
    EXPECT_TRUE(same(out, WheelLateralVelocityModel(x, v, layout))) << v.name;
    GpsAntennaModel(x, Eigen::Vector2d(0.3, -0.2), -1, out);
    EXPECT_TRUE(same(out, GpsAntennaModel(x, Eigen::Vector2d(0.3, -0.2)))) << v.name;
    GpsAntennaModel(x, Eigen::Vector2d(0.3, -0.2), layout.accel_bias, out);  // any pair of states as the bias
    EXPECT_TRUE(same(out, GpsAntennaModel(x, Eigen::Vector2d(0.3, -0.2), layout.accel_bias))) << v.name;
    ImuModel(x, Eigen::Vector2d(0.1, 0.05), layout.accel_bias, out);
    EXPECT_TRUE(same(out, ImuModel(x, Eigen::Vector2d(0.1, 0.05), layout.accel_bias))) << v.name;
    VioModel(x, Eigen::Vector2d(0.4, 0.0), out);
    EXPECT_TRUE(same(out, VioModel(x, Eigen::Vector2d(0.4, 0.0)))) << v.name;
    if (!steered.empty()) {
      SteeringModel(x, layout, steered, out);
      EXPECT_TRUE(same(out, SteeringModel(x, layout, steered))) << v.name;
    }
  }
}

TEST(WheelSpeedModel, AnEncoderWithALowPassReportsTheSpeedTauEarlier) {
  // Straight braking at 1 m/s^2 through 0.5 m/s: an encoder with a 0.02 s low-pass reads the speed
  // of 0.02 s before, 0.52 m/s; at constant speed the lag changes nothing.
  const mapio::VehicleConfig vehicle = mapio::VineyardUgv4wsConfig();
  const StateLayout layout = StateLayout::For(vehicle, false);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(layout.size);
  x(L::kVx) = 0.5;
  x(L::kAx) = -1.0;
  const double radius = vehicle.wheels[0].nominal_radius_m;
  const LinearizedMeasurement lagged = WheelSpeedModel(x, vehicle, layout, std::nullopt, 0.02);
  const LinearizedMeasurement instant = WheelSpeedModel(x, vehicle, layout, std::nullopt, 0.0);
  for (Eigen::Index i = 0; i < lagged.predicted.size(); ++i) {
    EXPECT_NEAR(lagged.predicted(i) * radius, 0.52, 1e-12);
    EXPECT_NEAR(instant.predicted(i) * radius, 0.50, 1e-12);
    EXPECT_NEAR(lagged.jacobian(i, L::kAx) * radius, -0.02, 1e-12);
    EXPECT_EQ(instant.jacobian(i, L::kAx), 0.0);
  }
  x(L::kAx) = 0.0;
  EXPECT_EQ(WheelSpeedModel(x, vehicle, layout, std::nullopt, 0.02).predicted,
            WheelSpeedModel(x, vehicle, layout, std::nullopt, 0.0).predicted);
  EXPECT_THROW(WheelSpeedModel(x, vehicle, layout, std::nullopt, -0.01), std::invalid_argument);
  EXPECT_THROW(WheelSpeedModel(x, vehicle, layout, std::nullopt, std::nan("")), std::invalid_argument);
}

TEST(WheelSpeedModel, StraightDriveGivesEqualWheelSpeeds) {
  for (const mapio::VehicleConfig& vehicle : ShippedVehicles()) {
    SCOPED_TRACE(vehicle.name);
    const StateLayout layout = StateLayout::For(vehicle, false);
    Eigen::VectorXd x = Eigen::VectorXd::Zero(layout.size);
    x(L::kPhi) = 0.7;  // heading and position do not matter
    x(L::kX) = 12.0;
    x(L::kVx) = 1.3;   // every delta = 0
    const LinearizedMeasurement m = WheelSpeedModel(x, vehicle, layout, std::nullopt);
    ASSERT_EQ(m.predicted.size(), static_cast<Eigen::Index>(vehicle.wheels.size()));
    for (std::size_t i = 0; i < vehicle.wheels.size(); ++i) {
      EXPECT_NEAR(m.predicted(static_cast<Eigen::Index>(i)), 1.3 / vehicle.wheels[i].nominal_radius_m, 1e-14);
    }
  }
}

TEST(WheelSpeedModel, SwerveWheelsAlignedWithTheirVelocityRollAtItsMagnitude) {
  std::mt19937 rng(53);
  for (const mapio::VehicleConfig& vehicle : {mapio::AgrimaroSwerveConfig(), mapio::VineyardUgv4wsConfig()}) {
    const StateLayout layout = StateLayout::For(vehicle, false);
    for (int trial = 0; trial < 20; ++trial) {
      Eigen::VectorXd x = RandomState(layout, rng);
      std::vector<double> expected;
      for (std::size_t i = 0; i < vehicle.wheels.size(); ++i) {
        const Eigen::Vector2d l = vehicle.wheels[i].position_m;
        const Eigen::Vector2d v(x(L::kVx) - x(L::kYawRate) * l.y(), x(L::kVy) + x(L::kYawRate) * l.x());
        x(layout.steering[i]) = std::atan2(v.y(), v.x());  // wheel heading along the centre velocity
        expected.push_back(v.norm() / vehicle.wheels[i].nominal_radius_m);
        // Turned by 90 degrees, the wheel would not roll at all.
        Eigen::VectorXd across = x;
        across(layout.steering[i]) += kPi / 2;
        EXPECT_NEAR(WheelLongitudinalVelocity(across, vehicle, layout, i), 0.0, 1e-12);
      }
      const LinearizedMeasurement m = WheelSpeedModel(x, vehicle, layout, std::nullopt);
      for (std::size_t i = 0; i < expected.size(); ++i) {
        EXPECT_NEAR(m.predicted(static_cast<Eigen::Index>(i)), expected[i], 1e-12) << vehicle.name << " " << i;
      }
    }
  }
}

TEST(WheelLateralVelocityModel, WheelCentreVelocityAcrossTheWheel) {
  std::mt19937 rng(56);
  for (const mapio::VehicleConfig& vehicle : ShippedVehicles()) {
    SCOPED_TRACE(vehicle.name);
    const StateLayout layout = StateLayout::For(vehicle, false);
    // Straight ahead with every delta = 0: no sideways velocity at any wheel.
    Eigen::VectorXd straight = Eigen::VectorXd::Zero(layout.size);
    straight(L::kVx) = 1.7;
    EXPECT_EQ(WheelLateralVelocityModel(straight, vehicle, layout).predicted.cwiseAbs().maxCoeff(), 0.0);
    // Random twist: along^2 + across^2 = |wheel-centre velocity|^2, and across = v . (-sin, cos).
    for (int trial = 0; trial < 20; ++trial) {
      const Eigen::VectorXd x = RandomState(layout, rng);
      const LinearizedMeasurement m = WheelLateralVelocityModel(x, vehicle, layout);
      ASSERT_EQ(m.predicted.size(), static_cast<Eigen::Index>(vehicle.wheels.size()));
      for (std::size_t i = 0; i < vehicle.wheels.size(); ++i) {
        const Eigen::Vector2d l = vehicle.wheels[i].position_m;
        const Eigen::Vector2d v(x(L::kVx) - x(L::kYawRate) * l.y(), x(L::kVy) + x(L::kYawRate) * l.x());
        const double delta = layout.steering[i] >= 0 ? x(layout.steering[i]) : 0.0;
        const double across = m.predicted(static_cast<Eigen::Index>(i));
        EXPECT_NEAR(across, -std::sin(delta) * v.x() + std::cos(delta) * v.y(), 1e-14);
        const double along = WheelLongitudinalVelocity(x, vehicle, layout, i);
        EXPECT_NEAR(along * along + across * across, v.squaredNorm(), 1e-12);
      }
    }
  }
  // Differential drive sliding sideways at 0.2 m/s: both wheels see it.
  const mapio::VehicleConfig diff = mapio::DifferentialDriveConfig();
  const StateLayout layout = StateLayout::For(diff, false);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(layout.size);
  x(L::kVy) = 0.2;
  EXPECT_NEAR((WheelLateralVelocityModel(x, diff, layout).predicted - Eigen::Vector2d(0.2, 0.2)).norm(), 0.0, 1e-15);
}

TEST(WheelSpeedModel, DifferentialDriveTurningOnTheSpot) {
  const mapio::VehicleConfig vehicle = mapio::DifferentialDriveConfig();  // wheels at y = +-0.28 m
  const StateLayout layout = StateLayout::For(vehicle, false);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(layout.size);
  x(L::kYawRate) = 0.5;  // counter-clockwise: left wheel backwards, right wheel forwards
  const LinearizedMeasurement m = WheelSpeedModel(x, vehicle, layout, std::nullopt);
  EXPECT_NEAR(m.predicted(0), -0.5 * 0.28 / 0.165, 1e-14);
  EXPECT_NEAR(m.predicted(1), 0.5 * 0.28 / 0.165, 1e-14);
}

TEST(WheelSpeedModel, SlipAwareOdometerFollowsSeed004) {
  std::mt19937 rng(54);
  for (const mapio::VehicleConfig& vehicle : ShippedVehicles()) {
    const StateLayout layout = StateLayout::For(vehicle, true);
    for (int trial = 0; trial < 20; ++trial) {
      const Eigen::VectorXd x = RandomState(layout, rng);
      // Traction coefficients mu = T / (N r) from -0.4 (braking) up to 1.1; kappa mu stays below 0.4.
      std::vector<double> torques;
      for (std::size_t i = 0; i < vehicle.wheels.size(); ++i) {
        torques.push_back((0.5 * static_cast<double>(i) - 0.4) * WheelTractionScaleNm(vehicle, i));
      }
      const LinearizedMeasurement with = WheelSpeedModel(x, vehicle, layout, torques);
      const LinearizedMeasurement without = WheelSpeedModel(x, vehicle, layout, std::nullopt);
      for (std::size_t i = 0; i < vehicle.wheels.size(); ++i) {
        const auto row = static_cast<Eigen::Index>(i);
        const double v = WheelLongitudinalVelocity(x, vehicle, layout, i);
        // The form of Lindgren et al. 2002 with its torque/slip gradient k_s = N r / kappa (N = m g / wheel count).
        const double load_n = vehicle.mass_kg * 9.80665 / static_cast<double>(vehicle.wheels.size());
        const double k = load_n * vehicle.wheels[i].nominal_radius_m / x(layout.slip_compliance[i]);
        const double radius = x(layout.rolling_radius[i]);
        EXPECT_EQ(WheelRollingRadius(x, vehicle, layout, i), radius);
        EXPECT_NEAR(with.predicted(row), v * k / (radius * (k - torques[i])), 1e-12 * std::abs(v / radius) + 1e-15);
        EXPECT_NEAR(without.predicted(row), v / radius, 1e-12 * std::abs(v / radius) + 1e-15);  // T = 0
        // Driving torque (T > 0): the odometer reads more than the true speed (the wheel slips).
        if (torques[i] > 0 && v > 0) {
          EXPECT_GT(with.predicted(row), without.predicted(row));
        }
      }
    }
  }
}

// The turning term of a skid steer, written out here apart from the implementation:
// -sign(l_y) mu_t l / (2 B) times the turn's direction, 0 below r_0 / 2, full from r_0 = 2 v_0 / B.
double ExpectedTurningTraction(const mapio::VehicleConfig& v, std::size_t i, double r) {
  if (v.kind != mapio::VehicleKind::kSkidSteer) return 0.0;
  const double gauge = std::abs(v.wheels[0].position_m.y() - v.wheels[1].position_m.y());
  const double full = 2.0 * 0.05 / gauge, start = 0.5 * full;
  const double turn = std::copysign(std::clamp((std::abs(r) - start) / (full - start), 0.0, 1.0), r);
  return -std::copysign(1.0, v.wheels[i].position_m.y()) * v.tracks->turning_resistance_coefficient *
         v.tracks->contact_length_m / (2.0 * gauge) * turn;
}

// Without torques, traction_from_acceleration takes mu = (cos(delta) a_x + sin(delta) a_y) / g
// (plus a skid steer's turning term): braking (mu < 0) lowers the predicted encoder speed,
// speeding up raises it; torques, when given, win, and a filter without slip states ignores the
// switch.
TEST(WheelSpeedModel, TractionFromTheAccelerationWithoutTorque) {
  std::mt19937 rng(77);
  for (const mapio::VehicleConfig& vehicle : ShippedVehicles()) {
    const StateLayout layout = StateLayout::For(vehicle, true);
    for (int trial = 0; trial < 20; ++trial) {
      const Eigen::VectorXd x = RandomState(layout, rng);
      const std::vector<double> torques(vehicle.wheels.size(), 5.0);
      const LinearizedMeasurement from_acceleration = WheelSpeedModel(x, vehicle, layout, std::nullopt, 0.0, true);
      const LinearizedMeasurement zero = WheelSpeedModel(x, vehicle, layout, std::nullopt, 0.0, false);
      EXPECT_EQ(WheelSpeedModel(x, vehicle, layout, torques, 0.0, true).predicted,
                WheelSpeedModel(x, vehicle, layout, torques, 0.0, false).predicted);
      for (std::size_t i = 0; i < vehicle.wheels.size(); ++i) {
        const auto row = static_cast<Eigen::Index>(i);
        const double delta = layout.steering[i] >= 0 ? x(layout.steering[i]) : 0.0;
        const double mu = (std::cos(delta) * x(L::kAx) + std::sin(delta) * x(L::kAy)) / 9.80665 +
                          ExpectedTurningTraction(vehicle, i, x(L::kYawRate));
        EXPECT_NEAR(WheelTractionCoefficient(x, vehicle, layout, i, std::nullopt, true), mu, 1e-15);
        EXPECT_EQ(WheelTractionCoefficient(x, vehicle, layout, i, std::nullopt, false), 0.0);
        EXPECT_EQ(WheelTractionCoefficient(x, vehicle, layout, i, torques, true), 5.0 / WheelTractionScaleNm(vehicle, i));
        const double kappa = x(layout.slip_compliance[i]);
        EXPECT_NEAR(from_acceleration.predicted(row), zero.predicted(row) / (1.0 - kappa * mu),
                    1e-12 * std::abs(zero.predicted(row)) + 1e-15);
        if (std::abs(zero.predicted(row)) > 1e-3 && std::abs(mu) > 1e-3) {  // |omega| grows with mu
          EXPECT_EQ(std::abs(from_acceleration.predicted(row)) > std::abs(zero.predicted(row)), mu > 0.0);
        }
      }
    }
    const Eigen::VectorXd any = RandomState(layout, rng);
    const std::size_t n = vehicle.wheels.size();
    EXPECT_THROW(WheelTractionCoefficient(any, vehicle, layout, n, std::nullopt, true), std::invalid_argument);
    EXPECT_THROW(WheelTractionCoefficient(any, vehicle, layout, 0, std::vector<double>(n + 1, 1.0), true),
                 std::invalid_argument);
    const StateLayout plain = StateLayout::For(vehicle, false);
    const Eigen::VectorXd x = RandomState(plain, rng);
    EXPECT_EQ(WheelSpeedModel(x, vehicle, plain, std::nullopt, 0.0, true).predicted,
              WheelSpeedModel(x, vehicle, plain, std::nullopt, 0.0, false).predicted);
  }
}

// Wong §7.2: in a turn the outer track pushes forward and the inner one holds back, by
// mu_t l / (2 B) of a track's load (tracked: 0.3 x 1.0 / 2.2); nothing on a straight drive (the
// dead zone below r_0 / 2), a ramp between, and nothing for wheeled vehicles or mu_t = 0.
TEST(TurningResistanceTraction, OuterTrackPushesInnerHoldsBackOnlyInATurn) {
  const mapio::VehicleConfig tracked = mapio::TrackedVehicleConfig();  // left track at +y
  const double full = 0.3 * 1.0 / 2.2, r0 = 2.0 * 0.05 / 1.1;
  EXPECT_NEAR(TurningResistanceTraction(tracked, 1, 0.16).value, full, 1e-15);   // left turn: right is outer
  EXPECT_NEAR(TurningResistanceTraction(tracked, 0, 0.16).value, -full, 1e-15);
  EXPECT_NEAR(TurningResistanceTraction(tracked, 0, -0.16).value, full, 1e-15);  // right turn
  EXPECT_EQ(TurningResistanceTraction(tracked, 0, 0.16).d_yaw_rate, 0.0);
  for (const double r : {0.0, 0.01, -0.02, 0.49 * r0}) {
    EXPECT_EQ(TurningResistanceTraction(tracked, 0, r).value, 0.0) << r;
    EXPECT_EQ(TurningResistanceTraction(tracked, 0, r).d_yaw_rate, 0.0) << r;
  }
  // The ramp: continuous at both ends, its derivative the central difference.
  EXPECT_NEAR(TurningResistanceTraction(tracked, 1, 0.5 * r0 + 1e-9).value, 0.0, 1e-6);
  EXPECT_NEAR(TurningResistanceTraction(tracked, 1, r0 - 1e-9).value, full, 1e-6);
  for (const double r : {0.6 * r0, -0.75 * r0, 0.9 * r0}) {
    const double h = 1e-7;
    const double numeric = (TurningResistanceTraction(tracked, 1, r + h).value -
                            TurningResistanceTraction(tracked, 1, r - h).value) / (2.0 * h);
    EXPECT_NEAR(TurningResistanceTraction(tracked, 1, r).d_yaw_rate, numeric, 1e-6) << r;
    EXPECT_NEAR(TurningResistanceTraction(tracked, 1, r).value, ExpectedTurningTraction(tracked, 1, r), 1e-15);
  }
  mapio::VehicleConfig smooth = tracked;
  smooth.tracks->turning_resistance_coefficient = 0.0;  // the vehicle file's off switch
  EXPECT_EQ(TurningResistanceTraction(smooth, 1, 0.16).value, 0.0);
  for (const mapio::VehicleConfig& wheeled :
       {mapio::AgrimaroSwerveConfig(), mapio::VineyardUgv4wsConfig(), mapio::DifferentialDriveConfig()}) {
    EXPECT_EQ(TurningResistanceTraction(wheeled, 0, 0.16).value, 0.0) << wheeled.name;
  }
  // In the odometer model: in a left turn the right (outer) track turns faster than without the
  // term, the left one slower, for the same body motion and kappa > 0.
  const StateLayout layout = StateLayout::For(tracked, true);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(layout.size);
  x(L::kVx) = 0.8;
  x(L::kYawRate) = 0.16;
  for (std::size_t i = 0; i < 2; ++i) {
    x(layout.rolling_radius[i]) = 0.13;
    x(layout.slip_compliance[i]) = 1.5;
  }
  const Eigen::VectorXd with = WheelSpeedModel(x, tracked, layout, std::nullopt, 0.0, true).predicted;
  const Eigen::VectorXd without = WheelSpeedModel(x, smooth, layout, std::nullopt, 0.0, true).predicted;
  EXPECT_GT(with(1), without(1) * 1.15);
  EXPECT_LT(with(0), without(0) / 1.15);
}

TEST(WheelSpeedModel, RejectsAWrongTorqueCount) {
  for (const mapio::VehicleConfig& vehicle : ShippedVehicles()) {
    for (bool slip : {false, true}) {
      const StateLayout layout = StateLayout::For(vehicle, slip);
      const Eigen::VectorXd x = Eigen::VectorXd::Constant(layout.size, 0.5);
      const std::vector<double> short_list(vehicle.wheels.size() - 1, 1.0), long_list(vehicle.wheels.size() + 1, 1.0);
      EXPECT_THROW(WheelSpeedModel(x, vehicle, layout, short_list), std::invalid_argument) << vehicle.name;
      EXPECT_THROW(WheelSpeedModel(x, vehicle, layout, long_list), std::invalid_argument) << vehicle.name;
      EXPECT_THROW(WheelSpeedModel(x, vehicle, layout, std::vector<double>{}), std::invalid_argument);
      EXPECT_NO_THROW(WheelSpeedModel(x, vehicle, layout, std::vector<double>(vehicle.wheels.size(), 1.0)));
    }
  }
}

TEST(SteeringModel, ObservesTheSteeringStatesAndRejectsFixedWheels) {
  const mapio::VehicleConfig swerve = mapio::AgrimaroSwerveConfig();
  const StateLayout layout = StateLayout::For(swerve, true);
  std::mt19937 rng(55);
  const Eigen::VectorXd x = RandomState(layout, rng);
  const LinearizedMeasurement m = SteeringModel(x, layout, {2, 0});
  ASSERT_EQ(m.predicted.size(), 2);
  EXPECT_EQ(m.predicted(0), x(layout.steering[2]));
  EXPECT_EQ(m.predicted(1), x(layout.steering[0]));
  EXPECT_EQ(m.jacobian.row(0).sum(), 1.0);
  EXPECT_EQ(m.jacobian(0, layout.steering[2]), 1.0);

  for (const mapio::VehicleConfig& fixed : {mapio::DifferentialDriveConfig(), mapio::TrackedVehicleConfig()}) {
    const StateLayout fixed_layout = StateLayout::For(fixed, false);
    const Eigen::VectorXd y = Eigen::VectorXd::Zero(fixed_layout.size);
    EXPECT_THROW(SteeringModel(y, fixed_layout, {0}), std::invalid_argument) << fixed.name;
    EXPECT_THROW(SteeringModel(y, fixed_layout, {1}), std::invalid_argument) << fixed.name;
  }
  EXPECT_ANY_THROW(SteeringModel(x, layout, {3}));  // no such wheel
}

TEST(GpsAntennaModel, LeverArmRotatesWithTheHeading) {
  const Eigen::Vector2d l = Horizontal(mapio::AgrimaroSwerveConfig().gnss_antenna.position_m);  // (0, -0.4)
  ASSERT_GT(l.norm(), 0.0);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(L::kBaseSize);
  x(L::kX) = 5.0;
  x(L::kY) = -3.0;
  for (int k = -8; k <= 8; ++k) {
    x(L::kPhi) = k * kPi / 8;
    const LinearizedMeasurement m = GpsAntennaModel(x, l);
    const Eigen::Vector2d offset = m.predicted - Eigen::Vector2d(5.0, -3.0);
    EXPECT_NEAR(offset.norm(), l.norm(), 1e-14);
    // The offset is l turned by the heading: same length, direction atan2(l) + phi.
    const double direction = std::atan2(l.y(), l.x()) + x(L::kPhi);
    EXPECT_NEAR((offset - l.norm() * Eigen::Vector2d(std::cos(direction), std::sin(direction))).norm(), 0.0, 1e-14)
        << k;
  }
  x(L::kPhi) = 0.0;  // heading east: the antenna 0.4 m right of the vehicle is 0.4 m south
  EXPECT_NEAR((GpsAntennaModel(x, l).predicted - Eigen::Vector2d(5.0, -3.4)).norm(), 0.0, 1e-15);
  x(L::kPhi) = kPi / 2;  // heading north: it is 0.4 m east
  EXPECT_NEAR((GpsAntennaModel(x, l).predicted - Eigen::Vector2d(5.4, -3.0)).norm(), 0.0, 1e-15);
  // Without a lever arm the antenna is the reference point whatever the heading.
  EXPECT_EQ(GpsAntennaModel(x, Eigen::Vector2d::Zero()).predicted, Eigen::Vector2d(5.0, -3.0));
}

TEST(ImuModel, CentripetalTermAndGyroBias) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(L::kBaseSize);
  x(L::kAx) = 0.2;
  x(L::kAy) = 0.6;
  x(L::kYawRate) = 0.5;
  x(L::kGyroBias) = 0.01;
  const LinearizedMeasurement at_reference = ImuModel(x, Eigen::Vector2d::Zero());
  EXPECT_NEAR((at_reference.predicted - Eigen::Vector3d(0.2, 0.6, 0.51)).norm(), 0.0, 1e-15);
  // 1 m ahead of the reference point the IMU feels r^2 l towards the centre of rotation.
  const LinearizedMeasurement ahead = ImuModel(x, Eigen::Vector2d(1.0, -0.5));
  EXPECT_NEAR((ahead.predicted - Eigen::Vector3d(0.2 - 0.25, 0.6 + 0.125, 0.51)).norm(), 0.0, 1e-15);
}

TEST(VioModel, VelocityOfTheCameraPoint) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(L::kBaseSize);
  x(L::kVx) = 1.0;
  x(L::kVy) = 0.1;
  x(L::kYawRate) = 0.4;
  // Camera at (0.5, 0.25): v + r x l = (1 - 0.4 * 0.25, 0.1 + 0.4 * 0.5).
  const LinearizedMeasurement m = VioModel(x, Eigen::Vector2d(0.5, 0.25));
  EXPECT_NEAR((m.predicted - Eigen::Vector2d(0.9, 0.3)).norm(), 0.0, 1e-15);
}

}  // namespace
}  // namespace rowloc::localization
