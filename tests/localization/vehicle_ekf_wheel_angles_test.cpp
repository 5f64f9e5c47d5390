// VehicleEkf with wheel-angle measurements (FilterConfig wheels.angle_measurement,
// wheel_angle_model.hpp): accuracy on synthetic drives of every vehicle, anchoring, the fallback to
// speeds, re-anchoring after a gated-out update, input checks, and P staying symmetric positive
// definite over randomized steps.
#include "rowloc/localization/wheel_angle_model.hpp"
#include "vehicle_ekf_test_support.hpp"

namespace rowloc::localization {
namespace {

FilterConfig AngleConfig(bool slip_aware) {
  FilterConfig config;
  config.slip_aware_odometry.enabled = slip_aware;
  config.wheels.angle_measurement = true;
  // MakeDrive's wheel speeds carry 0.01 rad/s of white noise per 0.01 s sample: integrated, a rate
  // noise of 1e-3 rad/s/sqrt(Hz).
  config.wheels.angle_rate_noise_radps_per_sqrt_hz = 1e-3;
  return config;
}

void ExpectConvergedWithAngles(const VehicleConfig& v, bool slip_aware) {
  SCOPED_TRACE(v.name + (slip_aware ? " slip-aware" : ""));
  Drive d = MakeDrive(v, {{-5.0, 2.0}, 0.4}, StraightThenCircle(), 0.0, 3, slip_aware);
  AddWheelAngles(d);
  VehicleEkf ekf(v, AngleConfig(slip_aware), kOrigin, WheelNames(v));
  ASSERT_TRUE(ekf.layout().has_wheel_angles());
  std::size_t angle_updates = 0, speed_updates = 0, speed_updates_after_angles = 0;
  const WorstErrors worst = ReplayDrive(ekf, d, 8.0, [&](const ProcessResult& r) {
    for (const UpdateRecord& u : r.updates) {
      angle_updates += u.sensor == "wheel_angles";
      speed_updates += u.sensor == "wheels";
      speed_updates_after_angles += u.sensor == "wheels" && angle_updates > 0;
    }
  });
  EXPECT_GT(angle_updates, 3500u);
  // Every message carries angles: speeds only at the start, until the wheel rates are known
  // (wheels.angle_max_prediction_sigma_rad).
  EXPECT_GE(speed_updates, 1u);
  EXPECT_LE(speed_updates, 5u);
  EXPECT_EQ(speed_updates_after_angles, 0u);
  EXPECT_LT(worst.position_m, 0.05);
  EXPECT_LT(worst.heading_rad, kPi / 180);
  EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(ekf.covariance()).info(), Eigen::Success);
}

TEST(VehicleEkfWheelAngles, SyntheticStraightAndCircleEveryVehicle) {
  ExpectConvergedWithAngles(mapio::AgrimaroSwerveConfig(), false);
  ExpectConvergedWithAngles(mapio::AgrimaroSwerveConfig(), true);
  ExpectConvergedWithAngles(mapio::VineyardUgv4wsConfig(), false);
  ExpectConvergedWithAngles(mapio::DifferentialDriveConfig(), true);
  ExpectConvergedWithAngles(mapio::TrackedVehicleConfig(), false);
}

/// A filter initialised at rest by SetPose, and the wheel speeds of a straight drive. Its wheel
/// rates are unknown (velocity sigma 0.3 m/s), so with the default angle_max_prediction_sigma_rad
/// the first messages would be used as speeds; the tests of anchoring and gating lift that limit
/// (max_prediction_sigma_rad), and UntilTheRatesAreKnownTheSpeedsAreUsed tests it.
struct Rolling {
  explicit Rolling(double max_prediction_sigma_rad = 1.0)
      : ekf(v, Config(max_prediction_sigma_rad), kOrigin, WheelNames(v)) {
    ekf.SetPose(0.0, {0.0, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-4);
  }
  static FilterConfig Config(double max_prediction_sigma_rad) {
    FilterConfig config = AngleConfig(false);
    config.wheels.angle_max_prediction_sigma_rad = max_prediction_sigma_rad;
    return config;
  }
  VehicleConfig v = mapio::DifferentialDriveConfig();
  VehicleEkf ekf;
  formats::WheelsMessage Wheels(double t, double angle_rad) const {
    const double speed = 1.0 / v.wheels[0].nominal_radius_m;
    return {t, {speed, speed}, std::nullopt, std::vector<double>{angle_rad, angle_rad}};
  }
};

TEST(VehicleEkfWheelAngles, TheFirstAnglesAnchorTheStatesAndTheNextOnesUpdate) {
  Rolling r;
  const StateLayout& layout = r.ekf.layout();
  ProcessResult first = r.ekf.Process(r.Wheels(0.02, 123.0));
  for (const UpdateRecord& u : first.updates) EXPECT_NE(u.sensor, "wheel_angles");  // anchored, not updated
  for (const int k : layout.wheel_angle) {
    EXPECT_EQ(r.ekf.state()(k), 123.0);
    EXPECT_DOUBLE_EQ(r.ekf.covariance()(k, k), r.ekf.config().wheels.angle_sigma_rad * r.ekf.config().wheels.angle_sigma_rad);
    EXPECT_EQ(r.ekf.covariance().row(k).cwiseAbs().sum(), r.ekf.covariance()(k, k));  // uncorrelated
  }
  const ProcessResult second = r.ekf.Process(r.Wheels(0.04, 123.0 + 0.02 / r.v.wheels[0].nominal_radius_m));
  ASSERT_FALSE(second.updates.empty());
  EXPECT_EQ(second.updates.front().sensor, "wheel_angles");
  EXPECT_TRUE(second.updates.front().outcome.accepted);
  // A reset forgets the anchor: after the next initialisation the first angles anchor again.
  r.ekf.Reset();
  r.ekf.SetPose(1.0, {0.0, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-4);
  first = r.ekf.Process(r.Wheels(1.02, -7.0));
  for (const UpdateRecord& u : first.updates) EXPECT_NE(u.sensor, "wheel_angles");
  EXPECT_EQ(r.ekf.state()(layout.wheel_angle[0]), -7.0);
}

// wheels.angle_max_prediction_sigma_rad: right after initialisation a predicted angle is uncertain
// by far more than a tick (the velocity's 0.3 m/s over 0.02 s), so the message's speeds update the
// filter and the angles are re-anchored to it; once the speeds have pinned the rates, the angles.
TEST(VehicleEkfWheelAngles, UntilTheRatesAreKnownTheSpeedsAreUsed) {
  Rolling r(FilterConfig{}.wheels.angle_max_prediction_sigma_rad);
  const StateLayout& layout = r.ekf.layout();
  const double step = 0.02 / r.v.wheels[0].nominal_radius_m;  // rad per message at 1 m/s
  r.ekf.Process(r.Wheels(0.02, 0.0));                          // anchors
  const ProcessResult second = r.ekf.Process(r.Wheels(0.04, step));
  ASSERT_FALSE(second.updates.empty());
  EXPECT_EQ(second.updates.front().sensor, "wheels");
  const double variance = r.ekf.config().wheels.angle_sigma_rad * r.ekf.config().wheels.angle_sigma_rad;
  for (const int k : layout.wheel_angle) {
    EXPECT_EQ(r.ekf.state()(k), step);  // re-anchored to this message
    EXPECT_DOUBLE_EQ(r.ekf.covariance()(k, k), variance);
    EXPECT_EQ(r.ekf.covariance().row(k).cwiseAbs().sum(), r.ekf.covariance()(k, k));
  }
  const ProcessResult third = r.ekf.Process(r.Wheels(0.06, 2.0 * step));
  ASSERT_FALSE(third.updates.empty());
  EXPECT_EQ(third.updates.front().sensor, "wheel_angles");
  EXPECT_TRUE(third.updates.front().outcome.accepted);
  // Without the limit the second message already updates with its angles.
  Rolling unlimited;
  unlimited.ekf.Process(unlimited.Wheels(0.02, 0.0));
  EXPECT_EQ(unlimited.ekf.Process(unlimited.Wheels(0.04, step)).updates.front().sensor, "wheel_angles");
}

TEST(VehicleEkfWheelAngles, AMessageWithoutAnglesIsUsedAsSpeeds) {
  Rolling r;
  r.ekf.Process(r.Wheels(0.02, 0.0));
  formats::WheelsMessage speeds_only = r.Wheels(0.04, 0.0);
  speeds_only.angle_rad.reset();
  const ProcessResult result = r.ekf.Process(speeds_only);
  ASSERT_FALSE(result.updates.empty());
  EXPECT_EQ(result.updates.front().sensor, "wheels");
}

// At rest the angles stop changing and their quantization error is frozen: a bias, not noise. No
// wheel ticking since the last message: the speeds are used; the angles again once a wheel ticks.
TEST(VehicleEkfWheelAngles, AtRestTheSpeedsAreUsed) {
  Rolling r;
  r.ekf.Process(r.Wheels(0.02, 5.0));
  formats::WheelsMessage still = r.Wheels(0.04, 5.0);
  still.speed_radps = {0.0, 0.0};
  ProcessResult result = r.ekf.Process(still);
  ASSERT_FALSE(result.updates.empty());
  EXPECT_EQ(result.updates.front().sensor, "wheels");
  still.time_s = 0.06;
  result = r.ekf.Process(still);
  EXPECT_EQ(result.updates.front().sensor, "wheels");
  formats::WheelsMessage one_tick = still;
  one_tick.time_s = 0.08;
  (*one_tick.angle_rad)[1] += kTickRad;  // one wheel ticks
  result = r.ekf.Process(one_tick);
  EXPECT_EQ(result.updates.front().sensor, "wheel_angles");
}

TEST(VehicleEkfWheelAngles, AGatedOutUpdateReanchorsAndSaysSo) {
  Rolling r;
  const StateLayout& layout = r.ekf.layout();
  r.ekf.Process(r.Wheels(0.02, 10.0));
  const ProcessResult jump = r.ekf.Process(r.Wheels(0.04, 60.0));  // 50 rad in 0.02 s: a counter glitch
  ASSERT_FALSE(jump.updates.empty());
  EXPECT_EQ(jump.updates.front().sensor, "wheel_angles");
  EXPECT_FALSE(jump.updates.front().outcome.accepted);
  ASSERT_TRUE(jump.notice.has_value());
  EXPECT_THAT(*jump.notice, HasSubstr("re-anchored"));
  for (const int k : layout.wheel_angle) EXPECT_EQ(r.ekf.state()(k), 60.0);
  EXPECT_LT(std::abs(r.ekf.state()(StateLayout::kVx)), 2.0);  // accepted, the glitch would mean 400 m/s
  const ProcessResult next = r.ekf.Process(r.Wheels(0.06, 60.0 + 0.02 / r.v.wheels[0].nominal_radius_m));
  EXPECT_TRUE(next.updates.front().outcome.accepted);
}

TEST(VehicleEkfWheelAngles, BadAnglesAreRejected) {
  Rolling r;
  formats::WheelsMessage bad = r.Wheels(0.02, 1.0);
  bad.angle_rad->back() = kNaN;
  ExpectRejected(r.ekf, bad, "angle_rad", "NaN angle");
  bad.angle_rad = std::vector<double>{1.0};
  ExpectRejected(r.ekf, bad, "wheel angles", "one angle for two wheels");
}

TEST(VehicleEkfWheelAngles, LayoutNamesTheAngleStatesLast) {
  const VehicleConfig v = mapio::AgrimaroSwerveConfig();
  const VehicleEkf ekf(v, AngleConfig(true), kOrigin, WheelNames(v));
  const StateLayout& layout = ekf.layout();
  const std::vector<std::string> names = layout.Names(v);
  ASSERT_EQ(layout.size, 20 + 3);  // the slip-aware swerve layout + one angle per wheel
  for (std::size_t i = 0; i < v.wheels.size(); ++i) {
    EXPECT_EQ(layout.wheel_angle[i], 20 + static_cast<int>(i));
    EXPECT_EQ(names[static_cast<std::size_t>(layout.wheel_angle[i])], "theta_" + v.wheels[i].name);
  }
  EXPECT_FALSE(MakeEkf(v, true).layout().has_wheel_angles());
}

// P stays symmetric positive definite with angle updates, valid and hostile (counter jumps), torques
// (measuring the traction states, with steps) and accelerations, over randomized time steps.
TEST(VehicleEkfWheelAngles, CovarianceStaysSymmetricPositiveDefinite) {
  const VehicleConfig v = mapio::AgrimaroSwerveConfig();
  FilterConfig config = AngleConfig(true);
  config.slip_aware_odometry.torque_sigma_nm = 0.05;  // and the traction states (wheel-angles.json)
  VehicleEkf ekf(v, config, kOrigin, WheelNames(v));
  ASSERT_TRUE(ekf.layout().has_traction());
  const Segment drive{0.0, 1.0, 0.2, 0.1};
  ekf.SetPose(0.0, {0.0, 0.0, 0.0}, Eigen::Vector3d(0.01, 0.01, 0.01).asDiagonal());
  std::mt19937_64 rng(20261202);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::normal_distribution<double> n01;
  std::vector<double> rolled(v.wheels.size(), 0.0);
  long accepted = 0, gated = 0;
  for (long step = 0; step < 20000; ++step) {
    const double t = ekf.time_s() + (u01(rng) < 0.05 ? 0.2 * u01(rng) : 0.02 * u01(rng));
    Readings exact = Exact(v, drive, t);
    const bool hostile = u01(rng) < 0.1;
    formats::SensorMessage m;
    if (u01(rng) < 0.4) {
      exact.imu.accel_x_mps2 += 0.02 * n01(rng);
      exact.imu.gyro_z_radps += 0.002 * n01(rng);
      m = exact.imu;
    } else {
      std::vector<double> angles;
      for (std::size_t i = 0; i < rolled.size(); ++i) {
        rolled[i] = exact.wheels.speed_radps[i] * t;
        angles.push_back(rolled[i] + (hostile ? 100.0 * n01(rng) : kTickRad * u01(rng)));
      }
      exact.wheels.angle_rad = angles;
      if (u01(rng) < 0.5) exact.wheels.torque_nm = std::vector<double>(v.wheels.size(), hostile ? 500.0 : 5.0 * u01(rng));
      m = exact.wheels;
    }
    const ProcessResult r = ekf.Process(m);
    for (const auto& u : r.updates) ++(u.outcome.accepted ? accepted : gated);
    const Eigen::MatrixXd& p = ekf.covariance();
    ASSERT_TRUE((p.array() == p.transpose().array()).all()) << "step " << step;
    if (step % 100 == 99) {
      ASSERT_TRUE(ekf.state().allFinite() && p.allFinite()) << "step " << step;
      const Eigen::VectorXd d = p.diagonal().cwiseSqrt().cwiseInverse();
      const Eigen::MatrixXd c = d.asDiagonal() * p * d.asDiagonal();
      ASSERT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(c, Eigen::EigenvaluesOnly).eigenvalues()(0), 0.0)
          << "step " << step;
    }
  }
  EXPECT_GT(accepted, 10000);
  EXPECT_GT(gated, 100);
}

}  // namespace
}  // namespace rowloc::localization
