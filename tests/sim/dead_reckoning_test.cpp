#include "rowloc/sim/dead_reckoning.hpp"

#include "rowloc/sim/vehicle_model.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace rowloc::sim {
namespace {

using ::testing::HasSubstr;

constexpr double kPi = std::numbers::pi;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool IsSteered(const VehicleConfig& config) {
  return config.kind == VehicleKind::kSwerveDrive || config.kind == VehicleKind::kFourWheelSteer;
}

/// Encoder readings without slip: the true steering angle and ground speed / nominal radius.
struct Readings {
  std::vector<double> steering_rad;
  std::vector<double> speed_radps;
};

Readings ReadingsFor(const VehicleConfig& config, const BodyMotion& motion) {
  const VehicleModel model(config, TerrainSlipTable::Defaults());
  const std::vector<TerrainClass> terrain(config.wheels.size(), TerrainClass::kTiles);
  Readings readings;
  const std::vector<WheelTruth> truth = model.Wheels(motion, terrain);
  for (std::size_t i = 0; i < truth.size(); ++i) {
    readings.steering_rad.push_back(truth[i].steering_angle_rad);
    readings.speed_radps.push_back(truth[i].longitudinal_speed_mps / config.wheels[i].nominal_radius_m);
  }
  return readings;
}

/// Random feasible motion; fixed-axle kinds get the no-side-slip v_y = -r x_axle (0 when shipped).
BodyMotion RandomFeasibleMotion(const VehicleConfig& config, std::mt19937_64& rng) {
  const VehicleModel model(config, TerrainSlipTable::Defaults());
  std::uniform_real_distribution<double> speed(-1.5, 1.5), rate(-0.8, 0.8);
  for (;;) {
    BodyMotion m{.v_x_mps = speed(rng), .v_y_mps = 0.3 * speed(rng), .yaw_rate_radps = rate(rng)};
    if (!IsSteered(config)) m.v_y_mps = -m.yaw_rate_radps * config.wheels.front().position_m.x();
    if (!model.MotionProblem(m)) return m;
  }
}

/// A feasible turning motion with sideways velocity where the kind allows it.
BodyMotion TurningMotion(const VehicleConfig& config) {
  return {.v_x_mps = 0.8, .v_y_mps = IsSteered(config) ? 0.2 : 0.0, .yaw_rate_radps = 0.5};
}

void ExpectTwist(const BodyTwist& twist, const BodyMotion& motion, double tolerance) {
  EXPECT_NEAR(twist.v_x_mps, motion.v_x_mps, tolerance);
  EXPECT_NEAR(twist.v_y_mps, motion.v_y_mps, tolerance);
  EXPECT_NEAR(twist.yaw_rate_radps, motion.yaw_rate_radps, tolerance);
}

double AngleDifference(double a, double b) { return std::remainder(a - b, 2.0 * kPi); }

void ExpectWrapped(double heading_rad) {
  EXPECT_GT(heading_rad, -kPi);
  EXPECT_LE(heading_rad, kPi);
}

const PlanarPose kStart{.time_s = 2.0, .position_m = {12.5, -3.0}, .heading_rad = 3.0};

/// Drives a constant motion through the given wheel times (the first only starts the clock).
DeadReckoning DriveConstant(const VehicleConfig& config, const BodyMotion& motion, YawSource source,
                            const std::vector<double>& wheel_times_s) {
  const Readings readings = ReadingsFor(config, motion);
  DeadReckoning dr(config, kStart, source);
  dr.SetSteering(kStart.time_s, readings.steering_rad);
  dr.SetYawRate(kStart.time_s, motion.yaw_rate_radps);
  for (const double t : wheel_times_s) {
    dr.AddWheelSpeeds(t, readings.speed_radps);
    ExpectWrapped(dr.pose().heading_rad);
  }
  return dr;
}

std::vector<double> UniformTimes(double duration_s, int steps) {
  std::vector<double> times;
  for (int k = 0; k <= steps; ++k) times.push_back(kStart.time_s + duration_s * k / steps);
  return times;
}

std::vector<double> RandomTimes(double duration_s, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> cut(0.0, duration_s);
  std::vector<double> times = {kStart.time_s, kStart.time_s + duration_s};
  for (int k = 0; k < 40; ++k) times.push_back(kStart.time_s + cut(rng));
  std::sort(times.begin(), times.end());
  return times;
}

class DeadReckoningShipped : public ::testing::TestWithParam<VehicleConfig (*)()> {
 protected:
  VehicleConfig config_ = GetParam()();
};

TEST_P(DeadReckoningShipped, ExactInverseOfTheVehicleModel) {
  std::mt19937_64 rng(17);
  DeadReckoning gyro(config_, kStart, YawSource::kGyro);
  DeadReckoning wheels(config_, kStart, YawSource::kWheels);
  for (int k = 0; k < 300; ++k) {
    const BodyMotion motion = RandomFeasibleMotion(config_, rng);
    const Readings readings = ReadingsFor(config_, motion);
    const double t = kStart.time_s + 0.02 * k;
    for (DeadReckoning* dr : {&gyro, &wheels}) {
      dr->SetSteering(t, readings.steering_rad);
      dr->SetYawRate(t, motion.yaw_rate_radps);
      dr->AddWheelSpeeds(t, readings.speed_radps);
    }
    SCOPED_TRACE("sample " + std::to_string(k));
    ExpectTwist(gyro.twist(), motion, 1e-9);
    ExpectTwist(wheels.twist(), motion, 1e-9);
  }
}

TEST_P(DeadReckoningShipped, ParallelWheelsFallBackToTheMinimumNormTwist) {
  // Driving straight, every steered wheel points forward: v_y does not appear in the equations.
  const BodyMotion motion{.v_x_mps = -0.7};
  for (const YawSource source : {YawSource::kGyro, YawSource::kWheels}) {
    const DeadReckoning dr = DriveConstant(config_, motion, source, {kStart.time_s, kStart.time_s + 1.0});
    ExpectTwist(dr.twist(), motion, 1e-12);
  }
}

TEST_P(DeadReckoningShipped, CircleClosesAfterOneTurnWhateverTheStep) {
  const BodyMotion motion = TurningMotion(config_);
  const double period_s = 2.0 * kPi / motion.yaw_rate_radps;
  const Eigen::Vector2d v(motion.v_x_mps, motion.v_y_mps);
  // Centre of the circle (instantaneous centre of rotation): the body point (-v_y, v_x) / r.
  const Eigen::Vector2d centre_body = Eigen::Vector2d(-v.y(), v.x()) / motion.yaw_rate_radps;
  const Eigen::Vector2d centre = kStart.position_m + Eigen::Rotation2Dd(kStart.heading_rad) * centre_body;
  std::mt19937_64 rng(5);
  for (const std::vector<double>& times : {UniformTimes(period_s, 1), UniformTimes(period_s, 2),
                                           UniformTimes(period_s, 7), UniformTimes(period_s, 500),
                                           RandomTimes(period_s, rng)}) {
    SCOPED_TRACE(std::to_string(times.size() - 1) + " steps");
    const Readings readings = ReadingsFor(config_, motion);
    DeadReckoning dr(config_, kStart, YawSource::kGyro);
    dr.SetSteering(0.0, readings.steering_rad);
    dr.SetYawRate(0.0, motion.yaw_rate_radps);
    for (const double t : times) {
      const PlanarPose pose = dr.AddWheelSpeeds(t, readings.speed_radps);
      EXPECT_NEAR((pose.position_m - centre).norm(), v.norm() / motion.yaw_rate_radps, 1e-9);
      EXPECT_NEAR(AngleDifference(pose.heading_rad, kStart.heading_rad + motion.yaw_rate_radps * (t - kStart.time_s)),
                  0.0, 1e-9);
      ExpectWrapped(pose.heading_rad);
    }
    EXPECT_NEAR((dr.pose().position_m - kStart.position_m).norm(), 0.0, 1e-9);
    EXPECT_NEAR(AngleDifference(dr.pose().heading_rad, kStart.heading_rad), 0.0, 1e-9);
    EXPECT_NEAR(dr.pose().time_s, kStart.time_s + period_s, 1e-12);
  }
}

TEST_P(DeadReckoningShipped, StraightLineMovesExactlyVelocityTimesTime) {
  const BodyMotion motion{.v_x_mps = 1.1, .v_y_mps = IsSteered(config_) ? 0.3 : 0.0};
  for (const YawSource source : {YawSource::kGyro, YawSource::kWheels}) {
    const DeadReckoning dr = DriveConstant(config_, motion, source, UniformTimes(4.0, 9));
    const Eigen::Vector2d expected =
        kStart.position_m + Eigen::Rotation2Dd(kStart.heading_rad) * Eigen::Vector2d(1.1, motion.v_y_mps) * 4.0;
    EXPECT_NEAR((dr.pose().position_m - expected).norm(), 0.0, 1e-12);
    if (source == YawSource::kGyro) {
      EXPECT_EQ(dr.pose().heading_rad, kStart.heading_rad);  // r = 0 exactly
    } else {
      EXPECT_NEAR(dr.pose().heading_rad, kStart.heading_rad, 1e-14);  // r from a decomposition: round-off
    }
  }
}

TEST_P(DeadReckoningShipped, ConstantTwistResultDoesNotDependOnTheStepCount) {
  const BodyMotion motion = TurningMotion(config_);
  std::mt19937_64 rng(11);
  const PlanarPose one = DriveConstant(config_, motion, YawSource::kWheels, UniformTimes(23.7, 1)).pose();
  for (const std::vector<double>& times : {UniformTimes(23.7, 3), UniformTimes(23.7, 1000), RandomTimes(23.7, rng)}) {
    const PlanarPose many = DriveConstant(config_, motion, YawSource::kWheels, times).pose();
    EXPECT_NEAR((many.position_m - one.position_m).norm(), 0.0, 1e-9);
    EXPECT_NEAR(AngleDifference(many.heading_rad, one.heading_rad), 0.0, 1e-9);
  }
}

INSTANTIATE_TEST_SUITE_P(Configs, DeadReckoningShipped,
                         ::testing::Values(&AgrimaroSwerveConfig, &VineyardUgv4wsConfig, &DifferentialDriveConfig,
                                           &TrackedVehicleConfig),
                         [](const auto& param_info) {
                           std::string name = param_info.param().name;
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

TEST(DeadReckoning, OffsetAsymmetricAxleUsesTheNoSideSlipConstraint) {
  VehicleConfig config = DifferentialDriveConfig();
  config.wheels[0].position_m = {0.3, 0.35};
  config.wheels[1].position_m = {0.3, -0.2};
  std::mt19937_64 rng(3);
  for (const YawSource source : {YawSource::kGyro, YawSource::kWheels}) {
    for (int k = 0; k < 50; ++k) {
      const BodyMotion motion = RandomFeasibleMotion(config, rng);
      ExpectTwist(DriveConstant(config, motion, source, {kStart.time_s}).twist(), motion, 1e-9);
    }
  }
}

TEST(DeadReckoning, GyroRateIsZeroUntilSetAndTheFirstWheelCallOnlyStartsTheClock) {
  const VehicleConfig config = DifferentialDriveConfig();
  DeadReckoning dr(config, kStart);
  const std::vector<double> speeds = {2.0, 4.0};
  const PlanarPose first = dr.AddWheelSpeeds(kStart.time_s + 0.5, speeds);
  EXPECT_EQ(first.position_m, kStart.position_m);
  EXPECT_EQ(first.heading_rad, kStart.heading_rad);
  EXPECT_EQ(first.time_s, kStart.time_s + 0.5);
  EXPECT_EQ(dr.twist().yaw_rate_radps, 0.0);
  EXPECT_NEAR(dr.twist().v_x_mps, 3.0 * config.wheels[0].nominal_radius_m, 1e-15);
}

/// Calls `call`, expects std::invalid_argument naming the method and the reason, and an unchanged
/// estimator (same pose and twist as `twin`, which never saw the bad call).
void ExpectRejected(const DeadReckoning& dr, const DeadReckoning& twin, const std::function<void()>& call,
                    const std::string& method, const std::string& reason) {
  SCOPED_TRACE(method + ": " + reason);
  try {
    call();
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& error) {
    EXPECT_THAT(error.what(), HasSubstr("DeadReckoning::" + method));
    EXPECT_THAT(error.what(), HasSubstr(reason));
  }
  EXPECT_EQ(dr.pose().time_s, twin.pose().time_s);
  EXPECT_EQ(dr.pose().position_m, twin.pose().position_m);
  EXPECT_EQ(dr.pose().heading_rad, twin.pose().heading_rad);
  EXPECT_EQ(dr.twist().v_x_mps, twin.twist().v_x_mps);
  EXPECT_EQ(dr.twist().yaw_rate_radps, twin.twist().yaw_rate_radps);
}

TEST(DeadReckoning, ConstructorRejectsAnInvalidConfigurationAndANonFinitePose) {
  VehicleConfig bad = VineyardUgv4wsConfig();
  bad.wheels[0].nominal_radius_m = 0.0;
  EXPECT_THROW(DeadReckoning(bad, kStart), std::invalid_argument);
  for (const PlanarPose& pose : {PlanarPose{.time_s = kNaN}, PlanarPose{.position_m = {0.0, kNaN}},
                                 PlanarPose{.heading_rad = std::numeric_limits<double>::infinity()}}) {
    EXPECT_THROW(DeadReckoning(VineyardUgv4wsConfig(), pose), std::invalid_argument);
  }
  EXPECT_NEAR(DeadReckoning(VineyardUgv4wsConfig(), PlanarPose{.heading_rad = 7.0}).pose().heading_rad, 7.0 - 2 * kPi,
              1e-15);
}

TEST(DeadReckoning, EveryInvalidInputThrowsAndLeavesTheEstimatorUnchanged) {
  for (const VehicleConfig& config : {VineyardUgv4wsConfig(), DifferentialDriveConfig()}) {
    SCOPED_TRACE(config.name);
    const Readings good = ReadingsFor(config, TurningMotion(config));
    const std::size_t n = config.wheels.size();
    DeadReckoning dr(config, kStart, YawSource::kWheels), twin(config, kStart, YawSource::kWheels);
    auto both = [&](const std::function<void(DeadReckoning&)>& call) {
      call(dr);
      call(twin);
    };
    auto rejected = [&](const std::function<void()>& call, const std::string& method, const std::string& reason) {
      ExpectRejected(dr, twin, call, method, reason);
    };
    std::vector<double> nan_entry = good.speed_radps;
    nan_entry.back() = kNaN;  // the last wheel: fixed on the differential drive, steered on the 4WS
    const std::vector<double> short_list(n - 1, 0.1), long_list(n + 1, 0.1);

    rejected([&] { dr.AddWheelSpeeds(kStart.time_s - 1e-9, good.speed_radps); }, "AddWheelSpeeds",
             "before the initial pose time");
    both([&](DeadReckoning& d) { d.SetSteering(1.0, good.steering_rad); });  // before the pose time: allowed
    both([&](DeadReckoning& d) { d.SetYawRate(1.0, 0.2); });
    both([&](DeadReckoning& d) { d.AddWheelSpeeds(kStart.time_s + 0.1, good.speed_radps); });

    rejected([&] { dr.SetSteering(2.0, short_list); }, "SetSteering", "for " + std::to_string(n) + " wheels");
    rejected([&] { dr.SetSteering(2.0, long_list); }, "SetSteering", "for " + std::to_string(n) + " wheels");
    rejected([&] { dr.SetSteering(2.0, nan_entry); }, "SetSteering", "not finite");
    rejected([&] { dr.SetSteering(kNaN, good.steering_rad); }, "SetSteering", "not finite");
    rejected([&] { dr.SetSteering(0.5, good.steering_rad); }, "SetSteering", "backwards");
    rejected([&] { dr.SetYawRate(2.0, kNaN); }, "SetYawRate", "not finite");
    rejected([&] { dr.SetYawRate(std::numeric_limits<double>::infinity(), 0.1); }, "SetYawRate", "not finite");
    rejected([&] { dr.SetYawRate(0.5, 0.1); }, "SetYawRate", "backwards");
    rejected([&] { dr.AddWheelSpeeds(2.5, short_list); }, "AddWheelSpeeds", "for " + std::to_string(n) + " wheels");
    rejected([&] { dr.AddWheelSpeeds(2.5, nan_entry); }, "AddWheelSpeeds", "not finite");
    rejected([&] { dr.AddWheelSpeeds(kNaN, good.speed_radps); }, "AddWheelSpeeds", "not finite");
    rejected([&] { dr.AddWheelSpeeds(kStart.time_s + 0.05, good.speed_radps); }, "AddWheelSpeeds", "backwards");
    const std::vector<double> huge(n, 1e300);
    rejected([&] { dr.AddWheelSpeeds(1e300, huge); }, "AddWheelSpeeds", "not finite");

    // Equal times are allowed, and the held values are those of the good calls only.
    both([&](DeadReckoning& d) { d.SetSteering(1.0, good.steering_rad); });
    both([&](DeadReckoning& d) { d.SetYawRate(1.0, 0.2); });
    both([&](DeadReckoning& d) { d.AddWheelSpeeds(kStart.time_s + 0.1, good.speed_radps); });
    both([&](DeadReckoning& d) { d.AddWheelSpeeds(kStart.time_s + 0.7, good.speed_radps); });
    EXPECT_EQ(dr.pose().position_m, twin.pose().position_m);
    EXPECT_EQ(dr.pose().heading_rad, twin.pose().heading_rad);
    EXPECT_NE(dr.pose().position_m, kStart.position_m);
  }
}

}  // namespace
}  // namespace rowloc::sim
