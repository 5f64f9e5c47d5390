// RangeNoiseEstimator (range_noise_estimator.hpp): the echoes' range sigma from their innovations,
// robust to echoes of another surface, between the configured floor and the cap.
#include "rowloc/localization/range_noise_estimator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

namespace rowloc::localization {
namespace {

/// Feeds `count` innovations nu ~ N(0, sigma^2 + S_rest), S_rest uniform in [0, max_rest] m^2
/// (default: a prediction sigma up to 1 cm), into `estimator`.
void Feed(RangeNoiseEstimator& estimator, double sigma_m, int count, std::mt19937& rng, double max_rest = 1e-4) {
  std::uniform_real_distribution<double> rest(0.0, max_rest);
  std::normal_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < count; ++i) {
    const double other = rest(rng);
    estimator.Observe(std::sqrt(sigma_m * sigma_m + other) * unit(rng), other);
  }
}

TEST(RangeNoiseEstimator, RecoversTheRangeSigmaOfGaussianInnovations) {
  std::mt19937 rng(7);
  for (const double sigma : {0.005, 0.01, 0.02, 0.04}) {
    RangeNoiseEstimator estimator(0.003, 0.05, 2000, 50);
    Feed(estimator, sigma, 2000, rng, 1e-5);  // predictions of 3 mm or better: the filter in its lane
    // The median of 2000 chi-square samples: about 3 % on the variance, 1.5 % on sigma (1-sigma).
    EXPECT_NEAR(estimator.sigma_m(), sigma, 0.08 * sigma) << sigma;
  }
}

TEST(RangeNoiseEstimator, IsLowWhenThePredictionsSpreadWidely) {
  // The documented bias of median(nu^2) / m_1 - median(S_rest): S_rest spread over 0 to (1 cm)^2
  // against sigma_r = 5 mm gives about two thirds of it; never above it.
  std::mt19937 rng(7);
  RangeNoiseEstimator estimator(0.001, 0.05, 4000, 50);
  Feed(estimator, 0.005, 4000, rng, 1e-4);
  EXPECT_GT(estimator.sigma_m(), 0.5 * 0.005);
  EXPECT_LT(estimator.sigma_m(), 0.85 * 0.005);
}

TEST(RangeNoiseEstimator, FollowsAChangeOfCanopyWithinItsWindow) {
  std::mt19937 rng(11);
  RangeNoiseEstimator estimator(0.003, 0.05, 200, 50);
  // Predictions of 3 mm or better (the filter in its lane): a window of 200 pins sigma to ~10 %.
  Feed(estimator, 0.03, 400, rng, 1e-5);  // leafy
  EXPECT_NEAR(estimator.sigma_m(), 0.03, 0.006);
  Feed(estimator, 0.006, 200, rng, 1e-5);  // a trimmed row: the window holds only its echoes now
  EXPECT_NEAR(estimator.sigma_m(), 0.006, 0.0015);
}

TEST(RangeNoiseEstimator, StaysBetweenTheConfiguredSigmaAndTheCap) {
  std::mt19937 rng(3);
  RangeNoiseEstimator smooth(0.003, 0.05, 500, 50);
  Feed(smooth, 0.0005, 500, rng);  // smoother than the sensor's own noise: the floor
  EXPECT_EQ(smooth.sigma_m(), 0.003);
  RangeNoiseEstimator rough(0.003, 0.02, 500, 50);
  Feed(rough, 0.04, 500, rng);  // rougher than the cap
  EXPECT_EQ(rough.sigma_m(), 0.02);
}

TEST(RangeNoiseEstimator, AssumesTheCapUntilEnoughEchoesAreCounted) {
  std::mt19937 rng(5);
  RangeNoiseEstimator estimator(0.003, 0.05, 200, 50);
  EXPECT_EQ(estimator.sigma_m(), 0.05);
  Feed(estimator, 0.004, 49, rng);
  EXPECT_EQ(estimator.samples(), 49u);
  EXPECT_EQ(estimator.sigma_m(), 0.05);
  Feed(estimator, 0.004, 1, rng);
  EXPECT_LT(estimator.sigma_m(), 0.01);
}

TEST(RangeNoiseEstimator, EchoesOfAnotherSurfaceAreNotCountedAndAFewLargeOnesMoveItLittle) {
  std::mt19937 rng(13);
  RangeNoiseEstimator estimator(0.003, 0.05, 1000, 50);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> unit(0.0, 1.0);
  int counted = 0;
  for (int i = 0; i < 1000; ++i) {
    const double u = uniform(rng);
    // 30 %: the far row through a gap (1.5 m off, beyond 5 x the cap: not counted); 15 %: 0.1-0.2 m off.
    const double innovation = u < 0.3 ? 1.5 : (u < 0.45 ? 0.1 + 0.1 * uniform(rng) : 0.01 * unit(rng));
    counted += estimator.Observe(innovation, 0.0) ? 1 : 0;
  }
  EXPECT_NEAR(counted, 700, 60);
  EXPECT_EQ(estimator.samples(), static_cast<std::size_t>(counted));
  // A median over 79 % inliers: the estimate stays within a factor 1.5 of the roughness.
  EXPECT_GT(estimator.sigma_m(), 0.01);
  EXPECT_LT(estimator.sigma_m(), 0.015);
}

TEST(RangeNoiseEstimator, BadValuesAreNotCounted) {
  RangeNoiseEstimator estimator(0.003, 0.05, 200, 1);
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(estimator.Observe(std::nan(""), 0.0));
  EXPECT_FALSE(estimator.Observe(inf, 0.0));
  EXPECT_FALSE(estimator.Observe(0.01, std::nan("")));
  EXPECT_FALSE(estimator.Observe(0.01, -1e-6));
  EXPECT_FALSE(estimator.Observe(0.01, inf));
  EXPECT_EQ(estimator.samples(), 0u);
  EXPECT_EQ(estimator.sigma_m(), 0.05);
  EXPECT_TRUE(estimator.Observe(0.01, 0.0));
  EXPECT_TRUE(std::isfinite(estimator.sigma_m()));
}

TEST(RangeNoiseEstimator, AFixedOneNeverMoves) {
  RangeNoiseEstimator fixed = RangeNoiseEstimator::Fixed(0.003);
  std::mt19937 rng(1);
  Feed(fixed, 0.03, 300, rng);
  EXPECT_EQ(fixed.sigma_m(), 0.003);
  EXPECT_EQ(fixed.samples(), 0u);
}

TEST(RangeNoiseEstimator, BadSettingsAreRefused) {
  EXPECT_THROW(RangeNoiseEstimator(0.0, 0.05, 200, 50), std::invalid_argument);
  EXPECT_THROW(RangeNoiseEstimator(std::nan(""), 0.05, 200, 50), std::invalid_argument);
  EXPECT_THROW(RangeNoiseEstimator(0.003, 0.002, 200, 50), std::invalid_argument);
  EXPECT_THROW(RangeNoiseEstimator(0.003, std::numeric_limits<double>::infinity(), 200, 50), std::invalid_argument);
  EXPECT_THROW(RangeNoiseEstimator(0.003, 0.05, 40, 50), std::invalid_argument);
  EXPECT_THROW(RangeNoiseEstimator(0.003, 0.05, 200, 0), std::invalid_argument);
  EXPECT_THROW(RangeNoiseEstimator::Fixed(-1.0), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::localization
