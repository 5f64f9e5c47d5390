// The iterated wheel-speed update (wheels.speed_update_iterations; filter_config.hpp;
// docs/notes/2026-12-02-localization-filter.md §5.9): it reaches the Gauss-Newton fixed point of the update, which
// the one-step EKF update of the ratio omega = v / (R_w (1 - kappa mu)) does not, and changes the
// track little where the linearization is good.
#include "vehicle_ekf_test_support.hpp"

namespace rowloc::localization {
namespace {

/// One wheels message at the pose's time (no prediction) into a filter just set at rest, from
/// wheels that turn at 5 rad/s: a large innovation of the ratio model. Returns (x0, P0) before the
/// message, the state and covariance after, and the message. The non-holonomic update that follows
/// every wheels message is made negligible (sigma 1e6 m/s).
struct OneUpdate {
  Eigen::VectorXd x0, x;
  Eigen::MatrixXd p0, p;
  Eigen::VectorXd z;
  Eigen::MatrixXd noise;
};

OneUpdate UpdateFromRest(int iterations, const VehicleConfig& v, FilterConfig& config) {
  config.wheels.speed_update_iterations = iterations;
  config.wheels.lateral_velocity_sigma_mps = 1e6;
  VehicleEkf ekf(v, config, kOrigin, WheelNames(v));
  ekf.SetPose(1.0, {0.0, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-4);
  OneUpdate u{ekf.state(), {}, ekf.covariance(), {}, {}, {}};
  const std::vector<double> speeds(v.wheels.size(), 5.0);
  ekf.Process(formats::WheelsMessage{1.0, speeds, std::nullopt, std::nullopt});
  u.x = ekf.state();
  u.p = ekf.covariance();
  u.z = Eigen::Map<const Eigen::VectorXd>(speeds.data(), static_cast<Eigen::Index>(speeds.size()));
  const double s = config.wheels.speed_sigma_radps, f = config.wheels.speed_sigma_fraction;
  u.noise = (s * s + (f * u.z.array()).square()).matrix().asDiagonal();
  return u;
}

/// How far x is from the iterated EKF's fixed point (the Gauss-Newton condition of the MAP
/// estimate): x - x0 - K (z - h(x) - H (x0 - x)), with H and K at x; and P against (I - K H) P0.
std::pair<double, double> FixedPointResidual(const OneUpdate& u, const VehicleConfig& v, const FilterConfig& config) {
  const StateLayout layout =
      StateLayout::For(v, {.slip_aware_odometry = true, .accel_bias = config.imu.estimate_accel_bias});
  const LinearizedMeasurement h = WheelSpeedModel(u.x, v, layout, std::nullopt, 0.0, true);
  const Eigen::MatrixXd s = h.jacobian * u.p0 * h.jacobian.transpose() + u.noise;
  const Eigen::MatrixXd k = u.p0 * h.jacobian.transpose() * s.inverse();
  const Eigen::VectorXd step = u.x - u.x0 - k * (u.z - h.predicted - h.jacobian * (u.x0 - u.x));
  const Eigen::MatrixXd p = (Eigen::MatrixXd::Identity(u.p0.rows(), u.p0.cols()) - k * h.jacobian) * u.p0;
  return {step.cwiseAbs().maxCoeff(), (u.p - p).cwiseAbs().maxCoeff() / u.p0.cwiseAbs().maxCoeff()};
}

TEST(VehicleEkfIteratedWheels, IterationsConvergeToTheGaussNewtonFixedPoint) {
  for (const VehicleConfig& v : {mapio::DifferentialDriveConfig(), mapio::VineyardUgv4wsConfig()}) {
    SCOPED_TRACE(v.name);
    FilterConfig config;
    // The EKF update (one linearization at x0) is far from the fixed point: the ratio is far from
    // linear over this step (v from 0 to about 1.2 m/s). Each iteration comes closer (Gauss-Newton
    // converges linearly here, by a factor 0.03-0.4 per iteration).
    double previous_step = 0.0, previous_p = 0.0, first_step = 0.0, first_p = 0.0;
    for (const int n : {1, 2, 3, 5, 10}) {
      const OneUpdate u = UpdateFromRest(n, v, config);
      const auto [step, p] = FixedPointResidual(u, v, config);
      EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(u.p).info(), Eigen::Success) << n;
      EXPECT_EQ(u.p, u.p.transpose()) << n;
      if (n == 1) {
        EXPECT_GT(step, 0.1);
        EXPECT_GT(p, 0.01);
        first_step = step, first_p = p;
      } else {
        EXPECT_LT(step, previous_step) << n;
      }
      previous_step = step, previous_p = p;
    }
    EXPECT_LT(previous_step, 1e-3 * first_step);  // after 10 iterations
    EXPECT_LT(previous_p, 1e-2 * first_p);
  }
}

TEST(VehicleEkfIteratedWheels, OnNearExactReadingsTheIterationsChangeTheTrackByMillimetres) {
  // Where the linearization is good (1 cm fixes, small innovations) the iterations change little:
  // the same drive ends elsewhere, but within 5 mm of the EKF's track.
  const VehicleConfig v = mapio::VineyardUgv4wsConfig();
  FilterConfig config;
  ASSERT_EQ(config.wheels.speed_update_iterations, 1);  // the default is the EKF update
  const Drive d = MakeDrive(v, {{0.0, 0.0}, 0.0}, StraightThenCircle(), 0.0, 4);
  VehicleEkf ekf(v, config, kOrigin, WheelNames(v));
  config.wheels.speed_update_iterations = 3;
  VehicleEkf iterated(v, config, kOrigin, WheelNames(v));
  double max_difference_m = 0.0;
  for (const formats::SensorMessage& m : d.messages) {
    ekf.Process(m);
    iterated.Process(m);
    if (ekf.initialised()) {
      max_difference_m = std::max(max_difference_m, (iterated.state().head<2>() - ekf.state().head<2>()).norm());
    }
  }
  EXPECT_GT(max_difference_m, 0.0);
  EXPECT_LT(max_difference_m, 0.005);
  EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(iterated.covariance()).info(), Eigen::Success);
}

}  // namespace
}  // namespace rowloc::localization
