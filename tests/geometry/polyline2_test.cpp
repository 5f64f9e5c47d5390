// Polylines and polygons: the segment queries over a row (docs/planar-geometry.md).
#include "rowloc/geometry/polyline2.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>

namespace rowloc::geometry {
namespace {

constexpr double kTol = 1e-12;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

Polyline2 UnitSquare() { return Polyline2({{0.0, 0.0}, {1.0, 0.0}, {1.0, 1.0}, {0.0, 1.0}}, true); }

TEST(Polyline2, SegmentsOfOpenAndClosedPolylines) {
  const Polyline2 open({{0.0, 0.0}, {1.0, 0.0}, {1.0, 1.0}}, false);
  EXPECT_EQ(open.SegmentCount(), 2u);
  EXPECT_DOUBLE_EQ(open.Length(), 2.0);
  const Polyline2 square = UnitSquare();
  EXPECT_EQ(square.SegmentCount(), 4u);
  EXPECT_DOUBLE_EQ(square.Length(), 4.0);
  const Segment2 closing = square.Segment(3);
  EXPECT_EQ(closing.a, Eigen::Vector2d(0.0, 1.0));
  EXPECT_EQ(closing.b, Eigen::Vector2d(0.0, 0.0));
  EXPECT_THROW(square.Segment(4), std::out_of_range);
  EXPECT_THROW(open.Segment(2), std::out_of_range);
}

TEST(Polyline2, RejectsBadVertices) {
  EXPECT_THROW(Polyline2({{0.0, 0.0}}, false), std::invalid_argument);
  EXPECT_THROW(Polyline2({{0.0, 0.0}, {1.0, 0.0}}, true), std::invalid_argument);
  EXPECT_THROW(Polyline2({{0.0, 0.0}, {kNaN, 0.0}}, false), std::invalid_argument);
  EXPECT_THROW(Polyline2({{0.0, 0.0}, {1.0, 0.0}, {1.0, 0.0}}, false), std::invalid_argument);
  // Closing segment of zero length (first vertex repeated at the end of a polygon).
  EXPECT_THROW(Polyline2({{0.0, 0.0}, {1.0, 0.0}, {1.0, 1.0}, {0.0, 0.0}}, true), std::invalid_argument);
  Row row;
  row.id = "r";
  row.points_m = {{0.0, 0.0}};
  EXPECT_THROW(Polyline2::FromRow(row), std::invalid_argument);
}

TEST(Polyline2, FromRowKeepsVerticesAndClosure) {
  const RowMap map = MakeSampleRowMap(SampleRowMapParams{});
  const Polyline2 outline = Polyline2::FromRow(map.rows.front());
  EXPECT_TRUE(outline.closed());
  EXPECT_EQ(outline.SegmentCount(), map.rows.front().SegmentCount());
  EXPECT_EQ(outline.vertices(), map.rows.front().points_m);
}

TEST(Polyline2, PolygonDistanceIsToTheBoundary) {
  const Polyline2 square = UnitSquare();
  const auto inside = square.ClosestPoint({0.5, 0.3});
  EXPECT_NEAR(inside.distance_m, 0.3, kTol);
  EXPECT_EQ(inside.segment, 0u);
  EXPECT_NEAR(inside.segment_param, 0.5, kTol);
  EXPECT_NEAR(square.Distance({-0.2, 0.5}), 0.2, kTol);  // the closing segment
  EXPECT_EQ(square.ClosestPoint({-0.2, 0.5}).segment, 3u);
  EXPECT_NEAR(square.Distance({2.0, 2.0}), std::sqrt(2.0), kTol);
  EXPECT_THROW(square.ClosestPoint({kNaN, 0.0}), std::invalid_argument);
}

TEST(Polyline2, RayCastHitsNearSideFromOutsideAndBoundaryFromInside) {
  const Polyline2 square = UnitSquare();
  const auto outside = square.RayCast({-2.0, 0.5}, {1.0, 0.0}, 10.0);
  ASSERT_TRUE(outside.has_value());
  EXPECT_EQ(outside->segment, 3u);
  EXPECT_NEAR(outside->hit.range_m, 2.0, kTol);
  EXPECT_TRUE(outside->hit.normal.isApprox(Eigen::Vector2d(-1.0, 0.0)));
  const auto inside = square.RayCast({0.5, 0.5}, {0.0, 1.0}, 10.0);
  ASSERT_TRUE(inside.has_value());
  EXPECT_EQ(inside->segment, 2u);
  EXPECT_NEAR(inside->hit.range_m, 0.5, kTol);
  EXPECT_FALSE(square.RayCast({-2.0, 0.5}, {-1.0, 0.0}, 10.0).has_value());
  EXPECT_THROW(square.RayCast({0.0, 0.0}, {0.0, 0.0}, 1.0), std::invalid_argument);
  EXPECT_THROW(square.RayCast({0.0, 0.0}, {1.0, 0.0}, 0.0), std::invalid_argument);
}

TEST(Polyline2, RayThroughACornerReportsTheLowerSegment) {
  const Polyline2 square = UnitSquare();
  const auto hit = square.RayCast({2.0, 2.0}, {-1.0, -1.0}, 10.0);  // corner (1, 1)
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(hit->hit.range_m, std::sqrt(2.0), kTol);
  EXPECT_EQ(hit->segment, 1u);  // segments 1 and 2 share the corner
}

TEST(Polyline2, ConeCastAllAtAPolygonCornerReturnsBothSegments) {
  const Polyline2 square = UnitSquare();
  // Range 2 m: the far sides (segments 0 and 3, >= 2.6 m) are outside; casts ignore occlusion.
  const Cone2 cone{{2.0, 2.0}, {-1.0, -1.0}, 7.5 * std::numbers::pi / 180.0, 2.0};
  const auto all = square.ConeCastAll(cone);
  ASSERT_EQ(all.size(), 2u);
  EXPECT_NEAR(all[0].hit.range_m, std::sqrt(2.0), kTol);
  EXPECT_NEAR(all[1].hit.range_m, std::sqrt(2.0), kTol);
  EXPECT_EQ(all[0].segment + all[1].segment, 3u);  // segments 1 and 2
  const auto nearest = square.ConeCast(cone);
  ASSERT_TRUE(nearest.has_value());
  EXPECT_EQ(nearest->segment, 1u);
  EXPECT_THROW(square.ConeCast(Cone2{cone.apex, cone.axis, std::numbers::pi, 4.0}), std::invalid_argument);
}

// Property: the polyline queries are the minimum of the per-segment queries.
TEST(Polyline2, QueriesAreTheMinimumOverSegments) {
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi);
  std::vector<Eigen::Vector2d> vertices;
  for (int i = 0; i < 30; ++i) vertices.emplace_back(u(rng), u(rng));
  for (bool closed : {false, true}) {
    const Polyline2 line(vertices, closed);
    for (int q = 0; q < 300; ++q) {
      const Eigen::Vector2d x(u(rng), u(rng));
      const Eigen::Vector2d d(std::cos(angle(rng)), std::sin(angle(rng)));
      const Cone2 cone{x, d, 0.3, 4.0};
      double min_distance = std::numeric_limits<double>::infinity();
      double min_ray = min_distance, min_cone = min_distance;
      std::size_t cone_count = 0;
      for (std::size_t i = 0; i < line.SegmentCount(); ++i) {
        const Segment2 s = line.Segment(i);
        min_distance = std::min(min_distance, s.Distance(x));
        if (auto h = RayCast(s, x, d, 4.0)) min_ray = std::min(min_ray, h->range_m);
        if (auto h = ConeCast(s, cone)) {
          min_cone = std::min(min_cone, h->range_m);
          ++cone_count;
        }
      }
      EXPECT_EQ(line.Distance(x), min_distance);
      const auto ray = line.RayCast(x, d, 4.0);
      EXPECT_EQ(ray ? ray->hit.range_m : std::numeric_limits<double>::infinity(), min_ray);
      const auto cone_hit = line.ConeCast(cone);
      EXPECT_EQ(cone_hit ? cone_hit->hit.range_m : std::numeric_limits<double>::infinity(), min_cone);
      const auto all = line.ConeCastAll(cone);
      EXPECT_EQ(all.size(), cone_count);
      for (std::size_t k = 1; k < all.size(); ++k) EXPECT_LE(all[k - 1].hit.range_m, all[k].hit.range_m);
    }
  }
}

}  // namespace
}  // namespace rowloc::geometry
