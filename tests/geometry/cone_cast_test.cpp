// Cone cast (docs/planar-geometry.md): the nearest point of a segment inside a sector.
#include "rowloc/geometry/cone_cast.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>

namespace rowloc::geometry {
namespace {

constexpr double kPi = std::numbers::pi;
// Random cases per property test: unoptimized (sanitizer) builds run a tenth.
#ifdef NDEBUG
constexpr int kCases = 3000;
#else
constexpr int kCases = 300;
#endif
const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

double Deg(double deg) { return deg * kPi / 180.0; }
Eigen::Vector2d Heading(double rad) { return {std::cos(rad), std::sin(rad)}; }

// A wall at perpendicular distance d from the apex, seen with the axis at angle theta from the
// wall's normal: the nearest point in the sector is at d if |theta| <= h (the perpendicular is
// inside the cone), otherwise on the nearer edge ray at d / cos(|theta| - h).
double AnalyticWallRange(double d, double theta, double h) {
  return std::abs(theta) <= h ? d : d / std::cos(std::abs(theta) - h);
}

class ConeCastWall : public ::testing::TestWithParam<double> {};

TEST_P(ConeCastWall, MatchesAnalyticRangeOfALongWall) {
  const double wall_heading = Deg(GetParam());
  const Eigen::Vector2d t = Heading(wall_heading);
  const Eigen::Vector2d n(-t.y(), t.x());  // from the apex towards the wall
  const Eigen::Vector2d apex(1.5, -2.0);
  const double d = 1.25;
  const Segment2 wall{apex + d * n - 500.0 * t, apex + d * n + 500.0 * t};
  for (double h_deg : {0.0, 1.0, 7.5, 30.0, 60.0, 89.0}) {
    for (double theta_deg : {-80.0, -45.0, -7.5, -3.0, 0.0, 2.0, 7.5, 20.0, 60.0, 85.0}) {
      const double h = Deg(h_deg), theta = Deg(theta_deg);
      const Cone2 cone{apex, Heading(wall_heading + kPi / 2.0 + theta), h, 100.0};
      const auto hit = ConeCast(wall, cone);
      ASSERT_TRUE(hit.has_value()) << h_deg << " " << theta_deg;
      EXPECT_NEAR(hit->range_m, AnalyticWallRange(d, theta, h), 1e-9) << h_deg << " " << theta_deg;
      EXPECT_NEAR((hit->point - apex).norm(), hit->range_m, 1e-9);
      EXPECT_TRUE(hit->normal.isApprox(-n, 1e-12));  // faces the apex
    }
  }
}

INSTANTIATE_TEST_SUITE_P(RowHeadings, ConeCastWall,
                         ::testing::Values(0.0, 45.0, 90.0, 135.0, 180.0, 270.0, 17.0));

TEST(ConeCast, LooksAwayOrTooShortMissesTheWall) {
  const Segment2 wall{{-100.0, 2.0}, {100.0, 2.0}};
  EXPECT_FALSE(ConeCast(wall, Cone2{{0.0, 0.0}, {0.0, -1.0}, Deg(30.0), 10.0}).has_value());
  // Axis along the wall: the upper edge (30 deg) meets it at 2 / sin(30 deg) = 4 m.
  EXPECT_FALSE(ConeCast(wall, Cone2{{0.0, 0.0}, {1.0, 0.0}, Deg(30.0), 3.9}).has_value());
  EXPECT_NEAR(ConeCast(wall, Cone2{{0.0, 0.0}, {1.0, 0.0}, Deg(30.0), 10.0})->range_m, 4.0, 1e-12);
  EXPECT_FALSE(ConeCast(wall, Cone2{{0.0, 0.0}, {0.0, 1.0}, Deg(7.5), 1.999}).has_value());
  const auto at_limit = ConeCast(wall, Cone2{{0.0, 0.0}, {0.0, 1.0}, Deg(7.5), 2.0});
  ASSERT_TRUE(at_limit.has_value());
  EXPECT_DOUBLE_EQ(at_limit->range_m, 2.0);
  // Edge ray hits at 2/cos(30 deg) = 2.309: clipped at 2.3, seen at 2.31.
  const Cone2 tilted{{0.0, 0.0}, Heading(Deg(90.0 - 60.0)), Deg(30.0), 2.3};
  EXPECT_FALSE(ConeCast(wall, tilted).has_value());
  EXPECT_NEAR(ConeCast(wall, Cone2{tilted.apex, tilted.axis, tilted.half_aperture_rad, 2.31})->range_m,
              2.0 / std::cos(Deg(30.0)), 1e-12);
}

TEST(ConeCast, EndpointInsideTheSectorIsTheNearestPoint) {
  // The segment starts inside the cone and leaves it; its closest point to the apex is outside.
  const Segment2 s{{3.0, 0.1}, {3.0, 50.0}};
  const auto hit = ConeCast(s, Cone2{{0.0, 0.0}, {1.0, 0.0}, Deg(10.0), 10.0});
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(hit->segment_param, 0.0, 1e-15);
  EXPECT_NEAR(hit->range_m, std::hypot(3.0, 0.1), 1e-12);
}

TEST(ConeCast, NearestPointOnAnEdgeWhenTheClosestPointIsOutside) {
  // Enters the sector at a = (3, 0.3) and leaves it through the counter-clockwise edge; its point
  // closest to the apex, (2.65, 1.13), is outside, so the answer is the crossing of that edge.
  const Segment2 s{{3.0, 0.3}, {1.0, 5.0}};
  const double h = Deg(10.0);
  const auto hit = ConeCast(s, Cone2{{0.0, 0.0}, {1.0, 0.0}, h, 10.0});
  const auto edge = RayCast(s, {0.0, 0.0}, Heading(h), 10.0);
  ASSERT_TRUE(hit && edge);
  EXPECT_NEAR(hit->range_m, edge->range_m, 1e-12);
  EXPECT_LT(hit->range_m, s.a.norm());
}

TEST(ConeCast, ApexOnTheSegmentGivesRangeZero) {
  const Segment2 s{{-1.0, 0.0}, {1.0, 0.0}};
  const auto hit = ConeCast(s, Cone2{{0.5, 0.0}, {0.0, 1.0}, Deg(5.0), 3.0});
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(hit->range_m, 0.0);
  EXPECT_NEAR(hit->segment_param, 0.75, 1e-15);
  EXPECT_TRUE(hit->normal.isApprox(Eigen::Vector2d(0.0, -1.0)));  // against the axis
}

TEST(ConeCast, CollinearSegmentAlongAnEdgeRay) {
  // Half aperture 20 deg, segment lying on the counter-clockwise edge from r = 2 to r = 5.
  const double h = Deg(20.0);
  const Eigen::Vector2d edge = Heading(h);
  const Segment2 s{5.0 * edge, 2.0 * edge};
  const auto hit = ConeCast(s, Cone2{{0.0, 0.0}, {1.0, 0.0}, h, 10.0});
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(hit->range_m, 2.0, 1e-12);
  EXPECT_NEAR(hit->segment_param, 1.0, 1e-12);
}

TEST(ConeCast, NonUnitAxisIsNormalized) {
  const Segment2 wall{{-10.0, 2.0}, {10.0, 2.0}};
  const auto unit = ConeCast(wall, Cone2{{0.0, 0.0}, Heading(Deg(80.0)), Deg(5.0), 10.0});
  const auto scaled = ConeCast(wall, Cone2{{0.0, 0.0}, 7.0 * Heading(Deg(80.0)), Deg(5.0), 10.0});
  ASSERT_TRUE(unit && scaled);
  EXPECT_DOUBLE_EQ(unit->range_m, scaled->range_m);
  EXPECT_NEAR(unit->range_m, 2.0 / std::cos(Deg(5.0)), 1e-12);
}

TEST(ConeCast, BadInputThrows) {
  const Segment2 wall{{-10.0, 2.0}, {10.0, 2.0}};
  const Eigen::Vector2d o(0.0, 0.0), axis(0.0, 1.0);
  EXPECT_THROW(ConeCast(wall, Cone2{o, axis, kPi / 2.0, 5.0}), std::invalid_argument);
  EXPECT_THROW(ConeCast(wall, Cone2{o, axis, 2.0, 5.0}), std::invalid_argument);
  EXPECT_THROW(ConeCast(wall, Cone2{o, axis, -0.1, 5.0}), std::invalid_argument);
  EXPECT_THROW(ConeCast(wall, Cone2{o, axis, kNaN, 5.0}), std::invalid_argument);
  EXPECT_THROW(ConeCast(wall, Cone2{o, axis, kInf, 5.0}), std::invalid_argument);
  EXPECT_THROW(ConeCast(wall, Cone2{o, {0.0, 0.0}, 0.1, 5.0}), std::invalid_argument);
  EXPECT_THROW(ConeCast(wall, Cone2{o, {kNaN, 1.0}, 0.1, 5.0}), std::invalid_argument);
  EXPECT_THROW(ConeCast(wall, Cone2{{kInf, 0.0}, axis, 0.1, 5.0}), std::invalid_argument);
  EXPECT_THROW(ConeCast(wall, Cone2{o, axis, 0.1, 0.0}), std::invalid_argument);
  EXPECT_THROW(ConeCast(wall, Cone2{o, axis, 0.1, -2.0}), std::invalid_argument);
  EXPECT_THROW(ConeCast(wall, Cone2{o, axis, 0.1, kNaN}), std::invalid_argument);
  EXPECT_THROW(ConeCast(Segment2{{1.0, 2.0}, {1.0, 2.0}}, Cone2{o, axis, 0.1, 5.0}),
               std::invalid_argument);
  EXPECT_NO_THROW(ConeCast(wall, Cone2{o, axis, kPi / 2.0 - 1e-9, kInf}));
}

TEST(ConeCast, ZeroApertureIsARayCast) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  int hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const Segment2 s{{u(rng), u(rng)}, {u(rng), u(rng)}};
    const Eigen::Vector2d apex(u(rng), u(rng));
    const Eigen::Vector2d axis = Heading(angle(rng));
    const auto cone = ConeCast(s, Cone2{apex, axis, 0.0, 6.0});
    const auto ray = RayCast(s, apex, axis, 6.0);
    ASSERT_EQ(cone.has_value(), ray.has_value()) << i;
    if (!cone) continue;
    ++hits;
    EXPECT_NEAR(cone->range_m, ray->range_m, 1e-9);
    EXPECT_LT((cone->point - ray->point).norm(), 1e-9);
  }
  EXPECT_GT(hits, 1000);
}

// Brute force: the minimum of |x - apex| over dense samples of the segment inside the sector.
// The cast must find a point of the sector at least as near as every sample, and must hit
// whenever a sample is inside.
TEST(ConeCast, NeverBeatenByDenseSamplingOnRandomCases) {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  std::uniform_real_distribution<double> aperture(0.0, Deg(89.0));
  constexpr int kSamples = 4000;
  int hits = 0;
  for (int i = 0; i < kCases; ++i) {
    const Segment2 s{{u(rng), u(rng)}, {u(rng), u(rng)}};
    const Cone2 cone{{u(rng), u(rng)}, Heading(angle(rng)), aperture(rng), 6.0};
    const PreparedCone prepared(cone);
    double sampled_min = kInf;
    for (int k = 0; k <= kSamples; ++k) {
      const Eigen::Vector2d x = s.PointAt(static_cast<double>(k) / kSamples);
      const double r = (x - cone.apex).norm();
      if (prepared.SectorContains(x) && r <= cone.max_range_m) sampled_min = std::min(sampled_min, r);
    }
    const auto hit = ConeCast(s, cone);
    if (sampled_min < kInf) {
      ASSERT_TRUE(hit.has_value()) << i;
    }
    if (!hit) continue;
    ++hits;
    EXPECT_LE(hit->range_m, sampled_min + 1e-9) << i;
    EXPECT_LE(hit->range_m, cone.max_range_m);
    EXPECT_NEAR((hit->point - cone.apex).norm(), hit->range_m, 1e-9);
    EXPECT_LT(s.Distance(hit->point), 1e-9);
    // The point is inside the sector up to rounding: its angle from the axis is <= h.
    const Eigen::Vector2d v = hit->point - cone.apex;
    if (v.norm() > 1e-6) {
      const double off_axis = std::atan2(std::abs(cone.axis.x() * v.y() - cone.axis.y() * v.x()),
                                         cone.axis.dot(v));
      EXPECT_LE(off_axis, cone.half_aperture_rad + 1e-9) << i;
    }
  }
  EXPECT_GT(hits, kCases / 10);
}

}  // namespace
}  // namespace rowloc::geometry
