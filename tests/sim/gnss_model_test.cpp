// GNSS error model: noise statistics (chi-square), canopy law, Markov dropouts and multipath,
// determinism and input errors.
#include "rowloc/sim/gnss_model.hpp"

#include <gtest/gtest.h>

#include "statistical_tests.hpp"

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/normal.hpp>

#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace rowloc::sim {
namespace {

constexpr double kAlpha = test::kStatisticalAlpha;

/// Pearson chi-square goodness of fit of samples to N(0, sigma^2) with equiprobable bins.
void ExpectNormalFit(const std::vector<double>& samples, double sigma) {
  constexpr int kBins = 20;
  const boost::math::normal normal(0.0, sigma);
  std::array<double, kBins> counts{};
  for (double s : samples) {
    const int bin = static_cast<int>(boost::math::cdf(normal, s) * kBins);
    counts[static_cast<std::size_t>(std::min(bin, kBins - 1))] += 1.0;
  }
  const double expected = static_cast<double>(samples.size()) / kBins;
  double statistic = 0.0;
  for (double c : counts) statistic += (c - expected) * (c - expected) / expected;
  EXPECT_LT(statistic, boost::math::quantile(boost::math::chi_squared(kBins - 1), 1.0 - kAlpha));
}

GnssConfig NoFaultConfig() {
  GnssConfig c;
  c.rate_hz = 10.0;
  c.sigma_horizontal_m = 0.6;
  c.sigma_vertical_m = 1.0;
  c.canopy_sigma_gain = 4.0;
  c.nominal_fix = formats::GnssFixQuality::kSbas;
  c.dropout = {0.0, 0.0, 1.0};
  c.multipath = {0.0, 0.0, 1.0};
  return c;
}

struct Errors {
  std::vector<double> east, north, up;
};

Errors CollectErrors(const GnssConfig& config, double canopy, int epochs, std::uint64_t seed) {
  GnssModel model(config, seed);
  const Eigen::Vector3d truth(100.0, -50.0, 3.0);
  Errors errors;
  for (int k = 0; k < epochs; ++k) {
    const GnssSample s = model.Measure(k * config.period_s(), truth, canopy);
    EXPECT_TRUE(s.has_fix);
    const Eigen::Vector3d e = s.position_m - truth;
    errors.east.push_back(e.x());
    errors.north.push_back(e.y());
    errors.up.push_back(e.z());
  }
  return errors;
}

TEST(GnssModel, NoiseVariancePerAxisMatchesConfiguration) {
  const GnssConfig config = NoFaultConfig();
  const Errors errors = CollectErrors(config, 0.0, 20000, 11);
  test::ExpectZeroMeanWithSigma(errors.east, config.sigma_horizontal_m);
  test::ExpectZeroMeanWithSigma(errors.north, config.sigma_horizontal_m);
  test::ExpectZeroMeanWithSigma(errors.up, config.sigma_vertical_m);
  ExpectNormalFit(errors.east, config.sigma_horizontal_m);
  ExpectNormalFit(errors.north, config.sigma_horizontal_m);
}

TEST(GnssModel, RtkNoiseVarianceMatchesOneCentimetre) {
  GnssConfig config = NoFaultConfig();
  config.sigma_horizontal_m = 0.01;
  config.sigma_vertical_m = 0.0;
  const Errors errors = CollectErrors(config, 0.0, 20000, 12);
  test::ExpectZeroMeanWithSigma(errors.east, 0.01);
  test::ExpectZeroMeanWithSigma(errors.north, 0.01);
  for (double up : errors.up) ASSERT_EQ(up, 0.0);  // no vertical noise configured
}

TEST(GnssModel, CanopyInflatesSigmaByTheDocumentedLaw) {
  const GnssConfig config = NoFaultConfig();
  const double canopy = 0.5;
  const double sigma = config.sigma_horizontal_m * (1.0 + config.canopy_sigma_gain * canopy);
  GnssModel model(config, 3);
  EXPECT_DOUBLE_EQ(model.Measure(0.0, Eigen::Vector3d::Zero(), canopy).sigma_horizontal_m, sigma);
  const Errors errors = CollectErrors(config, canopy, 20000, 13);
  test::ExpectZeroMeanWithSigma(errors.east, sigma);
  test::ExpectZeroMeanWithSigma(errors.up, config.sigma_vertical_m * (1.0 + config.canopy_sigma_gain * canopy));
}

struct RunStats {
  double occupancy = 0.0;
  double mean_run_epochs = 0.0;
  double runs = 0.0;
};

/// Fraction of epochs with the flag set, and mean length (epochs) of the completed runs.
template <typename Flag>
RunStats MeasureRuns(GnssModel& model, double canopy, int epochs, Flag flag) {
  RunStats stats;
  int current = 0;
  double total_run = 0.0;
  for (int k = 0; k < epochs; ++k) {
    const GnssSample s = model.Measure(k * model.config().period_s(), Eigen::Vector3d::Zero(), canopy);
    if (flag(s)) {
      ++current;
      stats.occupancy += 1.0 / epochs;
    } else if (current > 0) {
      total_run += current;
      stats.runs += 1.0;
      current = 0;
    }
  }
  stats.mean_run_epochs = total_run / stats.runs;
  return stats;
}

/// Checks occupancy and run length against the exact two-state chain with rates a, b at step dt.
void ExpectMarkovStatistics(const RunStats& stats, double a, double b, double dt, int epochs) {
  const MarkovStep step = ExactMarkovStep(a, b, dt);
  const double z = boost::math::quantile(boost::math::normal(), 1.0 - kAlpha / 2.0);
  // Occupancy: stationary pi = a / (a + b); the epochs are correlated with lag-one coefficient
  // lambda = 1 - p_onset - p_recovery, which inflates the variance of the mean by (1+lambda)/(1-lambda).
  const double pi = a / (a + b);
  EXPECT_NEAR(step.p_onset / (step.p_onset + step.p_recovery), pi, 1e-12);
  const double lambda = 1.0 - step.p_onset - step.p_recovery;
  const double occupancy_sd = std::sqrt(pi * (1.0 - pi) / epochs * (1.0 + lambda) / (1.0 - lambda));
  EXPECT_NEAR(stats.occupancy, pi, z * occupancy_sd);
  // Run lengths are i.i.d. geometric with mean 1/p and standard deviation sqrt(1-p)/p.
  const double p = step.p_recovery;
  ASSERT_GT(stats.runs, 100.0);
  EXPECT_NEAR(stats.mean_run_epochs, 1.0 / p, z * std::sqrt(1.0 - p) / p / std::sqrt(stats.runs));
  // In seconds the mean sampled outage dt/p tends to 1/b as dt -> 0 (here within 5 %).
  EXPECT_NEAR(dt / p, 1.0 / b, 0.05 / b);
}

TEST(GnssModel, DropoutsFollowTheMarkovChainInTheOpen) {
  GnssConfig config = NoFaultConfig();
  config.dropout = {0.2, 1.0, 2.0};
  GnssModel model(config, 21);
  const int epochs = 200000;
  const RunStats stats = MeasureRuns(model, 0.0, epochs, [](const GnssSample& s) { return s.faults.dropout; });
  ExpectMarkovStatistics(stats, 0.2, 0.5, config.period_s(), epochs);
}

TEST(GnssModel, DropoutOnsetRateRisesWithCanopy) {
  GnssConfig config = NoFaultConfig();
  config.dropout = {0.01, 0.3, 2.0};
  GnssModel model(config, 22);
  const int epochs = 200000;
  const double canopy = 0.8;
  const RunStats stats = MeasureRuns(model, canopy, epochs, [](const GnssSample& s) { return !s.has_fix; });
  ExpectMarkovStatistics(stats, 0.01 + (0.3 - 0.01) * canopy, 0.5, config.period_s(), epochs);
}

TEST(GnssModel, DropoutEpochsReportNoFix) {
  GnssConfig config = NoFaultConfig();
  config.dropout = {0.5, 0.5, 1.0};
  GnssModel model(config, 23);
  int dropouts = 0;
  for (int k = 0; k < 1000; ++k) {
    const GnssSample s = model.Measure(0.1 * k, Eigen::Vector3d(1.0, 2.0, 3.0), 0.0);
    EXPECT_EQ(s.has_fix, !s.faults.dropout);
    EXPECT_EQ(s.fix, s.has_fix ? formats::GnssFixQuality::kSbas : formats::GnssFixQuality::kNone);
    dropouts += s.faults.dropout ? 1 : 0;
  }
  EXPECT_GT(dropouts, 0);
}

TEST(GnssModel, MultipathAddsAConstantBoundedOffsetPerEpisode) {
  GnssConfig config = NoFaultConfig();
  config.sigma_horizontal_m = 0.0;
  config.sigma_vertical_m = 0.0;
  config.multipath = {0.1, 0.1, 3.0};
  config.multipath_offset_min_m = 0.5;
  config.multipath_offset_max_m = 2.0;
  GnssModel model(config, 31);
  const Eigen::Vector3d truth(5.0, 6.0, 7.0);
  Eigen::Vector2d previous = Eigen::Vector2d::Zero();
  bool previous_active = false;
  int episodes = 0;
  for (int k = 0; k < 50000; ++k) {
    const GnssSample s = model.Measure(0.1 * k, truth, 0.3);
    const Eigen::Vector2d offset = (s.position_m - truth).head<2>();
    ASSERT_TRUE(offset.isApprox(s.faults.multipath_offset_m, 1e-12) || offset.norm() < 1e-12);
    ASSERT_EQ(s.position_m.z(), truth.z());
    if (s.faults.multipath) {
      ASSERT_GE(offset.norm(), 0.5 - 1e-12);
      ASSERT_LE(offset.norm(), 2.0 + 1e-12);
      if (previous_active) {
        ASSERT_EQ(offset, previous);  // constant during an episode
      }
      episodes += previous_active ? 0 : 1;
    } else {
      ASSERT_EQ(offset.norm(), 0.0);
    }
    previous = offset;
    previous_active = s.faults.multipath;
  }
  EXPECT_GT(episodes, 100);
}

TEST(GnssModel, MultipathFollowsTheMarkovChain) {
  GnssConfig config = NoFaultConfig();
  config.multipath = {0.05, 0.25, 4.0};
  config.multipath_offset_min_m = 1.0;
  config.multipath_offset_max_m = 1.0;
  GnssModel model(config, 32);
  const int epochs = 200000;
  const double canopy = 0.5;
  const RunStats stats = MeasureRuns(model, canopy, epochs, [](const GnssSample& s) { return s.faults.multipath; });
  ExpectMarkovStatistics(stats, 0.15, 0.25, config.period_s(), epochs);
}

TEST(GnssModel, ExactMarkovStepMatchesTheMatrixExponential) {
  // Two steps of dt compose to one step of 2 dt (semigroup property of exp(Q t)).
  const double a = 0.3, b = 0.7, dt = 0.25;
  const MarkovStep one = ExactMarkovStep(a, b, dt);
  const MarkovStep two = ExactMarkovStep(a, b, 2.0 * dt);
  const double onset_twice = (1.0 - one.p_onset) * one.p_onset + one.p_onset * (1.0 - one.p_recovery);
  EXPECT_NEAR(two.p_onset, onset_twice, 1e-14);
  EXPECT_NEAR(ExactMarkovStep(a, b, 1e-9).p_onset, a * 1e-9, 1e-16);
  EXPECT_EQ(ExactMarkovStep(0.0, 0.0, 1.0).p_onset, 0.0);
}

std::vector<double> Sequence(std::uint64_t seed) {
  GnssConfig config = NoFaultConfig();
  config.dropout = {0.3, 0.6, 1.0};
  config.multipath = {0.3, 0.6, 1.0};
  config.multipath_offset_max_m = 1.0;
  GnssModel model(config, seed);
  std::vector<double> values;
  for (int k = 0; k < 500; ++k) {
    const GnssSample s = model.Measure(0.1 * k, Eigen::Vector3d(1.0, 2.0, 3.0), 0.01 * (k % 100));
    values.insert(values.end(), {s.position_m.x(), s.position_m.y(), s.position_m.z(), s.has_fix ? 1.0 : 0.0,
                                 s.faults.multipath_offset_m.x()});
  }
  return values;
}

TEST(GnssModel, SameSeedGivesIdenticalSequencesAndDifferentSeedsDiffer) {
  EXPECT_EQ(Sequence(7), Sequence(7));
  EXPECT_NE(Sequence(7), Sequence(8));
}

TEST(GnssModel, RejectsTimeGoingBackwardsOrRepeatedOrNonFinite) {
  GnssModel model(NoFaultConfig(), 1);
  const Eigen::Vector3d p = Eigen::Vector3d::Zero();
  model.Measure(1.0, p, 0.0);
  EXPECT_THROW(model.Measure(0.5, p, 0.0), std::invalid_argument);
  EXPECT_THROW(model.Measure(1.0, p, 0.0), std::invalid_argument);
  EXPECT_THROW(model.Measure(std::numeric_limits<double>::quiet_NaN(), p, 0.0), std::invalid_argument);
  EXPECT_THROW(model.Measure(std::numeric_limits<double>::infinity(), p, 0.0), std::invalid_argument);
  EXPECT_NO_THROW(model.Measure(1.1, p, 0.0));
}

TEST(GnssModel, RejectsNonFinitePositionAndCanopyOutsideUnitInterval) {
  GnssModel model(NoFaultConfig(), 1);
  EXPECT_THROW(model.Measure(0.0, Eigen::Vector3d(std::nan(""), 0.0, 0.0), 0.0), std::invalid_argument);
  EXPECT_THROW(model.Measure(0.1, Eigen::Vector3d::Zero(), -0.1), std::invalid_argument);
  EXPECT_THROW(model.Measure(0.2, Eigen::Vector3d::Zero(), 1.5), std::invalid_argument);
  EXPECT_THROW(model.Measure(0.3, Eigen::Vector3d::Zero(), std::nan("")), std::invalid_argument);
}

TEST(GnssModel, RejectsInvalidConfiguration) {
  const auto rejects = [](auto mutate) {
    GnssConfig c = NoFaultConfig();
    mutate(c);
    EXPECT_THROW(GnssModel(c, 1), std::invalid_argument);
  };
  rejects([](GnssConfig& c) { c.sigma_horizontal_m = -0.01; });
  rejects([](GnssConfig& c) { c.sigma_vertical_m = -1.0; });
  rejects([](GnssConfig& c) { c.rate_hz = 0.0; });
  rejects([](GnssConfig& c) { c.canopy_sigma_gain = std::nan(""); });
  rejects([](GnssConfig& c) { c.nominal_fix = formats::GnssFixQuality::kNone; });
  rejects([](GnssConfig& c) { c.dropout.mean_duration_s = 0.0; });
  rejects([](GnssConfig& c) { c.multipath.onset_rate_canopy_per_s = -1.0; });
  rejects([](GnssConfig& c) { c.multipath_offset_max_m = c.multipath_offset_min_m - 0.1; });
}

}  // namespace
}  // namespace rowloc::sim
