#include "rowloc/sim/vehicle_model.hpp"

#include "rowloc/sim/wheel_slip.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <limits>
#include <utility>
#include <numbers>
#include <random>
#include <vector>

namespace rowloc::sim {
namespace {

using ::testing::HasSubstr;

std::vector<TerrainClass> All(const VehicleModel& model, TerrainClass terrain) {
  return std::vector<TerrainClass>(model.config().wheels.size(), terrain);
}

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

/// Random motion with speeds and rates of a field robot (all components within the given scale).
BodyMotion RandomMotion(std::mt19937_64& rng, bool lateral) {
  std::uniform_real_distribution<double> speed(-1.5, 1.5), rate(-0.8, 0.8), accel(-0.5, 0.5);
  BodyMotion m;
  m.v_x_mps = speed(rng);
  m.v_y_mps = lateral ? 0.3 * speed(rng) : 0.0;
  m.yaw_rate_radps = rate(rng);
  m.dv_x_mps2 = accel(rng);
  m.dv_y_mps2 = lateral ? accel(rng) : 0.0;
  m.yaw_accel_radps2 = accel(rng);
  return m;
}

// The longitudinal force the header specifies, recomputed independently.
double ExpectedForce(const VehicleModel& model, std::size_t i, const BodyMotion& m, const WheelTruth& w) {
  const VehicleConfig& c = model.config();
  const Eigen::Vector2d p = c.wheels[i].position_m;
  const double r = m.yaw_rate_radps;
  const Eigen::Vector2d a(m.dv_x_mps2 - r * m.v_y_mps - m.yaw_accel_radps2 * p.y() - r * r * p.x(),
                          m.dv_y_mps2 + r * m.v_x_mps + m.yaw_accel_radps2 * p.x() - r * r * p.y());
  const Eigen::Vector2d h(std::cos(w.steering_angle_rad), std::sin(w.steering_angle_rad));
  const double share = c.mass_kg / static_cast<double>(c.wheels.size());
  const double n = share * 9.80665;
  const double crr = model.terrains().At(w.terrain).rolling_resistance_coefficient;
  const double v = w.longitudinal_speed_mps;
  return share * a.dot(h) + crr * n * v / std::max(std::abs(v), 0.05);
}

TEST(VehicleModel, RejectsAnInvalidConfiguration) {
  VehicleConfig config = DifferentialDriveConfig();
  config.mass_kg = -1.0;
  EXPECT_THROW(VehicleModel(config, TerrainSlipTable::Defaults()), std::invalid_argument);
}

TEST(VehicleModel, RejectsWrongTerrainCountAndNonFiniteMotion) {
  const VehicleModel model(AgrimaroSwerveConfig(), TerrainSlipTable::Defaults());
  const std::vector<TerrainClass> two(2, TerrainClass::kTiles);
  EXPECT_THROW(model.Wheels(BodyMotion{.v_x_mps = 1.0}, two), std::invalid_argument);
  const BodyMotion bad{.v_x_mps = std::numeric_limits<double>::quiet_NaN()};
  EXPECT_THAT(model.MotionProblem(bad).value_or(""), HasSubstr("non-finite"));
  EXPECT_THROW(model.Wheels(bad, All(model, TerrainClass::kTiles)), std::invalid_argument);
}

TEST(VehicleModel, ConstantSpeedSlipIsTheSteadyStateSlipOnEveryTerrain) {
  const TerrainSlipTable table = TerrainSlipTable::Defaults();
  const std::vector<std::pair<TerrainClass, double>> shipped = {{TerrainClass::kTiles, 0.00501},
                                                                {TerrainClass::kGrass, 0.12500},
                                                                {TerrainClass::kGravel, 0.13407},
                                                                {TerrainClass::kMud, 0.24993}};
  for (const VehicleConfig& config : {AgrimaroSwerveConfig(), VineyardUgv4wsConfig(), DifferentialDriveConfig()}) {
    const VehicleModel model(config, table);
    for (const auto& [terrain, rounded] : shipped) {
      const double expected = LongitudinalWheelDynamics(WheelDynamicsParams{}, table.At(terrain)).SteadyStateSlip();
      EXPECT_NEAR(expected, rounded, 5e-6);
      for (const double speed : {0.3, 1.0, 2.0}) {
        for (const WheelTruth& w : model.Wheels(BodyMotion{.v_x_mps = speed}, All(model, terrain))) {
          EXPECT_NEAR(w.slip, expected, 1e-9) << config.name << " " << TerrainClassName(terrain);
          EXPECT_NEAR(SaeLongitudinalSlip(w.wheel_angular_speed_radps, w.rolling_radius_m, speed), w.slip, 1e-12);
          EXPECT_FALSE(w.traction_limited);
        }
      }
    }
  }
}

TEST(VehicleModel, SteeredWheelsPointAlongTheirVelocity) {
  std::mt19937_64 rng(7);
  const TerrainSlipTable table = TerrainSlipTable::Defaults();
  int checked = 0;
  for (const VehicleConfig& config : {AgrimaroSwerveConfig(), VineyardUgv4wsConfig()}) {
    const VehicleModel model(config, table);
    for (int trial = 0; trial < 300; ++trial) {
      const BodyMotion m = RandomMotion(rng, true);
      if (model.MotionProblem(m)) continue;
      const auto wheels = model.Wheels(m, All(model, TerrainClass::kGrass));
      for (std::size_t i = 0; i < wheels.size(); ++i) {
        const Eigen::Vector2d p = config.wheels[i].position_m;
        const Eigen::Vector2d v(m.v_x_mps - m.yaw_rate_radps * p.y(), m.v_y_mps + m.yaw_rate_radps * p.x());
        const Eigen::Vector2d h(std::cos(wheels[i].steering_angle_rad), std::sin(wheels[i].steering_angle_rad));
        EXPECT_NEAR(Cross(h, v), 0.0, 1e-12);
        EXPECT_NEAR(std::abs(wheels[i].longitudinal_speed_mps), v.norm(), 1e-12);
        EXPECT_NEAR(wheels[i].longitudinal_speed_mps, h.dot(v), 1e-12);
        EXPECT_EQ(wheels[i].lateral_speed_mps, 0.0);
        EXPECT_LE(std::abs(wheels[i].steering_angle_rad), config.max_steering_angle_rad + 1e-12);
        EXPECT_NEAR(wheels[i].torque_nm, wheels[i].longitudinal_force_n * wheels[i].rolling_radius_m, 1e-12);
        EXPECT_NEAR(wheels[i].longitudinal_force_n, ExpectedForce(model, i, m, wheels[i]), 1e-9);
        EXPECT_NEAR(wheels[i].rolling_radius_m, config.wheels[i].nominal_radius_m * 0.98, 1e-15);
        if (std::abs(wheels[i].longitudinal_speed_mps) >= 0.05 && !wheels[i].traction_limited) {
          EXPECT_NEAR(SaeLongitudinalSlip(wheels[i].wheel_angular_speed_radps, wheels[i].rolling_radius_m,
                                          wheels[i].longitudinal_speed_mps),
                      wheels[i].slip, 1e-12);
          const double mu = JanosiHanamotoCurve(table.At(TerrainClass::kGrass)).TractionCoefficient(wheels[i].slip);
          EXPECT_NEAR(mu * wheels[i].normal_load_n, wheels[i].longitudinal_force_n, 1e-8);
        }
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 1000);
}

TEST(VehicleModel, SlipSignFollowsTheForce) {
  const VehicleModel model(VineyardUgv4wsConfig(), TerrainSlipTable::Defaults());
  const auto gravel = All(model, TerrainClass::kGravel);
  const double steady = model.Wheels(BodyMotion{.v_x_mps = 1.0}, gravel)[0].slip;
  for (const WheelTruth& w : model.Wheels(BodyMotion{.v_x_mps = 1.0, .dv_x_mps2 = 1.0}, gravel)) {
    EXPECT_GT(w.slip, steady);  // accelerating: more slip than cruising
    EXPECT_GT(w.wheel_angular_speed_radps * w.rolling_radius_m, 1.0);
  }
  for (const WheelTruth& w : model.Wheels(BodyMotion{.v_x_mps = 1.0, .dv_x_mps2 = -2.0}, gravel)) {
    EXPECT_LT(w.slip, 0.0);  // braking harder than rolling resistance
    EXPECT_LT(w.wheel_angular_speed_radps * w.rolling_radius_m, 1.0);
    EXPECT_LT(w.torque_nm, 0.0);
  }
  // Reversing (the 4WS wheel turns by pi: heading 0 is kept, longitudinal speed < 0).
  for (const WheelTruth& w : model.Wheels(BodyMotion{.v_x_mps = -1.0, .dv_x_mps2 = -1.0}, gravel)) {
    EXPECT_NEAR(w.steering_angle_rad, 0.0, 1e-15);
    EXPECT_DOUBLE_EQ(w.longitudinal_speed_mps, -1.0);
    EXPECT_LT(w.slip, 0.0);
    EXPECT_LT(w.wheel_angular_speed_radps * w.rolling_radius_m, -1.0);
  }
}

TEST(VehicleModel, TractionLimitSaturatesAndFlags) {
  const VehicleModel model(DifferentialDriveConfig(), TerrainSlipTable::Defaults());
  const auto mud = All(model, TerrainClass::kMud);
  for (const WheelTruth& w : model.Wheels(BodyMotion{.v_x_mps = 1.0, .dv_x_mps2 = 5.0}, mud)) {
    EXPECT_TRUE(w.traction_limited);
    EXPECT_EQ(w.slip, 1.0);
    EXPECT_NEAR(w.wheel_angular_speed_radps * w.rolling_radius_m, 1.0 / (1.0 - kSpinningSlipForSpeed), 1e-12);
  }
  for (const WheelTruth& w : model.Wheels(BodyMotion{.v_x_mps = 1.0, .dv_x_mps2 = -5.0}, mud)) {
    EXPECT_TRUE(w.traction_limited);
    EXPECT_EQ(w.slip, -1.0);
    EXPECT_EQ(w.wheel_angular_speed_radps, 0.0);  // locked
  }
}

TEST(VehicleModel, DeadbandGivesZeroSlipAndRollingSpeed) {
  const VehicleModel model(DifferentialDriveConfig(), TerrainSlipTable::Defaults());
  const auto mud = All(model, TerrainClass::kMud);
  for (const WheelTruth& w : model.Wheels(BodyMotion{.v_x_mps = 0.02, .dv_x_mps2 = 0.5}, mud)) {
    EXPECT_EQ(w.slip, 0.0);
    EXPECT_DOUBLE_EQ(w.wheel_angular_speed_radps * w.rolling_radius_m, 0.02);
    EXPECT_GT(w.torque_nm, 0.0);  // the acceleration still needs torque
  }
}

TEST(VehicleModel, DifferentialDriveCannotMoveSideways) {
  const VehicleModel model(DifferentialDriveConfig(), TerrainSlipTable::Defaults());
  const BodyMotion sideways{.v_x_mps = 1.0, .v_y_mps = 0.1};
  EXPECT_THAT(model.MotionProblem(sideways).value_or(""), HasSubstr("cannot move sideways"));
  EXPECT_THROW(model.Wheels(sideways, All(model, TerrainClass::kTiles)), std::invalid_argument);
  EXPECT_THAT(model.MotionProblem(BodyMotion{.v_x_mps = 1.0, .dv_y_mps2 = 0.1}).value_or(""),
              HasSubstr("cannot accelerate sideways"));
  EXPECT_EQ(model.MotionProblem(BodyMotion{.v_x_mps = 1.0, .yaw_rate_radps = 0.5}), std::nullopt);
  // Turning: wheel speeds follow the DWR kinematics of Tazzari et al. n.d. eq. (2) on tiles (tiny slip).
  const auto wheels =
      model.Wheels(BodyMotion{.v_x_mps = 1.0, .yaw_rate_radps = 0.5}, All(model, TerrainClass::kTiles));
  EXPECT_DOUBLE_EQ(wheels[0].longitudinal_speed_mps, 1.0 - 0.5 * 0.28);
  EXPECT_DOUBLE_EQ(wheels[1].longitudinal_speed_mps, 1.0 + 0.5 * 0.28);
  EXPECT_EQ(wheels[0].steering_angle_rad, 0.0);
}

TEST(VehicleModel, FourWheelSteerReportsSteeringBeyondItsLimit) {
  const VehicleModel model(VineyardUgv4wsConfig(), TerrainSlipTable::Defaults());
  EXPECT_THAT(model.MotionProblem(BodyMotion{.v_y_mps = 1.0}).value_or(""), HasSubstr("beyond"));
  // Spot turn: |delta| = atan(0.5/0.4) = 0.896 rad after turning the wheel by pi.
  EXPECT_EQ(model.MotionProblem(BodyMotion{.yaw_rate_radps = 0.5}), std::nullopt);
  const auto spot = model.Wheels(BodyMotion{.yaw_rate_radps = 0.5}, All(model, TerrainClass::kTiles));
  EXPECT_NEAR(std::abs(spot[0].steering_angle_rad), std::atan(0.5 / 0.4), 1e-12);
  const VehicleModel swerve(AgrimaroSwerveConfig(), TerrainSlipTable::Defaults());
  const auto crab = swerve.Wheels(BodyMotion{.v_y_mps = 1.0}, All(swerve, TerrainClass::kTiles));
  for (const WheelTruth& w : crab) EXPECT_NEAR(w.steering_angle_rad, std::numbers::pi / 2.0, 1e-15);
}

TEST(VehicleModel, MirroredMotionGivesMirroredWheels) {
  std::mt19937_64 rng(11);
  const VehicleModel model(VineyardUgv4wsConfig(), TerrainSlipTable::Defaults());
  const auto grass = All(model, TerrainClass::kGrass);
  int checked = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const BodyMotion m = RandomMotion(rng, true);
    BodyMotion mirrored = m;
    mirrored.v_y_mps = -m.v_y_mps;
    mirrored.dv_y_mps2 = -m.dv_y_mps2;
    mirrored.yaw_rate_radps = -m.yaw_rate_radps;
    mirrored.yaw_accel_radps2 = -m.yaw_accel_radps2;
    if (model.MotionProblem(m)) continue;
    const auto a = model.Wheels(m, grass);
    const auto b = model.Wheels(mirrored, grass);
    using Pair = std::pair<std::size_t, std::size_t>;
    for (const auto& [left, right] : {Pair{0, 1}, Pair{2, 3}}) {
      for (const auto& [x, y] : {Pair{left, right}, Pair{right, left}}) {
        EXPECT_NEAR(a[x].steering_angle_rad, -b[y].steering_angle_rad, 1e-12);
        EXPECT_NEAR(a[x].wheel_angular_speed_radps, b[y].wheel_angular_speed_radps, 1e-9);
        EXPECT_NEAR(a[x].slip, b[y].slip, 1e-12);
        EXPECT_NEAR(a[x].torque_nm, b[y].torque_nm, 1e-9);
      }
    }
    ++checked;
  }
  EXPECT_GT(checked, 50);
}

TEST(VehicleModel, ImuSpecificForceMatchesDifferentiatedWorldVelocity) {
  std::mt19937_64 rng(3);
  VehicleConfig config = VineyardUgv4wsConfig();
  config.imu.position_m = Eigen::Vector3d(0.3, -0.2, 0.25);
  const VehicleModel model(config, TerrainSlipTable::Defaults());
  const Eigen::Vector2d p = config.imu.position_m.head<2>();
  for (int trial = 0; trial < 50; ++trial) {
    const BodyMotion m = RandomMotion(rng, true);
    const double heading0 = 0.7;
    // World velocity of the IMU point at time t for a motion with constant body-frame derivatives.
    const auto world_velocity = [&](double t) {
      const double yaw_rate = m.yaw_rate_radps + m.yaw_accel_radps2 * t;
      const double heading = heading0 + m.yaw_rate_radps * t + 0.5 * m.yaw_accel_radps2 * t * t;
      const Eigen::Vector2d body(m.v_x_mps + m.dv_x_mps2 * t - yaw_rate * p.y(),
                                 m.v_y_mps + m.dv_y_mps2 * t + yaw_rate * p.x());
      return Eigen::Rotation2Dd(heading) * body;
    };
    const double h = 1e-5;
    const Eigen::Vector2d world_accel = (world_velocity(h) - world_velocity(-h)) / (2.0 * h);
    const Eigen::Vector2d body_accel = Eigen::Rotation2Dd(-heading0) * world_accel;
    EXPECT_NEAR((model.ImuSpecificForce(m) - body_accel).norm(), 0.0, 1e-8);
  }
  // Danzi 2026 eqs. (4.24)-(4.25): at the reference point a_Bx = dv_x/dt - yaw_rate v_y, a_By = dv_y/dt + yaw_rate v_x.
  const BodyMotion m{.v_x_mps = 1.0, .v_y_mps = 0.2, .yaw_rate_radps = 0.5, .dv_x_mps2 = 0.1, .dv_y_mps2 = 0.3};
  EXPECT_TRUE(PointAcceleration(m, Eigen::Vector2d::Zero()).isApprox(Eigen::Vector2d(0.1 - 0.1, 0.3 + 0.5)));
}

TEST(VehicleModel, TrackedStraightRunHasEqualSteadyStateSlips) {
  const TerrainSlipTable table = TerrainSlipTable::Defaults();
  const VehicleModel model(TrackedVehicleConfig(), table);
  for (const TerrainClass terrain : kAllTerrainClasses) {
    const double expected = LongitudinalWheelDynamics(WheelDynamicsParams{}, table.At(terrain)).SteadyStateSlip();
    const auto tracks = model.Wheels(BodyMotion{.v_x_mps = 0.8}, All(model, terrain));
    EXPECT_NEAR(tracks[0].slip, expected, 1e-9);
    EXPECT_NEAR(tracks[1].slip, expected, 1e-9);
    EXPECT_DOUBLE_EQ(tracks[0].rolling_radius_m, 0.15);  // the sprocket radius
  }
}

TEST(VehicleModel, TrackedTurnSlipsTheOuterTrackMore) {
  const VehicleModel model(TrackedVehicleConfig(), TerrainSlipTable::Defaults());
  for (const double yaw_rate : {0.2, -0.2}) {  // radius 4 m at 0.8 m/s, left then right
    const auto tracks = model.Wheels(BodyMotion{.v_x_mps = 0.8, .yaw_rate_radps = yaw_rate},
                                     All(model, TerrainClass::kGrass));
    const std::size_t outer = yaw_rate > 0.0 ? 1 : 0;  // right track is outer in a left turn
    EXPECT_GT(tracks[outer].slip, tracks[1 - outer].slip);
    EXPECT_GT(tracks[outer].torque_nm, tracks[1 - outer].torque_nm);
    EXPECT_FALSE(tracks[0].traction_limited || tracks[1].traction_limited);
  }
}

TEST(VehicleModel, TrackSlipsReproduceTheCommandedMotionThroughSeed001Eq3) {
  std::mt19937_64 rng(5);
  const VehicleConfig config = TrackedVehicleConfig();
  const VehicleModel model(config, TerrainSlipTable::Defaults());
  const double d = config.wheels[0].position_m.y();  // half gauge
  std::uniform_int_distribution<int> terrain_index(0, 3);
  int checked = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const BodyMotion m = RandomMotion(rng, false);
    const std::vector<TerrainClass> terrains = {kAllTerrainClasses[static_cast<std::size_t>(terrain_index(rng))],
                                                kAllTerrainClasses[static_cast<std::size_t>(terrain_index(rng))]};
    const auto tracks = model.Wheels(m, terrains);
    if (tracks[0].traction_limited || tracks[1].traction_limited) continue;
    const WheelTruth& left = tracks[0];
    const WheelTruth& right = tracks[1];
    const double eta_l = 1.0 - left.slip;
    const double eta_r = 1.0 - right.slip;
    const double v_r = right.rolling_radius_m * right.wheel_angular_speed_radps;
    const double v_l = left.rolling_radius_m * left.wheel_angular_speed_radps;
    EXPECT_NEAR((eta_r * v_r + eta_l * v_l) / 2.0, m.v_x_mps, 1e-12);
    EXPECT_NEAR((eta_r * v_r - eta_l * v_l) / (2.0 * d), m.yaw_rate_radps, 1e-12);
    for (const WheelTruth& track : tracks) {
      if (std::abs(track.longitudinal_speed_mps) < 0.05) continue;
      // Tazzari et al. n.d. eq. (6): i = 1 - V_t / (omega r).
      EXPECT_NEAR(track.slip, 1.0 - track.longitudinal_speed_mps / (track.wheel_angular_speed_radps * 0.15), 1e-12);
    }
    ++checked;
  }
  EXPECT_GT(checked, 100);
}

TEST(VehicleModel, TrackTurningResistanceFollowsWong) {
  const VehicleConfig config = TrackedVehicleConfig();
  const VehicleModel model(config, TerrainSlipTable::Defaults());
  const auto tracks = model.Wheels(BodyMotion{.v_x_mps = 0.8, .yaw_rate_radps = 0.3}, All(model, TerrainClass::kTiles));
  const double moment = 0.3 * 600.0 * 9.80665 * 1.0 / 4.0;  // mu_t m g l / 4
  const double gauge = 1.1;
  // Outer minus inner: 2 M_r / B plus the centripetal terms (zero: tracks at x = 0 with v_y = 0).
  EXPECT_NEAR(tracks[1].longitudinal_force_n - tracks[0].longitudinal_force_n, 2.0 * moment / gauge, 1e-9);
  EXPECT_NEAR(tracks[0].lateral_speed_mps, 0.0, 1e-15);
}

}  // namespace
}  // namespace rowloc::sim
