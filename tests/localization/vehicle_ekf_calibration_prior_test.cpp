// VehicleEkf::SetWheelCalibrationPrior: R_w and kappa priors from a previous drive replace the
// filter file's at initialisation (with the file's kappa correlation); bad priors are refused.
#include "vehicle_ekf_test_support.hpp"

namespace rowloc::localization {
namespace {

std::vector<WheelCalibrationPrior> PriorFor(const VehicleConfig& v) {
  std::vector<WheelCalibrationPrior> prior;
  double k = 0.5;
  for (const auto& w : v.wheels) {
    prior.push_back({w.name, 1.02 * w.nominal_radius_m, 5e-4, k, 0.1});
    k += 0.1;
  }
  return prior;
}

TEST(VehicleEkfCalibrationPrior, ReplacesTheFilterFilesPriorAtInitialisation) {
  const VehicleConfig v = mapio::AgrimaroSwerveConfig();
  FilterConfig config;
  config.slip_aware_odometry.enabled = true;
  config.slip_aware_odometry.slip_compliance_wheel_correlation = 0.9;
  config.slip_aware_odometry.carried_rolling_radius_change_sigma_m = 0.0;  // the carried sigmas as they are
  config.slip_aware_odometry.carried_slip_compliance_change_sigma = 0.0;
  VehicleEkf ekf(v, config, kOrigin, WheelNames(v));
  std::vector<WheelCalibrationPrior> prior = PriorFor(v);
  std::reverse(prior.begin(), prior.end());  // any order: matched by name
  ekf.SetWheelCalibrationPrior(prior);
  ekf.SetPose(0.0, {0.0, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-4);
  const StateLayout& l = ekf.layout();
  const std::vector<WheelCalibrationPrior> expected = PriorFor(v);
  for (std::size_t i = 0; i < v.wheels.size(); ++i) {
    EXPECT_EQ(ekf.state()(l.rolling_radius[i]), expected[i].rolling_radius_m);
    EXPECT_EQ(ekf.state()(l.slip_compliance[i]), expected[i].slip_compliance);
    EXPECT_DOUBLE_EQ(ekf.covariance()(l.rolling_radius[i], l.rolling_radius[i]), 25e-8);
    EXPECT_DOUBLE_EQ(ekf.covariance()(l.slip_compliance[i], l.slip_compliance[i]), 0.01);
    for (std::size_t j = 0; j < v.wheels.size(); ++j) {
      if (i != j) {
        EXPECT_DOUBLE_EQ(ekf.covariance()(l.slip_compliance[i], l.slip_compliance[j]), 0.9 * 0.1 * 0.1);
      }
    }
  }
  // A re-initialisation (Reset, then SetPose) uses it again.
  ekf.Reset();
  ekf.SetPose(1.0, {0.0, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-4);
  EXPECT_EQ(ekf.state()(l.rolling_radius[0]), expected[0].rolling_radius_m);
  // Without a prior: the nominal radius.
  VehicleEkf plain(v, config, kOrigin, WheelNames(v));
  plain.SetPose(0.0, {0.0, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-4);
  EXPECT_EQ(plain.state()(l.rolling_radius[0]), v.wheels[0].nominal_radius_m);
}

// slip_aware_odometry.carried_*_change_sigma*: what may have changed since the previous drive
// widens the carried sigmas in quadrature; the kappas and radii keep the file's correlations at the
// wider sigmas.
TEST(VehicleEkfCalibrationPrior, TheChangeBetweenDrivesWidensTheCarriedSigmas) {
  const VehicleConfig v = mapio::AgrimaroSwerveConfig();
  FilterConfig config;
  config.slip_aware_odometry.slip_compliance_wheel_correlation = 0.9;
  config.slip_aware_odometry.rolling_radius_prior_wheel_correlation = 0.8;
  config.slip_aware_odometry.carried_rolling_radius_change_sigma_m = 1.2e-3;
  config.slip_aware_odometry.carried_slip_compliance_change_sigma = 0.3;
  VehicleEkf ekf(v, config, kOrigin, WheelNames(v));
  ekf.SetWheelCalibrationPrior(PriorFor(v));
  ekf.SetPose(0.0, {0.0, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-4);
  const StateLayout& l = ekf.layout();
  const std::vector<WheelCalibrationPrior> prior = PriorFor(v);
  const double radius_variance = 5e-4 * 5e-4 + 1.2e-3 * 1.2e-3;
  const double kappa_variance = 0.1 * 0.1 + 0.3 * 0.3;
  for (std::size_t i = 0; i < v.wheels.size(); ++i) {
    EXPECT_EQ(ekf.state()(l.rolling_radius[i]), prior[i].rolling_radius_m);  // the values are kept
    EXPECT_EQ(ekf.state()(l.slip_compliance[i]), prior[i].slip_compliance);
    EXPECT_NEAR(ekf.covariance()(l.rolling_radius[i], l.rolling_radius[i]), radius_variance, 1e-18);
    EXPECT_NEAR(ekf.covariance()(l.slip_compliance[i], l.slip_compliance[i]), kappa_variance, 1e-15);
    for (std::size_t j = 0; j < v.wheels.size(); ++j) {
      if (i != j) {
        EXPECT_NEAR(ekf.covariance()(l.slip_compliance[i], l.slip_compliance[j]), 0.9 * kappa_variance, 1e-15);
        EXPECT_NEAR(ekf.covariance()(l.rolling_radius[i], l.rolling_radius[j]), 0.8 * radius_variance, 1e-18);
      }
    }
  }
  // Without a carried calibration the change is not used: the file's own prior.
  VehicleEkf plain(v, config, kOrigin, WheelNames(v));
  plain.SetPose(0.0, {0.0, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-4);
  const double file_sigma = config.slip_aware_odometry.rolling_radius_sigma_m;
  EXPECT_DOUBLE_EQ(plain.covariance()(l.rolling_radius[0], l.rolling_radius[0]), file_sigma * file_sigma);
}

TEST(VehicleEkfCalibrationPrior, BadPriorsAreRefused) {
  const VehicleConfig v = mapio::DifferentialDriveConfig();
  VehicleEkf ekf = MakeEkf(v, true);
  const auto refused = [&](std::vector<WheelCalibrationPrior> prior, const std::string& reason) {
    try {
      ekf.SetWheelCalibrationPrior(prior);
      ADD_FAILURE() << "accepted: " << reason;
    } catch (const std::invalid_argument& e) {
      EXPECT_THAT(e.what(), HasSubstr(reason));
    }
  };
  const std::vector<WheelCalibrationPrior> good = PriorFor(v);
  refused({good[0]}, "no entry for '" + v.wheels[1].name + "'");
  refused({good[0], good[0]}, "appears twice");
  refused({good[0], {"spare", 0.16, 1e-3, 1.0, 0.1}}, "'spare' is not a wheel");
  for (const auto& [field, value] : std::vector<std::pair<int, double>>{{0, 0.0}, {1, 0.0}, {2, -0.1}, {3, 0.0}, {0, kNaN}, {3, kInf}}) {
    std::vector<WheelCalibrationPrior> bad = good;
    double* numbers[] = {&bad[1].rolling_radius_m, &bad[1].rolling_radius_sigma_m, &bad[1].slip_compliance,
                         &bad[1].slip_compliance_sigma};
    *numbers[field] = value;
    refused(bad, "wheel calibration prior of '" + v.wheels[1].name + "'");
  }
  VehicleEkf no_slip = MakeEkf(v, false);
  EXPECT_THROW(no_slip.SetWheelCalibrationPrior(good), std::invalid_argument);
  // A refused prior leaves the filter's own: the nominal radius.
  ekf.SetPose(0.0, {0.0, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-4);
  EXPECT_EQ(ekf.state()(ekf.layout().rolling_radius[0]), v.wheels[0].nominal_radius_m);
}

}  // namespace
}  // namespace rowloc::localization
