// Wheel and steering encoder error models: tick conservation and quantization error bounds,
// exact first-order low-pass step response, noise statistics, determinism and input errors.
#include "rowloc/sim/encoder_model.hpp"

#include <gtest/gtest.h>

#include "statistical_tests.hpp"

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/normal.hpp>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

namespace rowloc::sim {
namespace {


WheelEncoderConfig RawEncoder() { return {50.0, 1024.0, 0.0, 0.0}; }

TEST(WheelEncoderModel, NoTickIsLostAndEachSampleIsWithinOneTick) {
  const WheelEncoderConfig config = RawEncoder();
  WheelEncoderModel model(config, 1);
  std::mt19937_64 truth_rng(99);
  std::uniform_real_distribution<double> rate(-20.0, 20.0);  // includes reversing
  const double ticks_per_rad = config.ticks_per_revolution / (2.0 * std::numbers::pi);
  const double dt = config.period_s();
  model.Measure(0.0, 0.0);
  double true_ticks = 0.0, error_sum = 0.0;
  const int samples = 100000;
  for (int k = 1; k <= samples; ++k) {
    const double w = rate(truth_rng);
    const WheelEncoderSample s = model.Measure(k * dt, w);
    true_ticks += w * dt * ticks_per_rad;
    const double error = s.quantized_speed_radps - w;
    ASSERT_LT(std::abs(error), 1.0 / (ticks_per_rad * dt) + 1e-9);  // one tick per interval
    ASSERT_EQ(s.speed_radps, s.quantized_speed_radps);               // no filter, no noise
    error_sum += error;
    // The cumulative count is the whole part of the true tick count (up to round-off at an edge).
    ASSERT_LE(std::abs(static_cast<double>(s.cumulative_ticks) - std::floor(true_ticks)), 1.0);
    // The reported angle is the count times the tick angle: at most one tick behind the truth.
    ASSERT_DOUBLE_EQ(s.cumulative_angle_rad, static_cast<double>(s.cumulative_ticks) / ticks_per_rad);
    ASSERT_LE(true_ticks / ticks_per_rad - s.cumulative_angle_rad, 1.0 / ticks_per_rad + 1e-9);
    ASSERT_GE(true_ticks / ticks_per_rad - s.cumulative_angle_rad, -1e-9);
  }
  // Zero mean: the errors telescope to the carried remainder, under one tick in total.
  EXPECT_LT(std::abs(error_sum), 1.0 / (ticks_per_rad * dt) + 1e-6);
}

TEST(WheelEncoderModel, SlowWheelAccumulatesFractionalTicks) {
  // 0.3 ticks per interval: counts are 0 or 1 and three of every ten intervals see a tick.
  WheelEncoderConfig config = RawEncoder();
  WheelEncoderModel model(config, 1);
  const double w = 0.3 * 2.0 * std::numbers::pi / config.ticks_per_revolution * config.rate_hz;
  model.Measure(0.0, w);
  std::int64_t last = 0;
  for (int k = 1; k <= 1000; ++k) {
    const WheelEncoderSample s = model.Measure(k * config.period_s(), w);
    ASSERT_TRUE(s.tick_count == 0 || s.tick_count == 1);
    last = s.cumulative_ticks;
  }
  EXPECT_NEAR(static_cast<double>(last), 300.0, 1.0);
}

TEST(WheelEncoderModel, LowPassStepResponseIsOneMinusExponential) {
  WheelEncoderConfig config{100.0, 1.0e6, 0.1, 0.0};
  WheelEncoderModel model(config, 2);
  const double w = 2.0;
  const double dt = config.period_s();
  const double tick_speed = 2.0 * std::numbers::pi / config.ticks_per_revolution / dt;
  model.Measure(0.0, 0.0);  // at rest until t = 0, step to w afterwards
  for (int k = 1; k <= 100; ++k) {
    const double t = k * dt;
    const WheelEncoderSample s = model.Measure(t, w);
    // The filter is a convex combination of quantized speeds, each within one tick of w.
    ASSERT_NEAR(s.speed_radps, w * (1.0 - std::exp(-t / config.low_pass_time_constant_s)), tick_speed) << t;
  }
}

TEST(WheelEncoderModel, AdditiveNoiseHasTheConfiguredSigma) {
  WheelEncoderConfig config{50.0, 1024.0, 0.0, 0.05};
  WheelEncoderModel model(config, 3);
  std::vector<double> noise;
  for (int k = 0; k < 20000; ++k) {
    const WheelEncoderSample s = model.Measure(k * config.period_s(), 5.0);
    noise.push_back(s.speed_radps - s.quantized_speed_radps);
  }
  test::ExpectZeroMeanWithSigma(noise, 0.05);
}

std::vector<double> WheelSequence(std::uint64_t seed) {
  WheelEncoderModel model({50.0, 1024.0, 0.02, 0.01}, seed);
  std::vector<double> out;
  for (int k = 0; k < 300; ++k) out.push_back(model.Measure(0.02 * k, std::sin(0.1 * k)).speed_radps);
  return out;
}

TEST(WheelEncoderModel, SameSeedGivesIdenticalSequencesAndDifferentSeedsDiffer) {
  EXPECT_EQ(WheelSequence(5), WheelSequence(5));
  EXPECT_NE(WheelSequence(5), WheelSequence(6));
}

TEST(WheelEncoderModel, RejectsBadTimeInputAndConfiguration) {
  WheelEncoderModel model(RawEncoder(), 1);
  model.Measure(1.0, 1.0);
  EXPECT_THROW(model.Measure(0.9, 1.0), std::invalid_argument);
  EXPECT_THROW(model.Measure(1.0, 1.0), std::invalid_argument);
  EXPECT_THROW(model.Measure(std::numeric_limits<double>::infinity(), 1.0), std::invalid_argument);
  EXPECT_THROW(model.Measure(1.1, std::nan("")), std::invalid_argument);
  EXPECT_NO_THROW(model.Measure(1.1, 1.0));
  EXPECT_THROW(WheelEncoderModel({50.0, 0.0, 0.0, 0.0}, 1), std::invalid_argument);
  EXPECT_THROW(WheelEncoderModel({50.0, 1024.0, -0.1, 0.0}, 1), std::invalid_argument);
  EXPECT_THROW(WheelEncoderModel({50.0, 1024.0, 0.0, -0.1}, 1), std::invalid_argument);
  EXPECT_THROW(WheelEncoderModel({0.0, 1024.0, 0.0, 0.0}, 1), std::invalid_argument);
}

TEST(SteeringEncoderModel, QuantizationErrorIsBoundedUniformAndZeroMean) {
  const double step = 0.0015;
  SteeringEncoderModel model({50.0, step, 0.0}, 1);
  std::mt19937_64 truth_rng(17);
  std::uniform_real_distribution<double> angle(-0.6, 0.6);
  std::vector<double> errors;
  for (int k = 0; k < 20000; ++k) {
    const double truth = angle(truth_rng);
    const double measured = model.Measure(0.02 * k, truth).angle_rad;
    ASSERT_NEAR(measured / step, std::round(measured / step), 1e-9);  // a whole number of steps
    ASSERT_LE(std::abs(measured - truth), step / 2.0 + 1e-12);
    errors.push_back(measured - truth);
  }
  test::ExpectZeroMeanWithSigma(errors, step / std::sqrt(12.0));  // uniform on [-step/2, step/2]
}

TEST(SteeringEncoderModel, NoiseHasTheConfiguredSigma) {
  SteeringEncoderModel model({50.0, 0.0, 0.002}, 2);
  std::vector<double> errors;
  for (int k = 0; k < 20000; ++k) errors.push_back(model.Measure(0.02 * k, 0.3).angle_rad - 0.3);
  test::ExpectZeroMeanWithSigma(errors, 0.002);
}

TEST(SteeringEncoderModel, SameSeedSameSequenceAndBadInputRejected) {
  const auto sequence = [](std::uint64_t seed) {
    SteeringEncoderModel model({50.0, 0.001, 0.003}, seed);
    std::vector<double> out;
    for (int k = 0; k < 200; ++k) out.push_back(model.Measure(0.02 * k, 0.01 * k).angle_rad);
    return out;
  };
  EXPECT_EQ(sequence(1), sequence(1));
  EXPECT_NE(sequence(1), sequence(2));
  SteeringEncoderModel model({50.0, 0.001, 0.0}, 1);
  model.Measure(0.5, 0.0);
  EXPECT_THROW(model.Measure(0.4, 0.0), std::invalid_argument);
  EXPECT_THROW(model.Measure(std::nan(""), 0.0), std::invalid_argument);
  EXPECT_THROW(model.Measure(0.6, std::numeric_limits<double>::infinity()), std::invalid_argument);
  EXPECT_THROW(SteeringEncoderModel({50.0, -0.001, 0.0}, 1), std::invalid_argument);
  EXPECT_THROW(SteeringEncoderModel({50.0, 0.001, -1.0}, 1), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::sim
