// Ray cast against a segment (docs/planar-geometry.md): geometry, edge cases, bad input, and
// random rays checked against Boost.Geometry's segment intersection as an independent oracle.
#include "rowloc/geometry/ray_cast.hpp"

// Boost 1.74's Boost.Math (pulled in by Boost.Geometry) includes a header it itself deprecated.
#ifndef BOOST_ALLOW_DEPRECATED_HEADERS
#define BOOST_ALLOW_DEPRECATED_HEADERS
#endif

#include <boost/geometry/algorithms/intersection.hpp>
#include <boost/geometry/geometries/point.hpp>
#include <boost/geometry/geometries/segment.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

namespace rowloc::geometry {
namespace {

constexpr double kTol = 1e-12;
const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

Eigen::Vector2d Heading(double deg) {
  const double rad = deg * std::numbers::pi / 180.0;
  return {std::cos(rad), std::sin(rad)};
}

TEST(RayCast, PerpendicularHitReportsRangePointParamAndNormal) {
  const Segment2 wall{{-1.0, 2.0}, {3.0, 2.0}};
  const auto hit = RayCast(wall, {0.0, 0.0}, {0.0, 1.0}, 10.0);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(hit->range_m, 2.0, kTol);
  EXPECT_TRUE(hit->point.isApprox(Eigen::Vector2d(0.0, 2.0), kTol));
  EXPECT_NEAR(hit->segment_param, 0.25, kTol);
  EXPECT_TRUE(hit->normal.isApprox(Eigen::Vector2d(0.0, -1.0), kTol));  // faces the origin
  // From the other side the normal flips.
  const auto back = RayCast(wall, {0.0, 5.0}, {0.0, -1.0}, 10.0);
  ASSERT_TRUE(back.has_value());
  EXPECT_NEAR(back->range_m, 3.0, kTol);
  EXPECT_TRUE(back->normal.isApprox(Eigen::Vector2d(0.0, 1.0), kTol));
}

TEST(RayCast, DirectionIsNormalized) {
  const Segment2 wall{{5.0, -1.0}, {5.0, 1.0}};
  const auto unit = RayCast(wall, {0.0, 0.0}, {1.0, 0.0}, 10.0);
  const auto scaled = RayCast(wall, {0.0, 0.0}, {1e-3, 0.0}, 10.0);
  ASSERT_TRUE(unit && scaled);
  EXPECT_NEAR(unit->range_m, 5.0, kTol);
  EXPECT_NEAR(scaled->range_m, 5.0, kTol);
}

TEST(RayCast, OriginOnTheSegmentHitsAtRangeZero) {
  const Segment2 wall{{0.0, 0.0}, {4.0, 0.0}};
  for (const Eigen::Vector2d& d : {Eigen::Vector2d(0.0, 1.0), Eigen::Vector2d(0.0, -1.0),
                                   Eigen::Vector2d(1.0, 1.0)}) {
    const auto hit = RayCast(wall, {1.0, 0.0}, d, 5.0);
    ASSERT_TRUE(hit.has_value());
    EXPECT_EQ(hit->range_m, 0.0);
    EXPECT_NEAR(hit->segment_param, 0.25, kTol);
    // The normal opposes the travel direction: the side the ray comes from.
    EXPECT_LT(hit->normal.dot(d), 0.0);
  }
  // At an endpoint too.
  const auto at_end = RayCast(wall, {4.0, 0.0}, {0.0, 1.0}, 5.0);
  ASSERT_TRUE(at_end.has_value());
  EXPECT_EQ(at_end->range_m, 0.0);
  EXPECT_EQ(at_end->segment_param, 1.0);
}

TEST(RayCast, SegmentBehindTheOriginIsNotHit) {
  const Segment2 wall{{-1.0, -2.0}, {1.0, -2.0}};
  EXPECT_FALSE(RayCast(wall, {0.0, 0.0}, {0.0, 1.0}, 100.0).has_value());
  // Just past the segment, looking away from it.
  EXPECT_FALSE(RayCast(wall, {0.0, -2.0 + 1e-6}, {0.0, 1.0}, 100.0).has_value());
  // Collinear and behind.
  const Segment2 row{{-5.0, 0.0}, {-1.0, 0.0}};
  EXPECT_FALSE(RayCast(row, {0.0, 0.0}, {1.0, 0.0}, 100.0).has_value());
}

TEST(RayCast, CollinearOverlapGivesNearestPointOfOverlap) {
  const Segment2 row{{2.0, 0.0}, {6.0, 0.0}};
  // Ahead: the near endpoint, whichever way the segment is oriented.
  for (const Segment2& s : {row, Segment2{row.b, row.a}}) {
    const auto hit = RayCast(s, {0.0, 0.0}, {1.0, 0.0}, 10.0);
    ASSERT_TRUE(hit.has_value());
    EXPECT_NEAR(hit->range_m, 2.0, kTol);
    EXPECT_TRUE(hit->point.isApprox(Eigen::Vector2d(2.0, 0.0), kTol));
    EXPECT_TRUE(hit->normal.isApprox(s.LeftNormal(), kTol));  // documented choice for collinear rays
  }
  // Origin inside the segment: range 0 in both directions.
  EXPECT_EQ(RayCast(row, {3.0, 0.0}, {1.0, 0.0}, 10.0)->range_m, 0.0);
  EXPECT_EQ(RayCast(row, {3.0, 0.0}, {-1.0, 0.0}, 10.0)->range_m, 0.0);
  // Looking back along the row from beyond its end.
  EXPECT_NEAR(RayCast(row, {9.0, 0.0}, {-1.0, 0.0}, 10.0)->range_m, 3.0, kTol);
  // Overlap starts beyond max range.
  EXPECT_FALSE(RayCast(row, {0.0, 0.0}, {1.0, 0.0}, 1.9).has_value());
  // Parallel but offset: no hit.
  EXPECT_FALSE(RayCast(row, {0.0, 1e-6}, {1.0, 0.0}, 10.0).has_value());
}

TEST(RayCast, CollinearOverlapAlongTheDiagonal) {
  const Eigen::Vector2d d = Heading(45.0);
  const Segment2 row{3.0 * d, 7.0 * d};
  const auto hit = RayCast(row, {0.0, 0.0}, {1.0, 1.0}, 10.0);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(hit->range_m, 3.0, 1e-12);
  EXPECT_NEAR(hit->segment_param, 0.0, 1e-12);
}

TEST(RayCast, RayThroughAnEndpointHitsIt) {
  // Rows in every direction: aim exactly at each endpoint from the side.
  for (double deg : {0.0, 45.0, 90.0, 135.0, 180.0, 270.0}) {
    const Eigen::Vector2d t = Heading(deg);
    const Eigen::Vector2d n(-t.y(), t.x());
    const Segment2 row{2.0 * t, 6.0 * t};
    for (const double param : {0.0, 1.0}) {
      const Eigen::Vector2d end = row.PointAt(param);
      const Eigen::Vector2d origin = end + 3.0 * n + 1.0 * t;
      const auto hit = RayCast(row, origin, end - origin, 10.0);
      ASSERT_TRUE(hit.has_value()) << deg << " " << param;
      EXPECT_NEAR(hit->range_m, std::sqrt(10.0), 1e-12);
      EXPECT_NEAR(hit->segment_param, param, 1e-12);
    }
  }
}

TEST(RayCast, MaxRangeIsInclusiveAndClips) {
  const Segment2 wall{{3.0, -1.0}, {3.0, 1.0}};
  EXPECT_TRUE(RayCast(wall, {0.0, 0.0}, {1.0, 0.0}, 3.0).has_value());
  EXPECT_FALSE(RayCast(wall, {0.0, 0.0}, {1.0, 0.0}, 2.999).has_value());
  EXPECT_TRUE(RayCast(wall, {0.0, 0.0}, {1.0, 0.0}, kInf).has_value());
}

TEST(RayCast, BadInputThrows) {
  const Segment2 wall{{3.0, -1.0}, {3.0, 1.0}};
  const Eigen::Vector2d o(0.0, 0.0), d(1.0, 0.0);
  EXPECT_THROW(RayCast(wall, o, {0.0, 0.0}, 5.0), std::invalid_argument);
  EXPECT_THROW(RayCast(wall, o, {kNaN, 1.0}, 5.0), std::invalid_argument);
  EXPECT_THROW(RayCast(wall, o, {kInf, 0.0}, 5.0), std::invalid_argument);
  EXPECT_THROW(RayCast(wall, {kNaN, 0.0}, d, 5.0), std::invalid_argument);
  EXPECT_THROW(RayCast(wall, o, d, 0.0), std::invalid_argument);
  EXPECT_THROW(RayCast(wall, o, d, -1.0), std::invalid_argument);
  EXPECT_THROW(RayCast(wall, o, d, kNaN), std::invalid_argument);
  EXPECT_THROW(RayCast(Segment2{{1.0, 1.0}, {1.0, 1.0}}, o, d, 5.0), std::invalid_argument);
  EXPECT_THROW(RayCast(Segment2{{1.0, kInf}, {1.0, 1.0}}, o, d, 5.0), std::invalid_argument);
}

// Independent oracle: Boost.Geometry intersection of the segment with the ray clipped at max range.
std::optional<Eigen::Vector2d> BoostIntersection(const Segment2& s, const Eigen::Vector2d& o,
                                                 const Eigen::Vector2d& end) {
  namespace bg = boost::geometry;
  using P = bg::model::point<double, 2, bg::cs::cartesian>;
  using S = bg::model::segment<P>;
  std::vector<P> points;
  bg::intersection(S(P(s.a.x(), s.a.y()), P(s.b.x(), s.b.y())), S(P(o.x(), o.y()), P(end.x(), end.y())),
                   points);
  if (points.empty()) return std::nullopt;
  return Eigen::Vector2d(bg::get<0>(points.front()), bg::get<1>(points.front()));
}

TEST(RayCast, AgreesWithBoostGeometryOnRandomRays) {
  std::mt19937_64 rng(20240611);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi);
  int hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const Segment2 s{{u(rng), u(rng)}, {u(rng), u(rng)}};
    const Eigen::Vector2d o(u(rng), u(rng));
    const double a = angle(rng);
    const Eigen::Vector2d d(std::cos(a), std::sin(a));
    const double max_range = 12.0;
    const auto hit = RayCast(s, o, d, max_range);
    const auto oracle = BoostIntersection(s, o, o + max_range * d);
    ASSERT_EQ(hit.has_value(), oracle.has_value()) << "case " << i;
    if (!hit) continue;
    ++hits;
    EXPECT_LT((hit->point - *oracle).norm(), 1e-9);
    EXPECT_LT((o + hit->range_m * d - hit->point).norm(), 1e-9);
    EXPECT_LT(s.Distance(hit->point), 1e-9);
    EXPECT_NEAR(hit->normal.norm(), 1.0, 1e-12);
    EXPECT_NEAR(hit->normal.dot(s.b - s.a), 0.0, 1e-9);
    EXPECT_GT(hit->normal.dot(o - hit->point), 0.0);  // faces the origin
  }
  EXPECT_GT(hits, 2000);  // the sample exercises the hit branch
}

}  // namespace
}  // namespace rowloc::geometry
