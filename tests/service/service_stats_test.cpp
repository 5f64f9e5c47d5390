// The latency histogram of `stats`: quantiles within one bin (4.4 %) of the exact ones.
#include "rowloc/service/service_stats.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace rowloc::service {
namespace {

TEST(LatencyHistogram, QuantilesWithinOneBinOfTheExactOnes) {
  LatencyHistogram histogram;
  EXPECT_EQ(histogram.Quantile(0.5), 0.0);
  std::mt19937_64 rng(7);
  std::lognormal_distribution<double> latency(3.0, 1.0);  // microseconds, median e^3 = 20 us
  std::vector<double> samples(20000);
  for (double& s : samples) {
    s = latency(rng);
    histogram.Record(s);
  }
  std::sort(samples.begin(), samples.end());
  EXPECT_EQ(histogram.count(), samples.size());
  for (const double q : {0.5, 0.9, 0.99}) {
    const double exact = samples[static_cast<std::size_t>(q * samples.size()) - 1];
    EXPECT_GE(histogram.Quantile(q), exact * (1 - 1e-9)) << q;
    EXPECT_LE(histogram.Quantile(q), exact * 1.045) << q;
  }
  EXPECT_NEAR(histogram.max_us(), samples.back(), 1e-3);  // kept in whole nanoseconds
}

TEST(LatencyHistogram, IgnoresNegativeAndNaN) {
  LatencyHistogram histogram;
  histogram.Record(-1.0);
  histogram.Record(std::nan(""));
  EXPECT_EQ(histogram.count(), 0u);
  histogram.Record(1e12);  // beyond the last bin: counted there
  EXPECT_EQ(histogram.count(), 1u);
}

}  // namespace
}  // namespace rowloc::service
