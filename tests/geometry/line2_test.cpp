// Line2 in normal form (docs/planar-geometry.md: rows along y must work).
#include "rowloc/geometry/line2.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>

namespace rowloc::geometry {
namespace {

constexpr double kTol = 1e-12;
const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

TEST(Line2, HorizontalLineThroughTwoPoints) {
  const Line2 line = Line2::Through({-3.0, 2.0}, {5.0, 2.0});
  EXPECT_NEAR(line.normal.x(), 0.0, kTol);
  EXPECT_NEAR(line.normal.y(), 1.0, kTol);  // left of +x
  EXPECT_NEAR(line.offset, 2.0, kTol);
  EXPECT_NEAR(line.SignedDistance({7.0, 5.0}), 3.0, kTol);
  EXPECT_NEAR(line.SignedDistance({7.0, -1.0}), -3.0, kTol);
  EXPECT_TRUE(line.Project({7.0, 5.0}).isApprox(Eigen::Vector2d(7.0, 2.0), kTol));
}

TEST(Line2, VerticalLineWorksWhereSlopeInterceptFails) {
  // A row along +y (North): y = m x + q has no finite m here.
  const Line2 line = Line2::Through({2.0, 0.0}, {2.0, 5.0});
  EXPECT_NEAR(line.normal.x(), -1.0, kTol);
  EXPECT_NEAR(line.normal.y(), 0.0, kTol);
  EXPECT_NEAR(line.offset, -2.0, kTol);
  EXPECT_NEAR(line.SignedDistance({5.0, 1.0}), -3.0, kTol);
  EXPECT_NEAR(line.Distance({5.0, 1.0}), 3.0, kTol);
  EXPECT_NEAR(line.Distance({-1.0, 100.0}), 3.0, kTol);
  EXPECT_TRUE(line.Project({5.0, 1.0}).isApprox(Eigen::Vector2d(2.0, 1.0), kTol));
  EXPECT_TRUE(line.Direction().isApprox(Eigen::Vector2d(0.0, 1.0), kTol));
}

// Rows in every direction, including both axes and both orientations.
class Line2Direction : public ::testing::TestWithParam<double> {};

TEST_P(Line2Direction, DistancesAndProjectionFollowTheRow) {
  const double heading = GetParam() * std::numbers::pi / 180.0;
  const Eigen::Vector2d t(std::cos(heading), std::sin(heading));
  const Eigen::Vector2d n(-t.y(), t.x());
  const Eigen::Vector2d a(3.0, -7.0);
  const Line2 line = Line2::Through(a, a + 10.0 * t);
  EXPECT_NEAR(line.normal.norm(), 1.0, kTol);
  EXPECT_TRUE(line.Direction().isApprox(t, kTol));
  for (double along : {-50.0, 0.0, 4.0, 80.0}) {
    for (double across : {-2.5, 0.0, 1.25}) {
      const Eigen::Vector2d x = a + along * t + across * n;
      EXPECT_NEAR(line.SignedDistance(x), across, 1e-11);
      EXPECT_LT((line.Project(x) - (a + along * t)).norm(), 1e-11);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Headings, Line2Direction,
                         ::testing::Values(0.0, 30.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0));

TEST(Line2, RandomLinesSatisfyProjectionProperties) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-100.0, 100.0);
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector2d a(u(rng), u(rng)), b(u(rng), u(rng)), x(u(rng), u(rng));
    const Line2 line = Line2::Through(a, b);
    EXPECT_NEAR(line.normal.norm(), 1.0, 1e-14);
    EXPECT_NEAR(line.SignedDistance(a), 0.0, 1e-10);
    EXPECT_NEAR(line.SignedDistance(b), 0.0, 1e-10);
    const Eigen::Vector2d p = line.Project(x);
    EXPECT_NEAR(line.SignedDistance(p), 0.0, 1e-10);
    // x - P(x) is along the normal, and P(x) is the nearest point of the line.
    EXPECT_NEAR(std::abs((x - p).dot(line.normal)), (x - p).norm(), 1e-9);
    EXPECT_LE((x - p).norm(), (x - a).norm() + 1e-12);
    EXPECT_LE((x - p).norm(), (x - b).norm() + 1e-12);
  }
}

TEST(Line2, FromNormalNormalizes) {
  const Line2 line = Line2::FromNormal({0.0, -4.0}, 8.0);  // -4 y = 8  <=>  y = -2
  EXPECT_NEAR(line.normal.y(), -1.0, kTol);
  EXPECT_NEAR(line.offset, 2.0, kTol);
  EXPECT_NEAR(line.SignedDistance({0.0, -2.0}), 0.0, kTol);
  EXPECT_THROW(Line2::FromNormal({0.0, 0.0}, 1.0), std::invalid_argument);
  EXPECT_THROW(Line2::FromNormal({kNaN, 1.0}, 1.0), std::invalid_argument);
  EXPECT_THROW(Line2::FromNormal({1.0, 0.0}, kInf), std::invalid_argument);
}

TEST(Line2, ThroughRejectsCoincidentAndNonFinitePoints) {
  EXPECT_THROW(Line2::Through({1.0, 2.0}, {1.0, 2.0}), std::invalid_argument);
  EXPECT_THROW(Line2::Through({kNaN, 2.0}, {1.0, 2.0}), std::invalid_argument);
  EXPECT_THROW(Line2::Through({1.0, 2.0}, {kInf, 2.0}), std::invalid_argument);
  // Finite points whose difference overflows.
  EXPECT_THROW(Line2::Through({-1e308, 0.0}, {1e308, 0.0}), std::invalid_argument);
}

TEST(Line2, IntersectMeetsBothLinesOrReportsParallel) {
  const Line2 vertical = Line2::Through({2.0, 0.0}, {2.0, 1.0});
  const Line2 horizontal = Line2::Through({0.0, -3.0}, {1.0, -3.0});
  const auto p = vertical.Intersect(horizontal);
  ASSERT_TRUE(p.has_value());
  EXPECT_TRUE(p->isApprox(Eigen::Vector2d(2.0, -3.0), kTol));
  EXPECT_FALSE(vertical.Intersect(Line2::Through({5.0, 0.0}, {5.0, -1.0})).has_value());
  EXPECT_FALSE(vertical.Intersect(vertical).has_value());

  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  for (int i = 0; i < 500; ++i) {
    const Line2 l1 = Line2::Through({u(rng), u(rng)}, {u(rng), u(rng)});
    const Line2 l2 = Line2::Through({u(rng), u(rng)}, {u(rng), u(rng)});
    const auto x = l1.Intersect(l2);
    ASSERT_TRUE(x.has_value());
    const double scale = 1.0 + x->norm();
    EXPECT_NEAR(l1.SignedDistance(*x), 0.0, 1e-9 * scale);
    EXPECT_NEAR(l2.SignedDistance(*x), 0.0, 1e-9 * scale);
  }
}

}  // namespace
}  // namespace rowloc::geometry
