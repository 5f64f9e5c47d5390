// Statistical assertions shared by the simulator's noise-model tests.
#pragma once

#include <boost/math/distributions/binomial.hpp>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/normal.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <vector>

namespace rowloc::test {

/// Significance of every two-sided statistical test (with fixed seeds, so never flaky).
inline constexpr double kStatisticalAlpha = 1e-3;

/// Two-sided tests that zero-mean samples have standard deviation sigma: the chi-square test of
/// the sample variance (n - 1 degrees of freedom, mean estimated) and a z test of the mean.
inline void ExpectZeroMeanWithSigma(const std::vector<double>& samples, double sigma) {
  const double n = static_cast<double>(samples.size());
  double mean = 0.0;
  for (double s : samples) mean += s / n;
  double sum_sq = 0.0;
  for (double s : samples) sum_sq += (s - mean) * (s - mean);
  const boost::math::chi_squared chi2(n - 1.0);
  const double statistic = sum_sq / (sigma * sigma);
  EXPECT_GT(statistic, boost::math::quantile(chi2, kStatisticalAlpha / 2.0)) << "sigma " << sigma;
  EXPECT_LT(statistic, boost::math::quantile(chi2, 1.0 - kStatisticalAlpha / 2.0)) << "sigma " << sigma;
  const double z = boost::math::quantile(boost::math::normal(), 1.0 - kStatisticalAlpha / 2.0);
  EXPECT_LT(std::abs(mean), z * sigma / std::sqrt(n)) << "sigma " << sigma;
}

/// Two-sided binomial test that `successes` of `trials` independent events of probability p is
/// not unusual.
inline void ExpectBinomialFrequency(std::size_t successes, std::size_t trials, double p) {
  const boost::math::binomial dist(static_cast<double>(trials), p);
  const double lo = boost::math::quantile(dist, kStatisticalAlpha / 2.0);
  const double hi = boost::math::quantile(boost::math::complement(dist, kStatisticalAlpha / 2.0));
  EXPECT_GE(static_cast<double>(successes), lo) << successes << " of " << trials;
  EXPECT_LE(static_cast<double>(successes), hi) << successes << " of " << trials;
}

}  // namespace rowloc::test
