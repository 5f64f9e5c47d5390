// Segment2: closest point and distance (docs/planar-geometry.md).
#include "rowloc/geometry/segment2.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <random>
#include <stdexcept>

namespace rowloc::geometry {
namespace {

constexpr double kTol = 1e-12;

TEST(Segment2, ClosestPointInsideAndBeyondTheEnds) {
  const Segment2 s{{0.0, 0.0}, {4.0, 0.0}};
  EXPECT_DOUBLE_EQ(s.Length(), 4.0);
  EXPECT_DOUBLE_EQ(s.ClosestParam({1.0, 3.0}), 0.25);
  EXPECT_TRUE(s.ClosestPoint({1.0, 3.0}).isApprox(Eigen::Vector2d(1.0, 0.0)));
  EXPECT_DOUBLE_EQ(s.Distance({1.0, 3.0}), 3.0);
  EXPECT_DOUBLE_EQ(s.ClosestParam({-3.0, 4.0}), 0.0);
  EXPECT_DOUBLE_EQ(s.Distance({-3.0, 4.0}), 5.0);  // to endpoint a
  EXPECT_DOUBLE_EQ(s.ClosestParam({7.0, -4.0}), 1.0);
  EXPECT_DOUBLE_EQ(s.Distance({7.0, -4.0}), 5.0);  // to endpoint b
  EXPECT_DOUBLE_EQ(s.Distance({2.0, 0.0}), 0.0);
}

TEST(Segment2, VerticalSegmentAndItsLine) {
  const Segment2 s{{1.0, 5.0}, {1.0, -5.0}};  // pointing South
  EXPECT_TRUE(s.Direction().isApprox(Eigen::Vector2d(0.0, -1.0), kTol));
  EXPECT_TRUE(s.LeftNormal().isApprox(Eigen::Vector2d(1.0, 0.0), kTol));
  EXPECT_DOUBLE_EQ(s.Distance({4.0, 2.0}), 3.0);
  const Line2 line = s.SupportingLine();
  EXPECT_NEAR(line.SignedDistance({4.0, 2.0}), 3.0, kTol);
  EXPECT_NEAR(line.SignedDistance(s.a), 0.0, kTol);
}

TEST(Segment2, DegenerateSegmentIsAPointForDistancesOnly) {
  const Segment2 s{{2.0, 2.0}, {2.0, 2.0}};
  EXPECT_FALSE(s.IsProper());
  EXPECT_DOUBLE_EQ(s.ClosestParam({5.0, 6.0}), 0.0);
  EXPECT_DOUBLE_EQ(s.Distance({5.0, 6.0}), 5.0);
  EXPECT_THROW(s.Direction(), std::invalid_argument);
  EXPECT_THROW(s.LeftNormal(), std::invalid_argument);
  EXPECT_THROW(s.SupportingLine(), std::invalid_argument);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE((Segment2{{nan, 0.0}, {1.0, 0.0}}).IsProper());
  EXPECT_THROW((Segment2{{nan, 0.0}, {1.0, 0.0}}).Direction(), std::invalid_argument);
  // Finite endpoints whose difference overflows.
  EXPECT_FALSE((Segment2{{-1e300, 0.0}, {1e300, 0.0}}).IsProper());
  EXPECT_TRUE((Segment2{{0.0, 0.0}, {1e-300, 0.0}}).IsProper());
}

// Property: the closest point lies on the segment and no sampled point of the segment is nearer.
TEST(Segment2, ClosestPointBeatsDenseSamplingOnRandomSegments) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  for (int i = 0; i < 500; ++i) {
    const Segment2 s{{u(rng), u(rng)}, {u(rng), u(rng)}};
    const Eigen::Vector2d x(u(rng), u(rng));
    const double param = s.ClosestParam(x);
    ASSERT_GE(param, 0.0);
    ASSERT_LE(param, 1.0);
    const double d = s.Distance(x);
    double sampled_min = std::numeric_limits<double>::infinity();
    for (int k = 0; k <= 2000; ++k) sampled_min = std::min(sampled_min, (x - s.PointAt(k / 2000.0)).norm());
    EXPECT_LE(d, sampled_min + 1e-12);
    EXPECT_GE(d, sampled_min - s.Length() / 2000.0);  // the sampling step bounds the gap
  }
}

}  // namespace
}  // namespace rowloc::geometry
