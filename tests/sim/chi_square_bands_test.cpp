// Chi-square bands of the consistency tests: tabulated quantiles, the Lindgren et al. 2002 numbers
// (Eqs. 43-44 and the whiteness band after Eq. 42), properties and bad arguments.
#include "rowloc/sim/chi_square_bands.hpp"

#include <boost/math/distributions/chi_squared.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace rowloc::sim {
namespace {

TEST(ChiSquareInterval, MatchesTabulatedQuantiles) {
  // Standard chi-square table, 2.5 % and 97.5 % points.
  const ChiSquareBand one = ChiSquareInterval(1.0);
  EXPECT_NEAR(one.lower, 0.000982, 1e-6);
  EXPECT_NEAR(one.upper, 5.024, 1e-3);
  const ChiSquareBand two = ChiSquareInterval(2.0);
  EXPECT_NEAR(two.lower, 0.0506, 1e-4);
  EXPECT_NEAR(two.upper, 7.378, 1e-3);
  const ChiSquareBand three = ChiSquareInterval(3.0);
  EXPECT_NEAR(three.lower, 0.216, 1e-3);
  EXPECT_NEAR(three.upper, 9.348, 1e-3);
  // For 2 dof the quantile is closed-form: -2 ln(1 - p).
  EXPECT_NEAR(two.lower, -2.0 * std::log(0.975), 1e-12);
  EXPECT_NEAR(two.upper, -2.0 * std::log(0.025), 1e-12);
}

TEST(ChiSquareInterval, HoldsTheRequestedProbability) {
  for (double dof : {1.0, 2.0, 3.0, 7.5, 100.0}) {
    for (double p : {0.5, 0.9, 0.95, 0.99}) {
      const ChiSquareBand b = ChiSquareInterval(dof, p);
      const boost::math::chi_squared dist(dof);
      EXPECT_NEAR(boost::math::cdf(dist, b.upper) - boost::math::cdf(dist, b.lower), p, 1e-10);
      EXPECT_NEAR(boost::math::cdf(dist, b.lower), (1.0 - p) / 2.0, 1e-10);  // central
      EXPECT_TRUE(b.Contains(dof - 0.5) || dof < 2.0);  // the mean region is inside
    }
  }
}

TEST(TimeAveragedBand, ReproducesSeed004) {
  // Lindgren et al. 2002: K = 1099 innovations of dimension 2 at 5 % significance: 1.8831 .. 2.1204 (Eq. 44).
  const ChiSquareBand b = TimeAveragedBand(2.0 * 1099, 1099);
  EXPECT_NEAR(b.lower, 1.8831, 5e-4);
  EXPECT_NEAR(b.upper, 2.1204, 5e-4);
  // The same band rounded: 1.88 - 2.12.
  EXPECT_NEAR(b.lower, 1.88, 5e-3);
  EXPECT_NEAR(b.upper, 2.12, 5e-3);
}

TEST(TimeAveragedBand, IsThePerSampleIntervalForOneSampleAndShrinksAroundTheDof) {
  const ChiSquareBand single = ChiSquareInterval(3.0);
  const ChiSquareBand averaged = TimeAveragedBand(3.0, 1);
  EXPECT_DOUBLE_EQ(single.lower, averaged.lower);
  EXPECT_DOUBLE_EQ(single.upper, averaged.upper);
  double previous_width = single.upper - single.lower;
  for (std::size_t n : {10u, 100u, 1000u, 100000u}) {
    const ChiSquareBand b = TimeAveragedBand(3.0 * static_cast<double>(n), n);
    EXPECT_TRUE(b.Contains(3.0)) << n;
    EXPECT_LT(b.upper - b.lower, previous_width) << n;
    previous_width = b.upper - b.lower;
    // Normal approximation: mean 3, standard deviation sqrt(2 * 3 / n).
    if (n >= 1000) {
      EXPECT_NEAR(b.upper - 3.0, 1.96 * std::sqrt(6.0 / static_cast<double>(n)), 0.03 * (b.upper - 3.0));
    }
  }
}

TEST(WhitenessBand, IsOnePointNineSixOverRootK) {
  EXPECT_NEAR(WhitenessBandHalfWidth(1099), 1.96 / std::sqrt(1099.0), 1e-5);  // Lindgren et al. 2002
  EXPECT_NEAR(WhitenessBandHalfWidth(1), 1.959964, 1e-6);
  EXPECT_NEAR(WhitenessBandHalfWidth(100, 0.99), 2.575829 / 10.0, 1e-6);
}

TEST(ChiSquareBands, RejectBadArguments) {
  EXPECT_THROW(ChiSquareInterval(0.0), std::invalid_argument);
  EXPECT_THROW(ChiSquareInterval(-1.0), std::invalid_argument);
  EXPECT_THROW(ChiSquareInterval(std::nan("")), std::invalid_argument);
  EXPECT_THROW(ChiSquareInterval(2.0, 1.0), std::invalid_argument);
  EXPECT_THROW(ChiSquareInterval(2.0, 0.0), std::invalid_argument);
  EXPECT_THROW(TimeAveragedBand(2.0, 0), std::invalid_argument);
  EXPECT_THROW(WhitenessBandHalfWidth(0), std::invalid_argument);
  EXPECT_THROW(WhitenessBandHalfWidth(10, 1.5), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::sim
