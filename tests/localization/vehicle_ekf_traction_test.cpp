// VehicleEkf with traction states (slip_aware_odometry.torque_sigma_nm > 0): the torques are a
// measurement of mu = T / (N r) instead of an exact input (errors in variables,
// docs/notes/2026-12-02-localization-filter.md §5.5): initialisation from the last torques, the `torque` update,
// the re-anchoring on a torque step, and the default without them.
#include "vehicle_ekf_test_support.hpp"

namespace rowloc::localization {
namespace {

FilterConfig TractionConfig() {
  FilterConfig config;
  config.slip_aware_odometry.torque_sigma_nm = 0.05;  // traction_noise_per_sqrt_s: the default, 1e-4
  return config;
}

struct Driving {
  VehicleConfig v = mapio::DifferentialDriveConfig();
  VehicleEkf ekf{v, TractionConfig(), kOrigin, WheelNames(v)};
  formats::WheelsMessage Wheels(double t, double torque_nm) const {
    const double speed = 0.5 / v.wheels[0].nominal_radius_m;
    return {t, {speed, speed}, std::vector<double>{torque_nm, torque_nm}, std::nullopt};
  }
};

TEST(VehicleEkfTraction, TheLayoutHasOneTractionStatePerWheelOnlyWithATorqueNoise) {
  Driving d;
  const StateLayout& layout = d.ekf.layout();
  ASSERT_TRUE(layout.has_traction());
  const std::vector<std::string> names = layout.Names(d.v);
  for (std::size_t i = 0; i < d.v.wheels.size(); ++i) {
    EXPECT_EQ(names[static_cast<std::size_t>(layout.traction[i])], "mu_" + d.v.wheels[i].name);
  }
  EXPECT_EQ(layout.size, StateLayout::For(d.v, {.slip_aware_odometry = true, .accel_bias = true}).size + 2);
  EXPECT_FALSE(MakeEkf(d.v, true).layout().has_traction());  // the default: torques taken as exact
  FilterConfig no_slip = TractionConfig();
  no_slip.slip_aware_odometry.enabled = false;  // mu only matters to the slip-aware model
  EXPECT_FALSE(VehicleEkf(d.v, no_slip, kOrigin, WheelNames(d.v)).layout().has_traction());
}

TEST(VehicleEkfTraction, InitialisedFromTheLastTorquesThenUpdatedByThem) {
  Driving d;
  d.ekf.Process(d.Wheels(0.0, 4.0));  // before initialisation: remembered
  d.ekf.SetPose(0.01, {0.0, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-4);
  const StateLayout& layout = d.ekf.layout();
  const double scale = WheelTractionScaleNm(d.v, 0);
  EXPECT_DOUBLE_EQ(d.ekf.state()(layout.traction[0]), 4.0 / scale);
  EXPECT_DOUBLE_EQ(d.ekf.covariance()(layout.traction[0], layout.traction[0]), (0.05 / scale) * (0.05 / scale));
  // A torque within its noise: a `torque` update, accepted, mu moves towards it and its variance shrinks.
  const double before_variance = d.ekf.covariance()(layout.traction[0], layout.traction[0]);
  const ProcessResult r = d.ekf.Process(d.Wheels(0.02, 4.05));
  ASSERT_FALSE(r.updates.empty());
  EXPECT_EQ(r.updates.front().sensor, "torque");
  EXPECT_TRUE(r.updates.front().outcome.accepted);
  const double mu = d.ekf.state()(layout.traction[0]);
  EXPECT_GT(mu, 4.0 / scale);
  EXPECT_LT(mu, 4.05 / scale);
  EXPECT_LT(d.ekf.covariance()(layout.traction[0], layout.traction[0]), before_variance);
}

TEST(VehicleEkfTraction, ATorqueStepReanchorsTheTractionStates) {
  Driving d;
  d.ekf.Process(d.Wheels(0.0, 4.0));
  d.ekf.SetPose(0.01, {0.0, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-4);
  const StateLayout& layout = d.ekf.layout();
  const ProcessResult step = d.ekf.Process(d.Wheels(0.02, 2.0));  // the drive halves its torque
  ASSERT_FALSE(step.updates.empty());
  EXPECT_EQ(step.updates.front().sensor, "torque");
  EXPECT_FALSE(step.updates.front().outcome.accepted);
  const double scale = WheelTractionScaleNm(d.v, 0);
  for (std::size_t i = 0; i < d.v.wheels.size(); ++i) {
    const int k = layout.traction[i];
    EXPECT_DOUBLE_EQ(d.ekf.state()(k), 2.0 / scale);
    double off_diagonal = 0.0;
    for (Eigen::Index j = 0; j < layout.size; ++j) off_diagonal += j == k ? 0.0 : std::abs(d.ekf.covariance()(k, j));
    EXPECT_EQ(off_diagonal, 0.0);
  }
  EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(d.ekf.covariance().bottomRightCorner(layout.size - 3, layout.size - 3)).info(),
            Eigen::Success);
}

// The torque noise as a measurement of mu removes the errors-in-variables pull of noisy torques on
// kappa: with torques scattered around a constant (the speeds do not follow their noise), kappa
// stays near its prior instead of drifting towards 0.
TEST(VehicleEkfTraction, NoisyTorquesNoLongerPullKappaDown) {
  const VehicleConfig v = mapio::DifferentialDriveConfig();
  std::mt19937_64 rng(4);
  std::normal_distribution<double> n01;
  const auto kappa_after = [&](const FilterConfig& config) {
    VehicleEkf ekf(v, config, kOrigin, WheelNames(v));
    ekf.SetPose(0.0, {0.0, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-6);
    rng.seed(4);
    const double scale = WheelTractionScaleNm(v, 0), mu = 0.1, kappa = 1.0;
    const double speed = 0.5 / (v.wheels[0].nominal_radius_m * (1.0 - kappa * mu));  // the prior's kappa
    for (int k = 1; k <= 5000; ++k) {
      const double t = 0.02 * k;
      const mapio::LocalFrame frame(kOrigin);
      if (k % 5 == 0) ekf.Process(Fix(frame, t, {0.5 * t + v.gnss_antenna.position_m.x(), 0.0}, 0.01));
      const double torque = mu * scale + 0.05 * n01(rng);
      const std::vector<double> torques{torque, torque + 0.05 * n01(rng)};
      ekf.Process(formats::WheelsMessage{t, {speed, speed}, torques, std::nullopt});
    }
    return ekf.state()(ekf.layout().slip_compliance[0]);
  };
  FilterConfig exact;  // torques taken as exact
  const double pulled = kappa_after(exact);
  const double kept = kappa_after(TractionConfig());
  EXPECT_LT(pulled, 0.8);  // measured: the errors-in-variables drift
  EXPECT_GT(kept, 0.9);
  EXPECT_LT(kept, 1.1);
}

}  // namespace
}  // namespace rowloc::localization
