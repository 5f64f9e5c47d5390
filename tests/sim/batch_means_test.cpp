// Batch-means interval and integrated autocorrelation time (batch_means.hpp): a hand-computed
// case, the errors, and the properties that matter for a filter's time-averaged NEES: the
// interval covers the expected value of a strongly correlated chi-square sequence in about 95 % of
// runs (where the independent-sample band of chi_square_bands.hpp does not), and it excludes the
// expected value of a biased (conservative) sequence.
#include "rowloc/sim/batch_means.hpp"

#include "rowloc/sim/chi_square_bands.hpp"
#include "rowloc/sim/metrics.hpp"
#include "statistical_tests.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

namespace rowloc::sim {
namespace {

/// NEES-like sequence: |e_k|^2 of a 3-D Gaussian AR(1) e_k = a e_(k-1) + sqrt(1 - a^2) n_k,
/// stationary N(0, scale I): each sample is scale * chi2(3), correlated over ~1 / (1 - a^2) samples.
std::vector<double> CorrelatedChiSquare(std::size_t n, double a, double scale, std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  double e[3] = {normal(rng), normal(rng), normal(rng)};
  std::vector<double> out(n);
  for (std::size_t k = 0; k < n; ++k) {
    double sum = 0.0;
    for (double& c : e) {
      c = a * c + std::sqrt(1.0 - a * a) * normal(rng);
      sum += c * c;
    }
    out[k] = scale * sum;
  }
  return out;
}

TEST(BatchMeans, HandComputedTwoBatches) {
  // Batches {1, 2, 3, 4} and {5, 6, 7, 8} (the 9th sample is dropped): means 2.5 and 6.5, mean 4.5,
  // s^2 = (2^2 + 2^2) / 1 = 8, standard error sqrt(8 / 2) = 2, t(1, 0.975) = 12.7062047.
  const auto r = BatchMeans({1, 2, 3, 4, 5, 6, 7, 8, 100}, 2);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->batch_count, 2u);
  EXPECT_EQ(r->batch_length, 4u);
  EXPECT_DOUBLE_EQ(r->mean, 4.5);
  EXPECT_NEAR(r->lower, 4.5 - 2.0 * 12.7062047362, 1e-8);
  EXPECT_NEAR(r->upper, 4.5 + 2.0 * 12.7062047362, 1e-8);
  EXPECT_TRUE(r->Contains(4.5));
  EXPECT_FALSE(r->Contains(100.0));
}

TEST(BatchMeans, ConstantSequenceHasAPointInterval) {
  const auto r = BatchMeans(std::vector<double>(100, 3.0), 20);
  ASSERT_TRUE(r.has_value());
  EXPECT_DOUBLE_EQ(r->lower, 3.0);
  EXPECT_DOUBLE_EQ(r->upper, 3.0);
  EXPECT_DOUBLE_EQ(r->batch_lag1_autocorrelation, 0.0);
}

TEST(BatchMeans, TooFewSamplesAndBadArguments) {
  EXPECT_FALSE(BatchMeans(std::vector<double>(39, 1.0), 20).has_value());  // < 2 per batch
  EXPECT_TRUE(BatchMeans(std::vector<double>(40, 1.0), 20).has_value());
  EXPECT_FALSE(BatchMeans({}, 20).has_value());
  EXPECT_THROW(BatchMeans({1.0, 2.0, 3.0, 4.0}, 1), std::invalid_argument);
  EXPECT_THROW(BatchMeans({1.0, 2.0, 3.0, 4.0}, 2, 1.0), std::invalid_argument);
  EXPECT_THROW(BatchMeans({1.0, 2.0, 3.0, 4.0}, 2, 0.0), std::invalid_argument);
  EXPECT_THROW(BatchMeans({1.0, std::nan(""), 3.0, 4.0}, 2), std::invalid_argument);
  EXPECT_THROW(BatchMeans({1.0, std::numeric_limits<double>::infinity(), 3.0, 4.0}, 2), std::invalid_argument);
  EXPECT_THROW(IntegratedAutocorrelationTime({1.0, std::nan(""), 3.0}), std::invalid_argument);
}

// The point of the interval: for a consistent filter whose NEES is correlated over ~50 samples,
// the batch-means interval covers 3 in ~95 % of runs, the independent-sample band in few.
TEST(BatchMeans, CoversTheExpectedValueOfACorrelatedSequence) {
  std::mt19937_64 rng(20261201);
  const std::size_t runs = 300, n = 4000;
  std::size_t batch_inside = 0, band_inside = 0;
  for (std::size_t run = 0; run < runs; ++run) {
    const std::vector<double> nees = CorrelatedChiSquare(n, 0.98, 1.0, rng);
    const auto r = BatchMeans(nees, 20);
    ASSERT_TRUE(r.has_value());
    if (r->Contains(3.0)) ++batch_inside;
    if (TimeAveragedBand(3.0 * n, n).Contains(r->mean)) ++band_inside;
  }
  test::ExpectBinomialFrequency(batch_inside, runs, 0.95);
  EXPECT_LT(band_inside, runs / 2) << "the independent-sample band should be too narrow here";
}

// A conservative filter (P 1/0.75 too large: NEES 2.25 on average) is detected despite the correlation.
TEST(BatchMeans, ExcludesTheExpectedValueOfABiasedSequence) {
  std::mt19937_64 rng(7);
  std::size_t excluded = 0;
  const std::size_t runs = 50;
  for (std::size_t run = 0; run < runs; ++run) {
    const auto r = BatchMeans(CorrelatedChiSquare(4000, 0.98, 0.75, rng), 20);
    ASSERT_TRUE(r.has_value());
    if (!r->Contains(3.0)) ++excluded;
  }
  EXPECT_GE(excluded, runs * 9 / 10);
}

// SummarizeConsistency sizes the batches from the correlation time: at least 4 tau per batch,
// 5-20 batches, none when the run holds fewer than 5 such batches.
TEST(SummarizeConsistency, BatchesAreAtLeastFourCorrelationTimesLong) {
  std::mt19937_64 rng(3);
  const std::vector<double> independent = CorrelatedChiSquare(2000, 0.0, 1.0, rng);
  const ConsistencySummary a = SummarizeConsistency(independent, std::vector<int>(independent.size(), 3));
  ASSERT_TRUE(a.batch_means.has_value());
  EXPECT_EQ(a.batch_means->batch_count, 20u);  // tau ~ 1: the cap
  const std::vector<double> correlated = CorrelatedChiSquare(8000, 0.995, 1.0, rng);  // tau ~ 200
  const ConsistencySummary b = SummarizeConsistency(correlated, std::vector<int>(correlated.size(), 3));
  ASSERT_TRUE(b.batch_means.has_value());
  EXPECT_GE(static_cast<double>(b.batch_means->batch_length), 4.0 * b.correlation_time_samples);
  EXPECT_GE(b.batch_means->batch_count, 5u);
  EXPECT_LT(b.batch_means->batch_count, 20u);
  const std::vector<double> short_run(correlated.begin(), correlated.begin() + 1000);
  const ConsistencySummary c = SummarizeConsistency(short_run, std::vector<int>(short_run.size(), 3));
  EXPECT_FALSE(c.batch_means.has_value());
  EXPECT_FALSE(c.expected_inside);
  EXPECT_LT(c.effective_sample_count, 20.0);
}

TEST(IntegratedAutocorrelationTime, IndependentAndAutoregressiveSequences) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> normal;
  std::vector<double> white(100000), ar(100000);
  double x = 0.0;
  for (std::size_t k = 0; k < white.size(); ++k) {
    white[k] = normal(rng);
    x = 0.9 * x + normal(rng);
    ar[k] = x;
  }
  EXPECT_NEAR(IntegratedAutocorrelationTime(white), 1.0, 0.05);
  EXPECT_NEAR(IntegratedAutocorrelationTime(ar), (1.0 + 0.9) / (1.0 - 0.9), 0.15 * 19.0);  // AR(1): (1 + a) / (1 - a)
  EXPECT_DOUBLE_EQ(IntegratedAutocorrelationTime(std::vector<double>(50, 2.0)), 1.0);
  EXPECT_DOUBLE_EQ(IntegratedAutocorrelationTime({1.0, 2.0}), 1.0);
}

}  // namespace
}  // namespace rowloc::sim
