// Ultrasonic rangers: exact cone casts against the canopy (planar wall = analytic range), the
// sampling error against a rough canopy, gaps and band, range limits, missed echoes (binomial),
// range noise (mean and chi-square variance), determinism and bad parameters.
#include "rowloc/sim/ultrasonic_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>

namespace rowloc::sim {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kHalfAperture = 7.5 * kPi / 180.0;

/// One straight smooth row along +x from x = 0 to 40, its right face the plane y = -0.25.
RowWorldParams Wall() {
  RowWorldParams p;
  p.row_count = 1;
  p.row_length_m = 40.0;
  p.canopy.half_width_variation_m = 0.0;
  p.canopy.height_variation_m = 0.0;
  return p;
}

TEST(UltrasonicModel, ConeCastAgainstAPlanarWallMatchesTheAnalyticRange) {
  const RowWorld world(Wall());
  CanopyCaster caster(world);
  for (const double d : {0.05, 0.5, 1.0, 2.7}) {
    for (double beta_deg = -70.0; beta_deg <= 70.0; beta_deg += 2.5) {
      const double beta = beta_deg * kPi / 180.0;  // angle of the axis from the wall normal
      const Eigen::Vector2d apex(20.0, -0.25 - d);
      const Eigen::Vector2d axis(std::sin(beta), std::cos(beta));
      const auto echo = caster.ConeCast({apex, axis, kHalfAperture, 4.0}, 1.0);
      const double expected = std::abs(beta) <= kHalfAperture ? d : d / std::cos(std::abs(beta) - kHalfAperture);
      SCOPED_TRACE(testing::Message() << "d " << d << " beta " << beta_deg);
      if (expected > 4.0) {
        EXPECT_FALSE(echo.has_value());
        continue;
      }
      ASSERT_TRUE(echo.has_value());
      EXPECT_NEAR(echo->range_m, expected, 1e-4);
      EXPECT_NEAR(echo->range_m, expected, 1e-9);  // the plane is sampled exactly
      EXPECT_NEAR(echo->point_m.y(), -0.25, 1e-12);
      EXPECT_EQ(echo->row, 0);
    }
  }
  EXPECT_EQ(caster.cached_slices(), 1u);
}

TEST(UltrasonicModel, NoEchoFromGapsOrOutsideTheBand) {
  RowWorldParams p = Wall();
  p.gaps = {{0, 18.0, 22.0}};
  const RowWorld world(p);
  CanopyCaster caster(world);
  const geometry::Cone2 into_gap{{20.0, -1.25}, {0.0, 1.0}, kHalfAperture, 4.0};
  EXPECT_FALSE(caster.ConeCast(into_gap, 1.0).has_value());
  const geometry::Cone2 at_wall{{10.0, -1.25}, {0.0, 1.0}, kHalfAperture, 4.0};
  EXPECT_TRUE(caster.ConeCast(at_wall, 1.0).has_value());
  EXPECT_FALSE(caster.ConeCast(at_wall, 0.3).has_value());  // below the canopy (bottom 0.5 m)
  EXPECT_FALSE(caster.ConeCast(at_wall, 1.95).has_value()); // above it (top 1.8 m)
  EXPECT_THROW(caster.ConeCast(at_wall, NAN), std::invalid_argument);
}

TEST(UltrasonicModel, SampledRoughCanopyIsWithinTheToleranceOfTheTrueSurface) {
  RowWorldParams p = Wall();
  p.row_length_m = 10.0;
  p.canopy.roughness_amplitude_m = 0.015;
  p.canopy.roughness_min_wavelength_m = 0.1;
  p.canopy.roughness_max_wavelength_m = 0.1;  // the sharpest roughness the defaults allow
  const RowWorld world(p);
  const double tolerance_m = 5e-5;
  const double step = world.StepForTolerance(tolerance_m);
  EXPECT_GT(step, 0.002);
  EXPECT_EQ(CanopyCaster(world, tolerance_m).step_m(), step);
  const CanopySlice slice(world, 1.0, step);
  double max_error_m = 0.0;
  for (double s = 1.0; s < 9.0; s += 0.000731) {
    const Eigen::Vector2d right = world.RowCentre(0, s) - world.RightHalfWidth(0, s) * world.ReferenceNormal(s);
    max_error_m = std::max(max_error_m, slice.index().Nearest(right, 1).front().first);
  }
  std::printf("step %.4g m: max distance of the true rough surface to the sampled outline %.3g m\n", step,
              max_error_m);
  EXPECT_LT(max_error_m, tolerance_m);
  EXPECT_GT(max_error_m, 0.0);
  // And the cone cast range is within that of the true nearest point (dense search in the cone).
  const Eigen::Vector2d apex(5.0, -1.25);
  const auto echo = slice.ConeCast({apex, {0.0, 1.0}, kHalfAperture, 4.0});
  ASSERT_TRUE(echo.has_value());
  double true_range = 1e9;
  for (double s = 4.0; s < 6.0; s += 1e-5) {
    const Eigen::Vector2d x = world.RowCentre(0, s) - world.RightHalfWidth(0, s) * world.ReferenceNormal(s);
    const Eigen::Vector2d v = x - apex;
    if (std::acos(v.normalized().y()) <= kHalfAperture) true_range = std::min(true_range, v.norm());
  }
  EXPECT_NEAR(echo->range_m, true_range, tolerance_m);
}

TEST(UltrasonicModel, RangeLimitsBlindZoneAndMaxRange) {
  const RowWorld world(Wall());
  CanopyCaster caster(world);
  UltrasonicParams params;
  params.range_sigma_m = 0.0;
  UltrasonicModel model(params, 1);
  EXPECT_FALSE(model.Measure(caster, {20.0, -0.25 - 4.2}, {0.0, 1.0}, 1.0).has_value());
  EXPECT_FALSE(model.Measure(caster, {20.0, -0.25 - 0.01}, {0.0, 1.0}, 1.0).has_value());
  const auto near_max = model.Measure(caster, {20.0, -0.25 - 3.9}, {0.0, 1.0}, 1.0);
  ASSERT_TRUE(near_max.has_value());
  EXPECT_NEAR(near_max->range_m, 3.9, 1e-9);
  // Away from the wall (pointing along it, behind its start): nothing.
  EXPECT_FALSE(model.Measure(caster, {-1.0, -1.25}, {-1.0, 0.0}, 1.0).has_value());
}

TEST(UltrasonicModel, MissedEchoesFollowTheirProbability) {
  const RowWorld world(Wall());
  CanopyCaster caster(world);
  UltrasonicParams params;
  params.miss_probability = 0.3;
  UltrasonicModel model(params, 42);
  const int n = 4000;
  int missed = 0;
  for (int i = 0; i < n; ++i)
    if (!model.Measure(caster, {20.0, -1.25}, {0.0, 1.0}, 1.0)) ++missed;
  const double mean = n * 0.3, sd = std::sqrt(n * 0.3 * 0.7);
  EXPECT_NEAR(missed, mean, 4.0 * sd);  // binomial, 4 sigma
}

TEST(UltrasonicModel, RangeNoiseHasItsMeanAndVariance) {
  const RowWorld world(Wall());
  CanopyCaster caster(world);
  UltrasonicModel model(UltrasonicParams{}, 7);
  const int n = 4000;
  double sum = 0.0, sum_sq = 0.0;
  for (int i = 0; i < n; ++i) {
    const auto reading = model.Measure(caster, {20.0, -1.25}, {0.0, 1.0}, 1.0);
    ASSERT_TRUE(reading.has_value());
    EXPECT_NEAR(reading->truth.range_m, 1.0, 1e-12);
    const double e = reading->range_m - 1.0;
    sum += e;
    sum_sq += e * e;
  }
  const double sigma = 0.003;
  EXPECT_NEAR(sum / n, 0.0, 4.0 * sigma / std::sqrt(n));
  // sum e^2 / sigma^2 ~ chi-square(n): mean n, sd sqrt(2n); accept 4 sd.
  EXPECT_NEAR(sum_sq / (sigma * sigma), n, 4.0 * std::sqrt(2.0 * n));
}

TEST(UltrasonicModel, SameSeedSameReadingsOtherSeedOther) {
  const RowWorld world(Wall());
  CanopyCaster caster(world);
  UltrasonicParams params;
  params.miss_probability = 0.2;
  UltrasonicModel a(params, 3), b(params, 3), c(params, 4);
  bool differ = false;
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector2d apex(10.0 + 0.1 * i, -1.25);
    const auto ra = a.Measure(caster, apex, {0.0, 1.0}, 1.0);
    const auto rb = b.Measure(caster, apex, {0.0, 1.0}, 1.0);
    const auto rc = c.Measure(caster, apex, {0.0, 1.0}, 1.0);
    ASSERT_EQ(ra.has_value(), rb.has_value());
    if (ra) {
      EXPECT_EQ(ra->range_m, rb->range_m);
    }
    differ = differ || ra.has_value() != rc.has_value() || (ra && rc && ra->range_m != rc->range_m);
  }
  EXPECT_TRUE(differ);
}

TEST(UltrasonicModel, RejectsBadParametersAndInputs) {
  const auto bad = [](auto mutate) {
    UltrasonicParams p;
    mutate(p);
    return UltrasonicParamsProblem(p).has_value();
  };
  EXPECT_FALSE(UltrasonicParamsProblem(UltrasonicParams{}).has_value());
  EXPECT_TRUE(bad([](UltrasonicParams& p) { p.miss_probability = 1.5; }));
  EXPECT_TRUE(bad([](UltrasonicParams& p) { p.range_sigma_m = -0.001; }));
  EXPECT_TRUE(bad([](UltrasonicParams& p) { p.half_aperture_rad = kPi / 2; }));
  EXPECT_TRUE(bad([](UltrasonicParams& p) { p.max_range_m = 0.01; }));
  EXPECT_TRUE(bad([](UltrasonicParams& p) { p.min_range_m = NAN; }));
  UltrasonicParams p;
  p.miss_probability = -0.1;
  EXPECT_THROW(UltrasonicModel(p, 1), std::invalid_argument);
  const RowWorld world(Wall());
  EXPECT_THROW(CanopyCaster(world, 0.0), std::invalid_argument);
  EXPECT_THROW(CanopyCaster(world, 0.002, 0.0), std::invalid_argument);
  CanopyCaster caster(world);
  UltrasonicModel model(UltrasonicParams{}, 1);
  EXPECT_THROW(model.Measure(caster, {20.0, -1.25}, {0.0, 0.0}, 1.0), std::invalid_argument);
  EXPECT_THROW(model.Measure(caster, {NAN, -1.25}, {0.0, 1.0}, 1.0), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::sim
