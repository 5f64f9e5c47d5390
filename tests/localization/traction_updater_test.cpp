// TractionUpdater (traction_updater.hpp) on its own: the torques kept in vehicle order, the
// measurement mu = T / (N r) of the traction states with its noise and gate, the states' prior at
// initialisation, and the refusals.
#include "rowloc/localization/traction_updater.hpp"

#include "rowloc/localization/kalman_update.hpp"
#include "rowloc/mapio/vehicle_config.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

namespace rowloc::localization {
namespace {

FilterConfig TractionConfig() {
  FilterConfig config;
  config.slip_aware_odometry.torque_sigma_nm = 0.05;
  return config;
}

/// N r of wheel i: its share of the weight times its nominal radius, N m.
double ScaleNm(const mapio::VehicleConfig& v, std::size_t i) {
  return v.mass_kg * 9.80665 / static_cast<double>(v.wheels.size()) * v.wheels[i].nominal_radius_m;
}

struct Swerve {
  mapio::VehicleConfig v = mapio::AgrimaroSwerveConfig();  // wheels left_front, left_rear, right
  StateLayout layout = StateLayout::For(v, {.slip_aware_odometry = true, .traction = true});
  TractionUpdater traction{v, TractionConfig(), layout};
  /// A message listing the wheels as right, left_front, left_rear.
  const std::vector<std::size_t> permuted{2, 0, 1};
  formats::WheelsMessage Wheels(std::optional<std::vector<double>> torque_nm) const {
    return {1.0, {0.0, 0.0, 0.0}, std::move(torque_nm), std::nullopt};
  }
};

TEST(TractionUpdater, TheTorquesAreKeptInVehicleOrderUntilAMessageWithoutThem) {
  Swerve s;
  EXPECT_FALSE(s.traction.last_torque_nm().has_value());
  s.traction.ObserveTorques(s.Wheels(std::vector<double>{3.0, 1.0, 2.0}), s.permuted);
  ASSERT_TRUE(s.traction.last_torque_nm().has_value());
  EXPECT_EQ(*s.traction.last_torque_nm(), (std::vector<double>{1.0, 2.0, 3.0}));
  s.traction.ObserveTorques(s.Wheels(std::nullopt), s.permuted);
  EXPECT_FALSE(s.traction.last_torque_nm().has_value());
}

TEST(TractionUpdater, TheTorquesMeasureTheTractionCoefficients) {
  Swerve s;
  s.traction.ObserveTorques(s.Wheels(std::vector<double>{30.0, 10.0, 20.0}), s.permuted);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(s.layout.size);
  for (std::size_t i = 0; i < 3; ++i) x(s.layout.traction[i]) = 0.01 * static_cast<double>(i + 1);
  const TractionMeasurement& m = s.traction.Measure(x);
  const double torque_nm[] = {10.0, 20.0, 30.0};  // vehicle order
  ASSERT_EQ(m.measured.size(), 3);
  for (std::size_t i = 0; i < 3; ++i) {
    const auto row = static_cast<Eigen::Index>(i);
    const double scale = ScaleNm(s.v, i);
    EXPECT_NEAR(m.measured(row), torque_nm[i] / scale, 1e-12);
    EXPECT_NEAR(m.innovation(row), torque_nm[i] / scale - 0.01 * static_cast<double>(i + 1), 1e-12);
    EXPECT_NEAR(m.noise(row, row), (0.05 / scale) * (0.05 / scale), 1e-15);
    for (Eigen::Index c = 0; c < x.size(); ++c) {
      EXPECT_EQ(m.model.jacobian(row, c), c == s.layout.traction[i] ? 1.0 : 0.0) << i << " " << c;
    }
  }
  EXPECT_EQ(m.noise(0, 1), 0.0);
  EXPECT_EQ(m.gate, ChiSquareGate(3, FilterConfig{}.wheels.gate_probability));
}

TEST(TractionUpdater, TheInitialTractionIsTheLastTorquesOrWideBeforeAny) {
  Swerve s;
  const TractionPrior before = s.traction.Initial(1);
  EXPECT_EQ(before.value, 0.0);
  EXPECT_EQ(before.variance, 0.25);
  s.traction.ObserveTorques(s.Wheels(std::vector<double>{30.0, 10.0, 20.0}), s.permuted);
  const TractionPrior after = s.traction.Initial(1);  // left_rear: 20 N m
  EXPECT_NEAR(after.value, 20.0 / ScaleNm(s.v, 1), 1e-12);
  EXPECT_NEAR(after.variance, (0.05 / ScaleNm(s.v, 1)) * (0.05 / ScaleNm(s.v, 1)), 1e-15);
}

TEST(TractionUpdater, MeasuringNeedsTractionStatesAndTorques) {
  Swerve s;
  const Eigen::VectorXd x = Eigen::VectorXd::Zero(s.layout.size);
  EXPECT_THROW(s.traction.Measure(x), std::logic_error);  // no torques yet
  const StateLayout plain = StateLayout::For(s.v, {.slip_aware_odometry = true});
  TractionUpdater without(s.v, FilterConfig{}, plain);
  without.ObserveTorques(s.Wheels(std::vector<double>{1.0, 1.0, 1.0}), s.permuted);
  EXPECT_TRUE(without.last_torque_nm().has_value());  // the wheel-speed model still uses them
  EXPECT_THROW(without.Measure(Eigen::VectorXd::Zero(plain.size)), std::logic_error);
  // A layout of another vehicle (two wheels) is refused.
  const StateLayout two = StateLayout::For(mapio::DifferentialDriveConfig(), {.slip_aware_odometry = true});
  EXPECT_THROW(TractionUpdater(s.v, TractionConfig(), two), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::localization
