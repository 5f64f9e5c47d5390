// The per-wheel two-sided CUSUM of terrain_change_detector.hpp: silent on white innovations,
// quick on a step of either sign, one wheel at a time, sums that restart after an alarm, a reset
// and a skipped (non-finite) sample, and settings refused with their name.
#include "rowloc/localization/terrain_change_detector.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstddef>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

namespace rowloc::localization {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

TerrainChangeConfig Settings(double drift, double threshold) {
  TerrainChangeConfig c;
  c.enabled = true;
  c.cusum_drift_sigma = drift;
  c.cusum_threshold_sigma = threshold;
  return c;
}

Eigen::VectorXd Sample(std::initializer_list<double> values) {
  Eigen::VectorXd v(static_cast<Eigen::Index>(values.size()));
  Eigen::Index i = 0;
  for (const double x : values) v(i++) = x;
  return v;
}

TEST(TerrainChangeDetector, WhiteInnovationsRaiseNoAlarm) {
  // 4 wheels x 200,000 samples (an hour at 50 Hz) of N(0, 1). Siegmund's approximation of the
  // average run length of one side between false alarms, (exp(2 d b) - 2 d b - 1) / (2 d^2) with
  // b = h + 1.166: 1.1e5 samples for d = 1, h = 5 (about 14 alarms expected here over the 8 sums)
  // and 2.5e9 for d = 1, h = 10 (none).
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  TerrainChangeDetector loose(4, Settings(1.0, 5.0)), strict(4, Settings(1.0, 10.0));
  Eigen::VectorXd e(4);
  for (int k = 0; k < 200000; ++k) {
    for (int i = 0; i < 4; ++i) e(i) = normal(rng);
    loose.Observe(e);
    strict.Observe(e);
  }
  std::size_t loose_alarms = 0;
  for (const std::size_t a : loose.alarms()) loose_alarms += a;
  EXPECT_GE(loose_alarms, 5u);  // within a factor of 3 of the approximation
  EXPECT_LE(loose_alarms, 43u);
  EXPECT_THAT(strict.alarms(), ElementsAre(0u, 0u, 0u, 0u));
}

TEST(TerrainChangeDetector, AStepOfEitherSignIsReportedWithinAFewSamplesOnItsWheelOnly) {
  for (const double step : {4.0, -4.0}) {
    TerrainChangeDetector d(3, Settings(1.0, 10.0));
    int fired_at = -1;
    for (int k = 0; k < 10 && fired_at < 0; ++k) {
      const std::vector<std::size_t>& fired = d.Observe(Sample({0.3, step, -0.2}));
      if (!fired.empty()) {
        EXPECT_THAT(fired, ElementsAre(1u));
        fired_at = k;
      }
    }
    // (|step| - d) per sample: 3 per sample crosses 10 at the fourth.
    EXPECT_EQ(fired_at, 3) << "step " << step;
    EXPECT_THAT(d.alarms(), ElementsAre(0u, 1u, 0u));
    EXPECT_DOUBLE_EQ(d.upper(1), 0.0);  // both sums restart after an alarm
    EXPECT_DOUBLE_EQ(d.lower(1), 0.0);
  }
}

TEST(TerrainChangeDetector, TheSumsFollowPagesRecursion) {
  TerrainChangeDetector d(1, Settings(0.5, 100.0));
  d.Observe(Sample({2.0}));  // g+ = 1.5, g- = max(0, -2.5) = 0
  EXPECT_DOUBLE_EQ(d.upper(0), 1.5);
  EXPECT_DOUBLE_EQ(d.lower(0), 0.0);
  d.Observe(Sample({-1.0}));  // g+ = max(0, 1.5 - 1.5) = 0, g- = 0.5
  EXPECT_DOUBLE_EQ(d.upper(0), 0.0);
  EXPECT_DOUBLE_EQ(d.lower(0), 0.5);
  d.Observe(Sample({-3.0}));  // g- = 0.5 + 2.5
  EXPECT_DOUBLE_EQ(d.lower(0), 3.0);
}

TEST(TerrainChangeDetector, ANonFiniteSampleAndAResetRestartTheSums) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  TerrainChangeDetector d(2, Settings(0.0, 5.0));
  d.Observe(Sample({3.0, 3.0}));
  EXPECT_THAT(d.Observe(Sample({nan, 1.0})), IsEmpty());  // wheel 0 skipped (an excluded encoder)
  EXPECT_DOUBLE_EQ(d.upper(0), 0.0);
  EXPECT_DOUBLE_EQ(d.upper(1), 4.0);
  d.Reset();
  EXPECT_DOUBLE_EQ(d.upper(1), 0.0);
  EXPECT_THAT(d.Observe(Sample({3.0, 3.0})), IsEmpty());  // 3 < 5 again after the reset
  EXPECT_THAT(d.Observe(Sample({3.0, 3.0})), ElementsAre(0u, 1u));
}

TEST(TerrainChangeDetector, BadSettingsAndSizesAreRefusedByName) {
  const auto refused = [](TerrainChangeConfig c, const char* name) {
    try {
      TerrainChangeDetector d(4, c);
      ADD_FAILURE() << name << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_THAT(e.what(), HasSubstr(name));
    }
  };
  TerrainChangeConfig c = Settings(1.0, 10.0);
  c.cusum_drift_sigma = -1.0;
  refused(c, "cusum_drift_sigma");
  c = Settings(1.0, 0.0);
  refused(c, "cusum_threshold_sigma");
  c = Settings(1.0, std::numeric_limits<double>::infinity());
  refused(c, "cusum_threshold_sigma");
  c = Settings(1.0, 10.0);
  c.radius_sigma_fraction = std::numeric_limits<double>::quiet_NaN();
  refused(c, "radius_sigma_fraction");
  TerrainChangeDetector d(4, Settings(1.0, 10.0));
  EXPECT_THROW(d.Observe(Sample({1.0, 2.0})), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::localization
