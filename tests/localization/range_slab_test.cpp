#include "rowloc/localization/range_slab.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

namespace rowloc::localization {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

TEST(RangeSlab, HorizontalRowBelowTheVehicle) {
  // Row edge y = 0; vehicle at y = 1.2 heading east; right-looking sensor 0.3 m right of centre.
  const EdgeLine row{Eigen::Vector2d(0, 1), 0.0};
  const RangeSensorMount mount{Eigen::Vector2d(0.5, -0.3), -kPi / 2};
  const auto slab = MakeRangeSlab(row, mount, 0.0, 0.9, 0.003, 3.0);
  ASSERT_TRUE(slab.has_value());
  EXPECT_NEAR(slab->normal.x(), 0.0, 1e-15);
  EXPECT_NEAR(slab->normal.y(), 1.0, 1e-15);
  EXPECT_NEAR(slab->lower_m, 1.2 - 0.009, 1e-12);
  EXPECT_NEAR(slab->upper_m, 1.2 + 0.009, 1e-12);
  EXPECT_NEAR(slab->incidence_cos, 1.0, 1e-12);
}

TEST(RangeSlab, NormalIsOrientedTowardsTheSensorWhateverTheInputSign) {
  const RangeSensorMount mount{Eigen::Vector2d(0.5, -0.3), -kPi / 2};
  const auto a = MakeRangeSlab(EdgeLine{{0, 1}, 0.0}, mount, 0.0, 0.9, 0.003, 3.0);
  const auto b = MakeRangeSlab(EdgeLine{{0, -1}, 0.0}, mount, 0.0, 0.9, 0.003, 3.0);
  ASSERT_TRUE(a && b);
  EXPECT_NEAR((a->normal - b->normal).norm(), 0.0, 1e-15);
  EXPECT_NEAR(a->lower_m, b->lower_m, 1e-12);
  EXPECT_NEAR(a->upper_m, b->upper_m, 1e-12);
}

// Rows at 0, 45, 90, 135 degrees, sensors on both sides: for a random pose near the row, the
// range computed by the beam model gives a slab whose centre is exactly n^T p, with half width
// k sigma cos(gamma).
class RangeSlabAtAngle : public ::testing::TestWithParam<double> {};

TEST_P(RangeSlabAtAngle, RecoversTheReferencePointFromTheRange) {
  const double row_dir = GetParam();
  const Eigen::Vector2d along(std::cos(row_dir), std::sin(row_dir));
  const Eigen::Vector2d normal(-along.y(), along.x());
  const EdgeLine row{normal, 2.0};
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> jitter(-0.2, 0.2);
  for (double side : {+1.0, -1.0}) {
    for (int i = 0; i < 200; ++i) {
      // Vehicle 1.25 m from the edge on `side`, driving along the row with small heading error.
      const double heading = row_dir + jitter(rng);
      const Eigen::Vector2d p = (2.0 + side * 1.25) * normal + 10.0 * jitter(rng) * along;
      const RangeSensorMount mount{Eigen::Vector2d(0.75, side * -0.5), side * -kPi / 2 + jitter(rng)};
      const double pose[3] = {p.x(), p.y(), heading};
      double range = 0.0;
      ASSERT_TRUE(RangeToLine(pose, mount, row, &range));
      const auto slab = MakeRangeSlab(row, mount, heading, range, 0.003, 3.0);
      ASSERT_TRUE(slab.has_value());
      const double np = slab->normal.dot(p);
      EXPECT_NEAR(0.5 * (slab->lower_m + slab->upper_m), np, 1e-9);
      EXPECT_NEAR(slab->upper_m - slab->lower_m, 2 * 0.009 * slab->incidence_cos, 1e-12);
      EXPECT_GT(slab->normal.dot(normal) * side, 0.0);  // points from the row towards the vehicle
    }
  }
}

INSTANTIATE_TEST_SUITE_P(RowDirections, RangeSlabAtAngle,
                         ::testing::Values(0.0, kPi / 4, kPi / 2, 3 * kPi / 4));

TEST(RangeSlab, LeverArmShiftsTheSlab) {
  const EdgeLine row{Eigen::Vector2d(0, 1), 0.0};
  const auto centred = MakeRangeSlab(row, RangeSensorMount{{0, 0}, -kPi / 2}, 0.0, 1.0, 0.01, 1.0);
  const auto shifted = MakeRangeSlab(row, RangeSensorMount{{0, -0.4}, -kPi / 2}, 0.0, 1.0, 0.01, 1.0);
  ASSERT_TRUE(centred && shifted);
  EXPECT_NEAR(shifted->lower_m - centred->lower_m, 0.4, 1e-12);
  // Heading pi: the body's right is world +y, so the same lever arm shifts the other way.
  const EdgeLine above{Eigen::Vector2d(0, 1), 3.0};
  const auto turned = MakeRangeSlab(above, RangeSensorMount{{0, -0.4}, -kPi / 2}, kPi, 1.0, 0.01, 1.0);
  ASSERT_TRUE(turned);
  EXPECT_NEAR(turned->normal.y(), -1.0, 1e-12);
  // Sensor at y_p + 0.4 and 0.99..1.01 m below the edge y = 3, so -y_p in [-1.61, -1.59].
  EXPECT_NEAR(turned->lower_m, -3.0 + 0.99 + 0.4, 1e-12);
  EXPECT_NEAR(turned->upper_m, -3.0 + 1.01 + 0.4, 1e-12);
}

TEST(RangeSlab, ConeEchoComesFromTheNearestPointOfTheEdge) {
  // Edge y = 0, sensor at the reference point 1 m above it, beam tilted 5 degrees off the normal.
  const EdgeLine row{Eigen::Vector2d(0, 1), 0.0};
  const double tilt = 5.0 * kPi / 180.0;
  const double half = 7.5 * kPi / 180.0;
  // Inside the cone the echo is the perpendicular distance (1 m), whatever the tilt.
  const auto inside = MakeRangeSlab(row, RangeSensorMount{{0, 0}, -kPi / 2 + tilt, half}, 0.0, 1.0, 0.01, 1.0);
  ASSERT_TRUE(inside);
  EXPECT_NEAR(inside->incidence_cos, 1.0, 1e-15);
  EXPECT_NEAR(0.5 * (inside->lower_m + inside->upper_m), 1.0, 1e-12);
  // A ray model of the same echo would put the vehicle at cos(5 deg) = 0.9962 m: 3.8 mm off.
  const auto ray = MakeRangeSlab(row, RangeSensorMount{{0, 0}, -kPi / 2 + tilt, 0.0}, 0.0, 1.0, 0.01, 1.0);
  ASSERT_TRUE(ray);
  EXPECT_NEAR(0.5 * (ray->lower_m + ray->upper_m), std::cos(tilt), 1e-12);
  // Tilted 20 degrees: the nearest point in the cone is on its edge, 12.5 degrees off the normal.
  const double big = 20.0 * kPi / 180.0;
  const auto outside = MakeRangeSlab(row, RangeSensorMount{{0, 0}, -kPi / 2 + big, half}, 0.0,
                                     1.0 / std::cos(big - half), 0.01, 1.0);
  ASSERT_TRUE(outside);
  EXPECT_NEAR(0.5 * (outside->lower_m + outside->upper_m), 1.0, 1e-12);
  EXPECT_FALSE(MakeRangeSlab(row, RangeSensorMount{{0, 0}, -kPi / 2, kPi / 2}, 0.0, 1.0, 0.01, 1.0));
  EXPECT_FALSE(MakeRangeSlab(row, RangeSensorMount{{0, 0}, -kPi / 2, -0.1}, 0.0, 1.0, 0.01, 1.0));
}

TEST(RangeSlab, LowerBoundIsClampedAtZeroRange) {
  const auto slab = MakeRangeSlab(EdgeLine{{0, 1}, 0.0}, RangeSensorMount{{0, 0}, -kPi / 2}, 0.0,
                                  0.02, 0.01, 3.0);
  ASSERT_TRUE(slab);
  EXPECT_NEAR(slab->lower_m, 0.0, 1e-15);
  EXPECT_NEAR(slab->upper_m, 0.05, 1e-15);
}

TEST(RangeSlab, RejectsInvalidInput) {
  const EdgeLine row{Eigen::Vector2d(0, 1), 0.0};
  const RangeSensorMount mount{{0, 0}, -kPi / 2};
  EXPECT_FALSE(MakeRangeSlab(row, mount, 0.0, kNaN, 0.01, 3.0));
  EXPECT_FALSE(MakeRangeSlab(row, mount, kNaN, 1.0, 0.01, 3.0));
  EXPECT_FALSE(MakeRangeSlab(row, mount, 0.0, -1.0, 0.01, 3.0));
  EXPECT_FALSE(MakeRangeSlab(row, mount, 0.0, 1.0, 0.0, 3.0));
  EXPECT_FALSE(MakeRangeSlab(row, mount, 0.0, 1.0, 0.01, -3.0));
  EXPECT_FALSE(MakeRangeSlab(EdgeLine{{0, 0}, 0.0}, mount, 0.0, 1.0, 0.01, 3.0));
  EXPECT_FALSE(MakeRangeSlab(row, RangeSensorMount{{0, 0}, 0.0}, 0.0, 1.0, 0.01, 3.0));  // parallel
}

}  // namespace
}  // namespace rowloc::localization
