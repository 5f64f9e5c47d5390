// VehicleEkf with the GNSS-bias states (gps.estimate_bias; state_layout.hpp, process_model.hpp):
// the initial correlation of a position taken from a fix, the consistency of the position when the
// fixes carry a Gauss-Markov error (with and without the bias states), SetPose leaving the bias
// alone, and the smoother recording the bias's transition and the iterated wheel update.
#include "vehicle_ekf_test_support.hpp"

namespace rowloc::localization {
namespace {

using L = StateLayout;

FilterConfig BiasConfig(bool estimate_bias) {
  FilterConfig config;
  config.gps.estimate_bias = estimate_bias;
  config.gps.bias_sigma_m = 1.0;
  config.gps.bias_time_constant_s = 10.0;
  return config;
}

/// The drive's fixes replaced by the truth plus a first-order Gauss-Markov error (sigma 1 m, tau
/// 10 s, exact discretization) plus white noise of white_sigma_m, reported with that sigma.
void AddGaussMarkovFixErrors(const VehicleConfig& v, Drive& d, unsigned seed, double white_sigma_m) {
  const mapio::LocalFrame frame(kOrigin);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  Eigen::Vector2d bias(n01(rng), n01(rng));  // stationary from the start
  double previous_t = 0.0;
  std::size_t fix = 0;
  for (formats::SensorMessage& m : d.messages) {
    auto* gps = std::get_if<formats::GpsMessage>(&m);
    if (!gps) continue;
    const double a = std::exp(-(gps->time_s - previous_t) / 10.0);
    bias = a * bias + std::sqrt(1.0 - a * a) * Eigen::Vector2d(n01(rng), n01(rng));
    previous_t = gps->time_s;
    const Pose& pose = d.truth.at(fix++).pose;
    const Eigen::Vector2d antenna = pose.p + Rotate(pose.phi, v.gnss_antenna.position_m.head<2>());
    m = Fix(frame, gps->time_s, antenna + bias + white_sigma_m * Eigen::Vector2d(n01(rng), n01(rng)), white_sigma_m);
  }
}

/// Mean 2-dof position NEES at the fixes from from_s on (the state right after each fix).
double MeanPositionNees(VehicleEkf& ekf, const Drive& d, double from_s) {
  double sum = 0.0;
  int count = 0;
  std::size_t fix = 0;
  for (const formats::SensorMessage& m : d.messages) {
    ekf.Process(m);
    if (!std::holds_alternative<formats::GpsMessage>(m)) continue;
    const Sample& truth = d.truth.at(fix++);
    if (!ekf.initialised() || truth.t < from_s) continue;
    const Eigen::Vector2d e = ekf.state().head<2>() - truth.pose.p;
    sum += e.dot(ekf.covariance().topLeftCorner<2, 2>().llt().solve(e));
    ++count;
  }
  EXPECT_GT(count, 100);
  return sum / std::max(count, 1);
}

TEST(VehicleEkfGnssBias, APositionFromAFixCarriesTheBias) {
  const VehicleConfig v = mapio::VineyardUgv4wsConfig();
  const FilterConfig config = BiasConfig(true);
  VehicleEkf ekf(v, config, kOrigin, WheelNames(v));
  const Drive d = MakeDrive(v, {{0.0, 0.0}, 0.0}, {{10.0, 1.0, 0.0, 0.0}});
  for (const formats::SensorMessage& m : d.messages) {
    ekf.Process(m);
    if (ekf.initialised()) break;
  }
  ASSERT_TRUE(ekf.initialised());
  const int b = ekf.layout().gnss_bias;
  ASSERT_EQ(b, ekf.layout().size - 2);
  const Eigen::MatrixXd& p = ekf.covariance();
  EXPECT_EQ(ekf.state().segment<2>(b), Eigen::Vector2d::Zero());
  EXPECT_EQ(p(b, b), 1.0);
  EXPECT_EQ(p(b + 1, b + 1), 1.0);
  EXPECT_EQ(p(L::kX, b), -1.0);  // x = z - b
  EXPECT_EQ(p(L::kY, b + 1), -1.0);
  EXPECT_EQ(p(L::kX, b + 1), 0.0);
  // The fix's own variance (1 cm) plus the bias's.
  EXPECT_NEAR(p(L::kX, L::kX), 1.0 + 0.01 * 0.01, 1e-12);
  EXPECT_EQ(p, p.transpose());
  EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(p).info(), Eigen::Success);
  // The fix's position is x + b: its variance is the fix's alone.
  Eigen::RowVectorXd h = Eigen::RowVectorXd::Zero(p.cols());
  h(L::kX) = h(b) = 1.0;
  EXPECT_NEAR(h * p * h.transpose(), 0.01 * 0.01, 1e-12);
}

TEST(VehicleEkfGnssBias, PositionStaysConsistentWhenTheFixErrorIsCorrelated) {
  // Five drives of 120 s (straight, then a circle) whose fixes carry a 1 m error correlated over
  // 10 s on top of 0.3 m of white noise. Taken as white, 0.3 m at 10 Hz averages down to a few
  // centimetres while the error stays near 1 m: the filter is far overconfident. The bias states
  // describe that error, and the 2-dof NEES is near its expected value 2.
  const VehicleConfig v = mapio::VineyardUgv4wsConfig();
  double with_bias = 0.0, without = 0.0;
  constexpr int kDrives = 5;
  for (unsigned seed = 1; seed <= kDrives; ++seed) {
    Drive d = MakeDrive(v, {{0.0, 0.0}, 0.0}, {{60.0, 1.0, 0.0, 0.0}, {60.0, 1.0, 0.0, 0.1}}, 0.0, seed);
    AddGaussMarkovFixErrors(v, d, 100 + seed, 0.3);
    VehicleEkf biased(v, BiasConfig(true), kOrigin, WheelNames(v));
    VehicleEkf white(v, BiasConfig(false), kOrigin, WheelNames(v));
    with_bias += MeanPositionNees(biased, d, 10.0) / kDrives;
    without += MeanPositionNees(white, d, 10.0) / kDrives;
  }
  EXPECT_GT(with_bias, 1.3);  // 2.05 measured
  EXPECT_LT(with_bias, 3.0);
  EXPECT_GT(without, 10.0 * with_bias) << "with the bias states " << with_bias;  // 2041 measured
}

TEST(VehicleEkfGnssBias, SetPoseLeavesTheBiasButNotItsCorrelationWithThePose) {
  const VehicleConfig v = mapio::VineyardUgv4wsConfig();
  VehicleEkf ekf(v, BiasConfig(true), kOrigin, WheelNames(v));
  Drive d = MakeDrive(v, {{0.0, 0.0}, 0.0}, {{20.0, 1.0, 0.0, 0.0}});
  AddGaussMarkovFixErrors(v, d, 7, 0.3);
  for (const formats::SensorMessage& m : d.messages) ekf.Process(m);
  const int b = ekf.layout().gnss_bias;
  const Eigen::Vector2d bias = ekf.state().segment<2>(b);
  EXPECT_GT(bias.norm(), 0.0);
  const Eigen::Matrix2d bias_covariance = ekf.covariance().block<2, 2>(b, b);
  ekf.SetPose(ekf.time_s(), Eigen::Vector3d(20.0, 0.0, 0.0), Eigen::Vector3d(0.01, 0.01, 1e-4).asDiagonal());
  EXPECT_EQ(ekf.state().segment<2>(b), bias);
  const Eigen::Matrix2d bias_covariance_after = ekf.covariance().block<2, 2>(b, b);
  EXPECT_EQ(bias_covariance_after, bias_covariance);
  EXPECT_EQ(ekf.covariance().middleCols<2>(b).topRows<3>().cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(ekf.covariance()).info(), Eigen::Success);
}

TEST(VehicleEkfGnssBias, TheSmootherRecordsTheBiasDecayAndTheIteratedWheelUpdate) {
  // A transition the filter made without recording it shows as negative implied process noise
  // (fixed_interval_smoother.hpp); the bias decays at every prediction step. The iterated wheel
  // update (canopy-gnss.json's other part) restarts from the prior inside one node.
  const VehicleConfig v = mapio::VineyardUgv4wsConfig();
  for (const int iterations : {1, 3}) {
    SCOPED_TRACE(iterations);
    FilterConfig config = BiasConfig(true);
    config.wheels.speed_update_iterations = iterations;
    config.slip_aware_odometry.rolling_radius_prior_wheel_correlation = 0.99;
    VehicleEkf ekf(v, config, kOrigin, WheelNames(v));
    Drive d = MakeDrive(v, {{0.0, 0.0}, 0.0}, {{10.0, 1.0, 0.0, 0.0}, {10.0, 1.0, 0.0, 0.2}});
    AddGaussMarkovFixErrors(v, d, 3, 0.3);
    ekf.EnableSmoothing(/*check_transitions=*/true);
    double next_mark_s = 0.0;
    for (const formats::SensorMessage& m : d.messages) {
      ekf.Process(m);
      if (ekf.initialised() && ekf.time_s() >= next_mark_s) {
        ekf.MarkForSmoothing();
        next_mark_s = ekf.time_s() + 0.5;
      }
    }
    EXPECT_GT(ekf.smoother()->min_relative_process_noise(), -1e-9);
    const std::vector<SmoothedState> smoothed = ekf.FinishSmoothing();
    ASSERT_GT(smoothed.size(), 30u);
    for (const SmoothedState& s : smoothed) {
      EXPECT_TRUE(s.state.allFinite());
      EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(s.covariance).info(), Eigen::Success);
    }
  }
}

}  // namespace
}  // namespace rowloc::localization
