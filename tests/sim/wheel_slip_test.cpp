#include "rowloc/sim/wheel_slip.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace rowloc::sim {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

std::vector<double> SlipGrid() {
  std::vector<double> grid;
  for (int i = -100; i <= 100; ++i) grid.push_back(i / 100.0);
  for (const double s : {1e-9, 1e-6, 1e-4, 9.99e-4, 1.001e-3}) {
    grid.push_back(s);
    grid.push_back(-s);
  }
  return grid;
}

// ---- SAE slip ------------------------------------------------------------------------------

TEST(SaeLongitudinalSlipTest, TractionBrakingAndPureRolling) {
  EXPECT_DOUBLE_EQ(SaeLongitudinalSlip(10.0, 0.1, 0.8), (1.0 - 0.8) / 1.0);   // traction: / omega r
  EXPECT_DOUBLE_EQ(SaeLongitudinalSlip(8.0, 0.1, 1.0), (0.8 - 1.0) / 1.0);    // braking: / v
  EXPECT_DOUBLE_EQ(SaeLongitudinalSlip(10.0, 0.1, 1.0), 0.0);
  EXPECT_DOUBLE_EQ(SaeLongitudinalSlip(-10.0, 0.1, -0.8), -(1.0 - 0.8) / 1.0);  // reverse traction
  EXPECT_DOUBLE_EQ(SaeLongitudinalSlip(10.0, 0.1, 0.0), 1.0);   // spinning in place
  EXPECT_DOUBLE_EQ(SaeLongitudinalSlip(0.0, 0.1, 1.0), -1.0);   // locked wheel
}

TEST(SaeLongitudinalSlipTest, DeadbandAndSaturation) {
  EXPECT_EQ(SaeLongitudinalSlip(0.49, 0.1, 0.0), 0.0);    // 0.049 m/s: both under 0.05
  EXPECT_EQ(SaeLongitudinalSlip(0.4, 0.1, -0.049), 0.0);
  EXPECT_DOUBLE_EQ(SaeLongitudinalSlip(0.5, 0.1, 0.0), 1.0);  // 0.05 m/s is outside the deadband
  EXPECT_DOUBLE_EQ(SaeLongitudinalSlip(10.0, 0.1, -1.0), 1.0);   // opposite signs: 2 -> 1
  EXPECT_DOUBLE_EQ(SaeLongitudinalSlip(-10.0, 0.1, 1.0), -1.0);
  for (const double omega : {-30.0, -3.0, -0.3, 0.0, 0.3, 3.0, 30.0}) {
    for (const double v : {-3.0, -0.3, 0.0, 0.3, 3.0}) {
      const double s = SaeLongitudinalSlip(omega, 0.1, v);
      EXPECT_LE(std::abs(s), 1.0);
    }
  }
}

TEST(SaeLongitudinalSlipTest, RejectsBadInput) {
  EXPECT_THROW(SaeLongitudinalSlip(kNaN, 0.1, 1.0), std::invalid_argument);
  EXPECT_THROW(SaeLongitudinalSlip(1.0, 0.1, kInf), std::invalid_argument);
  EXPECT_THROW(SaeLongitudinalSlip(1.0, 0.0, 1.0), std::invalid_argument);
  EXPECT_THROW(SaeLongitudinalSlip(1.0, -0.1, 1.0), std::invalid_argument);
}

// ---- Janosi-Hanamoto curve -----------------------------------------------------------------

TEST(JanosiHanamotoCurveTest, ZeroAtZeroOddAndStrictlyIncreasing) {
  const JanosiHanamotoCurve curve(0.6, 0.2);
  EXPECT_EQ(curve.TractionCoefficient(0.0), 0.0);
  double previous = -kInf;
  auto grid = SlipGrid();
  std::sort(grid.begin(), grid.end());
  for (const double s : grid) {
    const double mu = curve.TractionCoefficient(s);
    EXPECT_GT(mu, previous) << s;
    EXPECT_DOUBLE_EQ(mu, -curve.TractionCoefficient(-s)) << s;
    EXPECT_LT(std::abs(mu), 0.6);
    previous = mu;
  }
}

TEST(JanosiHanamotoCurveTest, MatchesTheClosedFormAwayFromZero) {
  const double mu_max = 0.55;
  const double b = 0.3;
  const JanosiHanamotoCurve curve(mu_max, b);
  for (const double s : {0.01, 0.1, 0.5, 1.0}) {
    EXPECT_NEAR(curve.TractionCoefficient(s), mu_max * (1.0 - (b / s) * (1.0 - std::exp(-s / b))), 1e-14);
  }
}

TEST(JanosiHanamotoCurveTest, TendsToTractionMaximum) {
  const JanosiHanamotoCurve curve(0.7, 0.1);
  EXPECT_NEAR(curve.UnboundedTractionCoefficient(1e3), 0.7 * (1.0 - 1e-4), 1e-12);
  EXPECT_NEAR(curve.UnboundedTractionCoefficient(1e9), 0.7, 1e-9);
  EXPECT_NEAR(curve.UnboundedTractionCoefficient(-1e9), -0.7, 1e-9);
  EXPECT_DOUBLE_EQ(curve.MaxTractionCoefficient(), curve.TractionCoefficient(1.0));
}

TEST(JanosiHanamotoCurveTest, SlopeMatchesNumericDerivative) {
  const JanosiHanamotoCurve curve(0.8, 0.1);
  // At zero the slope is k_s = mu_max / (2B) (Lindgren et al. 2002 eq. (23)).
  EXPECT_NEAR(curve.Slope(0.0), 0.8 / (2.0 * 0.1), 1e-15);
  // Across 0 the odd extension mu = mu_max (s/(2B) - s|s|/(6B^2) + ...) makes the central
  // difference low by mu_max h/(6B^2) = 1.3e-5 at h = 1e-6.
  const double h = 1e-6;
  EXPECT_NEAR((curve.TractionCoefficient(h) - curve.TractionCoefficient(-h)) / (2.0 * h), 4.0, 2e-5);
  // Points on both sides of the series/closed-form switch at s/B = 1e-3 (s = 1e-4 here).
  for (const double s : {-0.9, -0.3, -0.05, -1e-3, 9.99e-5, 1.001e-4, 9.99e-3, 0.05, 0.3, 0.9}) {
    const double numeric = (curve.TractionCoefficient(s + h) - curve.TractionCoefficient(s - h)) / (2.0 * h);
    EXPECT_NEAR(curve.Slope(s), numeric, 1e-6 * std::max(1.0, numeric)) << s;
  }
}

TEST(JanosiHanamotoCurveTest, InverseRoundTrip) {
  for (const auto& terrain : {JanosiHanamotoCurve(0.8, 0.1), JanosiHanamotoCurve(0.41, 0.25),
                              JanosiHanamotoCurve(1.0, 0.01)}) {
    for (const double s : SlipGrid()) {
      const auto inverse = terrain.SlipFor(terrain.TractionCoefficient(s));
      EXPECT_EQ(inverse.status, SlipInverseStatus::kOk) << s;
      EXPECT_NEAR(inverse.slip, s, 1e-11) << s;
    }
  }
}

TEST(JanosiHanamotoCurveTest, DemandBeyondMaximumSpinsTheWheel) {
  const JanosiHanamotoCurve curve(0.5, 0.25);
  const double max = curve.MaxTractionCoefficient();
  const auto spin = curve.SlipFor(max * 1.001);
  EXPECT_EQ(spin.status, SlipInverseStatus::kWheelSpins);
  EXPECT_EQ(spin.slip, 1.0);
  const auto lock = curve.SlipFor(-0.49);
  EXPECT_EQ(lock.status, SlipInverseStatus::kWheelSpins);
  EXPECT_EQ(lock.slip, -1.0);
  EXPECT_EQ(curve.SlipFor(kInf).status, SlipInverseStatus::kWheelSpins);
  const auto at_max = curve.SlipFor(max);
  EXPECT_EQ(at_max.status, SlipInverseStatus::kOk);
  EXPECT_EQ(at_max.slip, 1.0);
}

TEST(JanosiHanamotoCurveTest, RejectsBadInput) {
  EXPECT_THROW(JanosiHanamotoCurve(0.0, 0.1), std::invalid_argument);
  EXPECT_THROW(JanosiHanamotoCurve(0.5, -0.1), std::invalid_argument);
  EXPECT_THROW(JanosiHanamotoCurve(kNaN, 0.1), std::invalid_argument);
  const JanosiHanamotoCurve curve(0.5, 0.25);
  EXPECT_THROW(curve.TractionCoefficient(1.0001), std::invalid_argument);
  EXPECT_THROW(curve.TractionCoefficient(kNaN), std::invalid_argument);
  EXPECT_THROW(curve.Slope(-1.5), std::invalid_argument);
  EXPECT_THROW(curve.UnboundedTractionCoefficient(kInf), std::invalid_argument);
  EXPECT_THROW(curve.SlipFor(kNaN), std::invalid_argument);
}

// ---- Longitudinal dynamics -----------------------------------------------------------------

// AgriMaRo assumption (docs/simulation-slip.md): 60 kg on three wheels, r = 0.1 m.
WheelDynamicsParams AgriMaRoWheel() {
  return {.mass_share_kg = 20.0, .wheel_inertia_kg_m2 = 0.05, .nominal_radius_m = 0.1,
          .gravity_mps2 = 9.80665, .internal_step_s = 1e-4};
}

struct RunSummary {
  double mean_slip_last_seconds = 0.0;
  double final_speed_mps = 0.0;
  double peak_abs_slip = 0.0;
};

// Point-mass vehicle with a PI speed controller tracking a 1 m/s^2 ramp to 1 m/s (Danzi 2026 ch. 7),
// held until t_end; the slip is averaged over the last `average_s` seconds.
RunSummary DriveRampAndHold(const LongitudinalWheelDynamics& wheel, double t_end_s, double average_s) {
  constexpr double kDt = 0.01;
  constexpr double kKp = 20.0;  // N m per m/s
  constexpr double kKi = 20.0;  // N m per m
  WheelState state;
  double integral = 0.0;
  RunSummary summary;
  double slip_sum = 0.0;
  int slip_count = 0;
  const int steps = static_cast<int>(std::lround(t_end_s / kDt));
  for (int k = 0; k < steps; ++k) {
    const double t = k * kDt;
    const double reference = std::min(t, 1.0);
    const double error = reference - state.vehicle_speed_mps;
    integral += error * kDt;
    const double torque = kKp * error + kKi * integral;
    const auto result = wheel.Step(state, torque, kDt);
    state = result.state;
    summary.peak_abs_slip = std::max(summary.peak_abs_slip, std::abs(result.slip));
    if (t + kDt > t_end_s - average_s) {
      slip_sum += result.slip;
      ++slip_count;
    }
  }
  summary.mean_slip_last_seconds = slip_sum / slip_count;
  summary.final_speed_mps = state.vehicle_speed_mps;
  return summary;
}

TEST(LongitudinalWheelDynamicsTest, SteadyStateSlipOnEveryTerrainWithinFiveThousandths) {
  const auto table = TerrainSlipTable::Defaults();
  for (const auto terrain : kAllTerrainClasses) {
    const LongitudinalWheelDynamics wheel(AgriMaRoWheel(), table.At(terrain));
    const auto run = DriveRampAndHold(wheel, 12.0, 4.0);
    SCOPED_TRACE(std::string(TerrainClassName(terrain)));
    EXPECT_NEAR(run.final_speed_mps, 1.0, 1e-3);
    EXPECT_NEAR(run.mean_slip_last_seconds, wheel.SteadyStateSlip(), 0.005);
    EXPECT_LT(run.peak_abs_slip, 1.0);  // 1 m/s^2 never spins the wheel
  }
}

TEST(LongitudinalWheelDynamicsTest, ConstantTorqueConvergesToRollingResistanceBalance) {
  // With T = r_roll * c_rr * N the equilibrium is v arbitrary with s = s*: start at s* and stay.
  const auto terrain = TerrainSlipTable::Defaults().At(TerrainClass::kGravel);
  const LongitudinalWheelDynamics wheel(AgriMaRoWheel(), terrain);
  const double s_star = wheel.SteadyStateSlip();
  const double r = wheel.rolling_radius_m();
  const WheelState start{.wheel_angular_speed_rad_s = 1.0 / ((1.0 - s_star) * r), .vehicle_speed_mps = 1.0};
  const auto result = wheel.Step(start, r * wheel.rolling_resistance_n(), 5.0);
  EXPECT_NEAR(result.slip, s_star, 1e-9);
  EXPECT_NEAR(result.state.vehicle_speed_mps, 1.0, 1e-9);
  EXPECT_NEAR(result.traction_force_n, wheel.rolling_resistance_n(), 1e-6);
  EXPECT_DOUBLE_EQ(result.rolling_radius_m, 0.1 * terrain.rolling_radius_factor);
}

TEST(LongitudinalWheelDynamicsTest, StableAtLargeInternalSteps) {
  // The slip mode on tiles has a time constant of ~ I v / (r^2 dF/ds) ~ 6 ms; explicit Euler would
  // diverge at h = 20 ms. The linearly implicit step stays bounded and reaches the same equilibrium.
  const auto terrain = TerrainSlipTable::Defaults().At(TerrainClass::kTiles);
  std::vector<double> final_speeds;
  for (const double h : {1e-4, 1e-3, 2e-2}) {
    auto params = AgriMaRoWheel();
    params.internal_step_s = h;
    const LongitudinalWheelDynamics wheel(params, terrain);
    const double torque = wheel.rolling_radius_m() * (wheel.rolling_resistance_n() + 4.0);
    WheelState state{.wheel_angular_speed_rad_s = 5.0, .vehicle_speed_mps = 0.5};
    double previous_speed = state.vehicle_speed_mps;
    for (int k = 0; k < 200; ++k) {  // 2 s with 4 N of net thrust
      const auto result = wheel.Step(state, torque, 0.01);
      state = result.state;
      ASSERT_TRUE(std::isfinite(state.wheel_angular_speed_rad_s)) << h;
      ASSERT_LE(std::abs(result.slip), 0.05) << "h = " << h << " step " << k;
      EXPECT_GE(state.vehicle_speed_mps, previous_speed - 1e-12) << h;
      previous_speed = state.vehicle_speed_mps;
    }
    // Net thrust 4 N on the mass plus the wheel's equivalent mass I / r^2 (slip nearly constant).
    const double equivalent_mass =
        params.mass_share_kg + params.wheel_inertia_kg_m2 / std::pow(wheel.rolling_radius_m(), 2);
    EXPECT_NEAR(state.vehicle_speed_mps, 0.5 + 4.0 / equivalent_mass * 2.0, 0.005) << h;
    final_speeds.push_back(state.vehicle_speed_mps);
  }
  EXPECT_NEAR(final_speeds.front(), final_speeds.back(), 1e-6);
}

TEST(LongitudinalWheelDynamicsTest, CoastsToRestWithoutReversing) {
  const auto terrain = TerrainSlipTable::Defaults().At(TerrainClass::kMud);
  const LongitudinalWheelDynamics wheel(AgriMaRoWheel(), terrain);
  WheelState state{.wheel_angular_speed_rad_s = 1.0 / wheel.rolling_radius_m(), .vehicle_speed_mps = 1.0};
  for (int k = 0; k < 1000; ++k) {
    const double before = state.vehicle_speed_mps;
    state = wheel.Step(state, 0.0, 0.01).state;
    EXPECT_LE(state.vehicle_speed_mps, before + 1e-12);
    EXPECT_GE(state.vehicle_speed_mps, -1e-6);
  }
  EXPECT_LT(std::abs(state.vehicle_speed_mps), 1e-3);
  EXPECT_LT(std::abs(state.wheel_angular_speed_rad_s * wheel.rolling_radius_m()), 1e-3);
}

TEST(LongitudinalWheelDynamicsTest, RejectsBadInput) {
  const auto terrain = TerrainSlipTable::Defaults().At(TerrainClass::kGrass);
  auto params = AgriMaRoWheel();
  params.wheel_inertia_kg_m2 = 0.0;
  EXPECT_THROW(LongitudinalWheelDynamics(params, terrain), std::invalid_argument);
  params = AgriMaRoWheel();
  params.mass_share_kg = kNaN;
  EXPECT_THROW(LongitudinalWheelDynamics(params, terrain), std::invalid_argument);
  auto bad_terrain = terrain;
  bad_terrain.shear_slip_constant = -1.0;
  EXPECT_THROW(LongitudinalWheelDynamics(AgriMaRoWheel(), bad_terrain), std::invalid_argument);
  const LongitudinalWheelDynamics wheel(AgriMaRoWheel(), terrain);
  EXPECT_THROW(wheel.Step({}, 1.0, 0.0), std::invalid_argument);
  EXPECT_THROW(wheel.Step({}, 1.0, -0.01), std::invalid_argument);
  EXPECT_THROW(wheel.Step({}, kNaN, 0.01), std::invalid_argument);
  EXPECT_THROW(wheel.Step({.wheel_angular_speed_rad_s = kInf}, 1.0, 0.01), std::invalid_argument);
  EXPECT_THROW(wheel.Step({}, 1.0, 1e9), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::sim
