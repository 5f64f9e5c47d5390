#include "rowloc/sim/vehicle_truth.hpp"

#include "rowloc/sim/route_builders.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace rowloc::sim {
namespace {

using ::testing::HasSubstr;

TEST(VehicleTruthSampler, FlatGroundGivesThePlanarMotion) {
  const Route route(CircleRoute({0, 0}, 0.3, 5.0, 1, 0.8, 0.5));
  const VehicleModel vehicle(VineyardUgv4wsConfig(), TerrainSlipTable::Defaults());
  const TerrainMap terrain_map;
  const VehicleTruthSampler sampler(route, vehicle, terrain_map, nullptr);
  for (double t : {0.5, 3.0, 10.0, 20.0}) {
    const VehicleTruth truth = sampler.At(t);
    const RoutePoint p = route.At(t);
    EXPECT_EQ(truth.route.position_m, p.position_m);
    EXPECT_EQ(truth.motion.v_x_mps, p.speed_mps);
    EXPECT_EQ(truth.motion.v_y_mps, 0.0);
    EXPECT_EQ(truth.motion.yaw_rate_radps, p.yaw_rate_radps);
    EXPECT_EQ(truth.position_m.z(), 0.0);
    const Eigen::Vector2d point(0.3, -0.2);
    EXPECT_TRUE(sampler.SpecificForce(truth, point).isApprox(PointAcceleration(truth.motion, point), 1e-15));
    const Eigen::Vector3d world = sampler.WorldPoint(truth, {0.3, -0.2, 1.0});
    const double c = std::cos(p.heading_rad), s = std::sin(p.heading_rad);
    EXPECT_NEAR(world.x(), p.position_m.x() + 0.3 * c + 0.2 * s, 1e-12);
    EXPECT_NEAR(world.y(), p.position_m.y() + 0.3 * s - 0.2 * c, 1e-12);
    EXPECT_EQ(world.z(), 1.0);
    ASSERT_EQ(truth.wheels.size(), 4u);
  }
}

TEST(VehicleTruthSampler, GravityOnASlopeAlongEachBodyAxis) {
  // At rest (start dwell) on a 10 % grade rising to the east: the accelerometer reads
  // g sin(atan 0.1) along the uphill body axis.
  TerrainParams params;
  params.grade_east = 0.1;
  params.undulation_amplitude_m = 0.0;
  const TerrainSurface surface(params, 1);
  const VehicleModel vehicle(DifferentialDriveConfig(), TerrainSlipTable::Defaults());
  const TerrainMap terrain_map;
  const double expected = kVehicleGravityMps2 * 0.1 / std::sqrt(1.01);
  for (const auto& [heading, fx, fy] : {std::tuple{0.0, expected, 0.0}, std::tuple{std::numbers::pi / 2, 0.0, -expected},
                                        std::tuple{std::numbers::pi, -expected, 0.0}}) {
    RouteSpec spec = StraightRoute({2.0, 1.0}, heading, 10.0, 1.0, 1.0);
    spec.start_dwell_s = 1.0;
    const Route route(spec);
    const VehicleTruthSampler sampler(route, vehicle, terrain_map, &surface);
    const VehicleTruth truth = sampler.At(0.5);
    const Eigen::Vector2d f = sampler.SpecificForce(truth, Eigen::Vector2d::Zero());
    EXPECT_NEAR(f.x(), fx, 1e-12) << heading;
    EXPECT_NEAR(f.y(), fy, 1e-12) << heading;
    EXPECT_NEAR(truth.position_m.z(), 0.2, 1e-12);  // z = 0.1 * x at x = 2
  }
}

TEST(VehicleTruthSampler, EachWheelSeesTheTerrainUnderIt) {
  // Mud under the left half-plane y > 0: driving east along y = 0, the left wheel is in the mud.
  const TerrainMap terrain_map(TerrainClass::kTiles, {TerrainPatch{TerrainClass::kMud, {{-10, 0.1}, {50, 0.1}, {50, 10}, {-10, 10}}}});
  const Route route(StraightRoute({0, 0}, 0.0, 20.0, 1.0, 1.0));
  const VehicleModel vehicle(DifferentialDriveConfig(), TerrainSlipTable::Defaults());
  const VehicleTruthSampler sampler(route, vehicle, terrain_map, nullptr);
  const VehicleTruth truth = sampler.At(8.0);
  ASSERT_EQ(truth.wheels.size(), 2u);
  EXPECT_EQ(truth.wheels[0].terrain, TerrainClass::kMud);   // left, y = +0.28
  EXPECT_EQ(truth.wheels[1].terrain, TerrainClass::kTiles); // right, y = -0.28
  EXPECT_GT(truth.wheels[0].slip, truth.wheels[1].slip);
}

TEST(VehicleTruthSampler, AMotionTheVehicleCannotDriveNamesTheTime) {
  // A 0.1 m circle needs 4WS steering angles beyond the 1.0 rad limit.
  const Route route(CircleRoute({0, 0}, 0.0, 0.1, 1, 0.1, 0.5));
  const VehicleModel vehicle(VineyardUgv4wsConfig(), TerrainSlipTable::Defaults());
  const TerrainMap terrain_map;
  const VehicleTruthSampler sampler(route, vehicle, terrain_map, nullptr);
  EXPECT_THAT([&] { sampler.At(1.0); },
              ::testing::ThrowsMessage<std::invalid_argument>(HasSubstr("cannot drive the route at t = 1.0")));
}

}  // namespace
}  // namespace rowloc::sim
