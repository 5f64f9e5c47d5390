// GnssBiasModel (gnss_bias_model.hpp) on its own: the bias columns of the GNSS measurement, the
// initial variance and the fix's correlation, the exact Gauss-Markov step (decay, stationary
// variance, independence of the step split), PredictStep using it, and a layout without the states.
#include "rowloc/localization/gnss_bias_model.hpp"

#include "rowloc/localization/process_model.hpp"
#include "rowloc/mapio/vehicle_config.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace rowloc::localization {
namespace {

using L = StateLayout;

GpsNoise BiasNoise() {
  GpsNoise gps;
  gps.estimate_bias = true;
  gps.bias_sigma_m = 0.5;
  gps.bias_time_constant_s = 4.0;
  return gps;
}

struct Biased {
  mapio::VehicleConfig v = mapio::VineyardUgv4wsConfig();
  StateLayout layout = StateLayout::For(v, {.slip_aware_odometry = true, .gnss_bias = true});
  StateLayout plain = StateLayout::For(v, {.slip_aware_odometry = true});
  GnssBiasModel model{BiasNoise(), layout};
  int b = layout.gnss_bias;
  /// A state with every entry set and a full positive-definite covariance.
  Eigen::VectorXd State() const { return Eigen::VectorXd::LinSpaced(layout.size, 0.1, 2.0); }
  Eigen::MatrixXd Covariance() const {
    Eigen::MatrixXd a(layout.size, layout.size);
    for (int i = 0; i < layout.size; ++i) {
      for (int j = 0; j < layout.size; ++j) a(i, j) = std::sin(7.0 * i + 3.0 * j + 1.0);
    }
    const Eigen::MatrixXd p = a * a.transpose() + Eigen::MatrixXd::Identity(layout.size, layout.size);
    return 0.5 * (p + p.transpose());  // exactly symmetric
  }
};

TEST(GnssBiasModel, TheFixMeasuresTheAntennaPlusTheBias) {
  Biased s;
  ASSERT_TRUE(s.model.estimated());
  ASSERT_EQ(s.model.index(), s.layout.size - 2);
  const Eigen::Vector2d arm(0.4, -0.2);
  Eigen::VectorXd x = s.State();
  x(s.b) = 0.3;
  x(s.b + 1) = -0.7;
  LinearizedMeasurement with;
  s.model.MeasureAntenna(x, arm, with);
  const LinearizedMeasurement without = GpsAntennaModel(x, arm, -1);
  ASSERT_EQ(with.jacobian.rows(), 2);
  ASSERT_EQ(with.jacobian.cols(), s.layout.size);
  EXPECT_NEAR(with.predicted(0), without.predicted(0) + 0.3, 1e-12);
  EXPECT_NEAR(with.predicted(1), without.predicted(1) - 0.7, 1e-12);
  // The bias columns are the identity; every other column is the antenna's.
  EXPECT_EQ(with.jacobian(0, s.b), 1.0);
  EXPECT_EQ(with.jacobian(1, s.b + 1), 1.0);
  EXPECT_EQ(with.jacobian(0, s.b + 1), 0.0);
  EXPECT_EQ(with.jacobian(1, s.b), 0.0);
  EXPECT_EQ(with.jacobian.leftCols(s.b), without.jacobian.leftCols(s.b));
  EXPECT_EQ(without.jacobian.rightCols<2>(), Eigen::Matrix2d::Zero());
}

TEST(GnssBiasModel, TheBiasStartsAtZeroWithItsStationaryVariance) {
  Biased s;
  EXPECT_DOUBLE_EQ(s.model.StationaryVariance(), 0.25);
  Eigen::VectorXd x = s.State();
  Eigen::MatrixXd p = Eigen::MatrixXd::Zero(s.layout.size, s.layout.size);
  p.topLeftCorner<3, 3>() = Eigen::Vector3d(0.04, 0.09, 0.01).asDiagonal();
  s.model.Initialise(x, p, /*position_from_gnss=*/false);
  EXPECT_EQ(x.segment<2>(s.b), Eigen::Vector2d::Zero());
  EXPECT_EQ(x(0), s.State()(0));  // the other states untouched
  EXPECT_EQ(p(s.b, s.b), 0.25);
  EXPECT_EQ(p(s.b + 1, s.b + 1), 0.25);
  EXPECT_EQ(p(s.b, s.b + 1), 0.0);
  EXPECT_EQ(p(L::kX, L::kX), 0.04);  // a position set otherwise does not carry the bias
  EXPECT_EQ(p.block(0, s.b, 3, 2), Eigen::MatrixXd::Zero(3, 2));
}

TEST(GnssBiasModel, APositionFromAFixIsTheFixMinusTheBias) {
  Biased s;
  Eigen::VectorXd x = s.State();
  Eigen::MatrixXd p = Eigen::MatrixXd::Zero(s.layout.size, s.layout.size);
  p.topLeftCorner<3, 3>() = Eigen::Vector3d(0.04, 0.09, 0.01).asDiagonal();
  s.model.Initialise(x, p, /*position_from_gnss=*/true);
  EXPECT_EQ(p(L::kX, L::kX), 0.04 + 0.25);
  EXPECT_EQ(p(L::kY, L::kY), 0.09 + 0.25);
  EXPECT_EQ(p(L::kX, s.b), -0.25);
  EXPECT_EQ(p(L::kY, s.b + 1), -0.25);
  EXPECT_EQ(p(L::kX, s.b + 1), 0.0);
  EXPECT_EQ(p(L::kPhi, s.b), 0.0);
  EXPECT_EQ(p, p.transpose());
  // x + b, what the fix measured, keeps the fix's own variance.
  Eigen::RowVectorXd antenna_x = Eigen::RowVectorXd::Zero(s.layout.size);
  antenna_x(L::kX) = antenna_x(s.b) = 1.0;
  EXPECT_NEAR((antenna_x * p * antenna_x.transpose())(0, 0), 0.04, 1e-15);
}

TEST(GnssBiasModel, ThePredictionIsAnExactGaussMarkovStep) {
  Biased s;
  const double dt = 0.5, a = std::exp(-dt / 4.0);
  EXPECT_DOUBLE_EQ(s.model.Decay(dt), a);
  EXPECT_EQ(s.model.Transition(dt), a * Eigen::Matrix2d::Identity());
  Eigen::VectorXd x = s.State();
  const Eigen::MatrixXd p0 = s.Covariance();
  Eigen::MatrixXd p = p0;
  s.model.Propagate(x, p, dt);
  EXPECT_NEAR(x(s.b), a * s.State()(s.b), 1e-15);
  EXPECT_NEAR(x(s.b + 1), a * s.State()(s.b + 1), 1e-15);
  EXPECT_EQ(x.head(s.b), s.State().head(s.b));  // the other states untouched
  const double added = 0.25 * (1.0 - a * a);
  EXPECT_NEAR(p(s.b, s.b), a * a * p0(s.b, s.b) + added, 1e-12);
  EXPECT_NEAR(p(s.b, s.b + 1), a * a * p0(s.b, s.b + 1), 1e-12);
  EXPECT_NEAR(p(L::kX, s.b), a * p0(L::kX, s.b), 1e-12);  // cross-covariances decay with the bias
  EXPECT_EQ(p.topLeftCorner(s.b, s.b), p0.topLeftCorner(s.b, s.b));
  EXPECT_EQ(p, p.transpose());
}

TEST(GnssBiasModel, TheStationaryVarianceStaysWhateverTheStepSplit) {
  Biased s;
  Eigen::MatrixXd one = Eigen::MatrixXd::Identity(s.layout.size, s.layout.size);
  one.bottomRightCorner<2, 2>() *= 0.25;  // stationary
  Eigen::MatrixXd many = one;
  Eigen::VectorXd x1 = s.State(), x2 = s.State();
  s.model.Propagate(x1, one, 2.0);
  for (int k = 0; k < 40; ++k) s.model.Propagate(x2, many, 0.05);
  EXPECT_NEAR(one(s.b, s.b), 0.25, 1e-15);
  EXPECT_NEAR(many(s.b + 1, s.b + 1), 0.25, 1e-14);
  EXPECT_NEAR(x1(s.b), x2(s.b), 1e-14);
  EXPECT_NEAR(x1(s.b), std::exp(-0.5) * s.State()(s.b), 1e-14);
  // From a known bias (variance 0) the variance grows to sigma^2 (1 - a^2).
  Eigen::MatrixXd known = Eigen::MatrixXd::Identity(s.layout.size, s.layout.size);
  known.bottomRightCorner<2, 2>().setZero();
  s.model.Propagate(x1, known, 4.0);
  EXPECT_NEAR(known(s.b, s.b), 0.25 * (1.0 - std::exp(-2.0)), 1e-15);
}

TEST(GnssBiasModel, PredictStepPropagatesTheBiasWithIt) {
  Biased s;
  FilterConfig config;
  config.gps = BiasNoise();
  Eigen::VectorXd x = s.State(), x_bias = s.State();
  Eigen::MatrixXd p = s.Covariance(), p_bias = p;
  PredictStep(s.v, s.layout, config, x, p, 0.02);
  s.model.Propagate(x_bias, p_bias, 0.02);
  EXPECT_EQ(x.tail<2>(), x_bias.tail<2>());
  EXPECT_EQ(p(s.b, s.b), p_bias(s.b, s.b));
  EXPECT_EQ(GnssBiasDecay(s.layout, config.gps, 0.02), s.model.Decay(0.02));
}

TEST(GnssBiasModel, WithoutBiasStatesNothingChanges) {
  Biased s;
  const GnssBiasModel none(BiasNoise(), s.plain);
  EXPECT_FALSE(none.estimated());
  EXPECT_EQ(none.index(), -1);
  EXPECT_EQ(none.Decay(3.0), 1.0);
  Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(s.plain.size, 0.1, 2.0);
  const Eigen::VectorXd x0 = x;
  Eigen::MatrixXd p = Eigen::MatrixXd::Identity(s.plain.size, s.plain.size);
  none.Propagate(x, p, 3.0);
  none.Initialise(x, p, true);
  EXPECT_EQ(x, x0);
  EXPECT_EQ(p, Eigen::MatrixXd::Identity(s.plain.size, s.plain.size));
  LinearizedMeasurement h;
  none.MeasureAntenna(x, Eigen::Vector2d(0.4, -0.2), h);
  EXPECT_EQ(h.jacobian.cols(), s.plain.size);
  EXPECT_EQ(h.predicted, GpsAntennaModel(x, Eigen::Vector2d(0.4, -0.2), -1).predicted);
}

}  // namespace
}  // namespace rowloc::localization
