// IMU error model: white-noise sigma from the density, bias random walk variance linear in time
// (chi-square tests), irregular sampling, determinism and input errors.
#include "rowloc/sim/imu_model.hpp"

#include <gtest/gtest.h>

#include "statistical_tests.hpp"

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/normal.hpp>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace rowloc::sim {
namespace {


ImuConfig WhiteOnlyConfig() {
  ImuConfig c;
  c.rate_hz = 200.0;
  c.accel_x = {0.002, 0.0, 0.1};
  c.accel_y = {0.003, 0.0, -0.2};
  c.gyro_z = {0.0002, 0.0, 0.01};
  return c;
}

TEST(ImuModel, WhiteNoiseSigmaIsDensityTimesRootRate) {
  const ImuConfig config = WhiteOnlyConfig();
  ImuModel model(config, 5);
  const ImuTruth truth{0.5, -0.25, 0.1};
  std::vector<double> ax, ay, gz;
  for (int k = 0; k < 20000; ++k) {
    const ImuSample s = model.Measure(k * config.period_s(), truth);
    ASSERT_EQ(s.bias.accel_x_mps2, 0.1);  // no random walk configured: the bias stays put
    ax.push_back(s.accel_x_mps2 - truth.accel_x_mps2 - s.bias.accel_x_mps2);
    ay.push_back(s.accel_y_mps2 - truth.accel_y_mps2 - s.bias.accel_y_mps2);
    gz.push_back(s.gyro_z_radps - truth.gyro_z_radps - s.bias.gyro_z_radps);
  }
  EXPECT_DOUBLE_EQ(config.SampleSigma(config.accel_x), 0.002 * std::sqrt(200.0));
  test::ExpectZeroMeanWithSigma(ax, 0.002 * std::sqrt(200.0));
  test::ExpectZeroMeanWithSigma(ay, 0.003 * std::sqrt(200.0));
  test::ExpectZeroMeanWithSigma(gz, 0.0002 * std::sqrt(200.0));
}

ImuConfig WalkConfig() {
  ImuConfig c;
  c.rate_hz = 100.0;
  c.accel_x = {0.002, 0.0004, 0.02};
  c.accel_y = {0.002, 0.0008, 0.0};
  c.gyro_z = {0.0002, 0.00002, 0.0};
  return c;
}

struct Series {
  std::vector<double> bias_x, bias_gz, meas_x;
};

Series RunImu(const ImuConfig& config, int samples, std::uint64_t seed) {
  ImuModel model(config, seed);
  Series series;
  for (int k = 0; k < samples; ++k) {
    const ImuSample s = model.Measure(k * config.period_s(), ImuTruth{});
    series.bias_x.push_back(s.bias.accel_x_mps2);
    series.bias_gz.push_back(s.bias.gyro_z_radps);
    series.meas_x.push_back(s.accel_x_mps2);
  }
  return series;
}

/// Non-overlapping increments x[i + lag] - x[i] (independent for a random walk plus white noise).
std::vector<double> Increments(const std::vector<double>& x, std::size_t lag) {
  std::vector<double> out;
  for (std::size_t i = 0; i + lag < x.size(); i += lag) out.push_back(x[i + lag] - x[i]);
  return out;
}

TEST(ImuModel, BiasRandomWalkVarianceGrowsLinearlyInTime) {
  const ImuConfig config = WalkConfig();
  const Series series = RunImu(config, 400000, 6);
  EXPECT_EQ(series.bias_x.front(), 0.02);  // the first sample sees the initial bias
  const double dt = config.period_s();
  for (const std::size_t lag : {1u, 10u, 100u}) {
    // Var[b(t + L dt) - b(t)] = K^2 L dt.
    test::ExpectZeroMeanWithSigma(Increments(series.bias_x, lag), 0.0004 * std::sqrt(lag * dt));
    test::ExpectZeroMeanWithSigma(Increments(series.bias_gz, lag), 0.00002 * std::sqrt(lag * dt));
  }
}

TEST(ImuModel, MeasurementIncrementsCombineWalkAndWhiteNoise) {
  // Allan-style check on the measurement alone: Var[y(t + L dt) - y(t)] = K^2 L dt + 2 sigma_d^2.
  // A strong walk (K = 0.02 m/s^2/sqrt(s)) so that both terms matter: at lag 100 (1 s) they are
  // comparable, at lag 2000 (20 s) the walk dominates.
  ImuConfig config = WalkConfig();
  config.accel_x.bias_random_walk = 0.02;
  const Series series = RunImu(config, 400000, 7);
  const double sigma_d = config.SampleSigma(config.accel_x);
  for (const std::size_t lag : {1u, 100u, 2000u}) {
    const double variance = 0.02 * 0.02 * lag * config.period_s() + 2.0 * sigma_d * sigma_d;
    test::ExpectZeroMeanWithSigma(Increments(series.meas_x, lag), std::sqrt(variance));
  }
}

TEST(ImuModel, BiasWalkIsExactForIrregularSampling) {
  ImuConfig config = WalkConfig();
  ImuModel model(config, 8);
  std::vector<double> normalised;
  double t = 0.0, previous_bias = 0.0;
  for (int k = 0; k < 20000; ++k) {
    const double dt = 0.001 + 0.05 * ((k * 37) % 11) / 10.0;  // 1 ms .. 51 ms, deterministic
    t += dt;
    const double bias = model.Measure(t, ImuTruth{}).bias.accel_y_mps2;
    if (k > 0) normalised.push_back((bias - previous_bias) / std::sqrt(dt));
    previous_bias = bias;
  }
  test::ExpectZeroMeanWithSigma(normalised, 0.0008);
}

std::vector<double> Sequence(std::uint64_t seed) {
  const Series s = RunImu(WalkConfig(), 300, seed);
  std::vector<double> out = s.meas_x;
  out.insert(out.end(), s.bias_gz.begin(), s.bias_gz.end());
  return out;
}

TEST(ImuModel, SameSeedGivesIdenticalSequencesAndDifferentSeedsDiffer) {
  EXPECT_EQ(Sequence(3), Sequence(3));
  EXPECT_NE(Sequence(3), Sequence(4));
}

TEST(ImuModel, RejectsTimeGoingBackwardsOrRepeatedOrNonFinite) {
  ImuModel model(WalkConfig(), 1);
  model.Measure(2.0, ImuTruth{});
  EXPECT_THROW(model.Measure(1.0, ImuTruth{}), std::invalid_argument);
  EXPECT_THROW(model.Measure(2.0, ImuTruth{}), std::invalid_argument);
  EXPECT_THROW(model.Measure(std::numeric_limits<double>::quiet_NaN(), ImuTruth{}), std::invalid_argument);
  EXPECT_THROW(model.Measure(2.1, ImuTruth{std::nan(""), 0.0, 0.0}), std::invalid_argument);
  EXPECT_THROW(model.Measure(2.1, ImuTruth{0.0, 0.0, std::numeric_limits<double>::infinity()}),
               std::invalid_argument);
  EXPECT_NO_THROW(model.Measure(2.1, ImuTruth{}));
}

TEST(ImuModel, RejectsInvalidConfiguration) {
  const auto rejects = [](auto mutate) {
    ImuConfig c = WalkConfig();
    mutate(c);
    EXPECT_THROW(ImuModel(c, 1), std::invalid_argument);
  };
  rejects([](ImuConfig& c) { c.rate_hz = -100.0; });
  rejects([](ImuConfig& c) { c.accel_x.noise_density = -0.1; });
  rejects([](ImuConfig& c) { c.accel_y.bias_random_walk = -1e-4; });
  rejects([](ImuConfig& c) { c.gyro_z.initial_bias = std::nan(""); });
}

}  // namespace
}  // namespace rowloc::sim
