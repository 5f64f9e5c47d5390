// SimplifyPolygon: CGAL Polyline_simplification_2 within the tolerance; unchanged when it cannot.
#include "rowloc/mapping/polyline_simplification.hpp"

#include "rowloc/geometry/row_map.hpp"
#include "rowloc/geometry/segment_index.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace rowloc::mapping {
namespace {

double WorstDistance(const std::vector<Eigen::Vector2d>& polygon, const std::vector<Eigen::Vector2d>& points) {
  geometry::RowMap map;
  map.rows.push_back(geometry::Row{"r", polygon, true, 0.0});
  const auto index = geometry::SegmentIndex::FromRowMap(map);
  double worst = 0.0;
  for (const auto& p : points) worst = std::max(worst, index.Nearest(p, 1).front().first);
  return worst;
}

TEST(PolylineSimplificationTest, CollinearVerticesOfARectangleGo) {
  std::vector<Eigen::Vector2d> polygon;
  for (double x = 0.0; x < 10.0; x += 0.05) polygon.emplace_back(x, 0.0);
  for (double x = 10.0; x > 0.0; x -= 0.05) polygon.emplace_back(x, 0.5);
  const SimplifiedPolygon simple = SimplifyPolygon(polygon, 0.001);
  EXPECT_TRUE(simple.simplified);
  EXPECT_EQ(simple.points_m.size(), 4U);
}

TEST(PolylineSimplificationTest, AWavyOutlineStaysWithinTheTolerance) {
  std::vector<Eigen::Vector2d> polygon;
  for (double x = 0.0; x < 20.0; x += 0.05) polygon.emplace_back(x, 0.03 * std::sin(x));
  for (double x = 20.0; x > 0.0; x -= 0.05) polygon.emplace_back(x, 0.5 + 0.03 * std::sin(x));
  for (double tolerance : {0.002, 0.005, 0.01}) {
    const SimplifiedPolygon simple = SimplifyPolygon(polygon, tolerance);
    ASSERT_TRUE(simple.simplified);
    EXPECT_LT(simple.points_m.size(), polygon.size() / 4);
    EXPECT_LE(WorstDistance(simple.points_m, polygon), tolerance * 1.0001);
  }
}

TEST(PolylineSimplificationTest, UnchangedWhenItCannotOrNeedNot) {
  const std::vector<Eigen::Vector2d> bowtie = {{0, 0}, {2, 0}, {1.5, 0.5}, {0, 1}, {1, -1}};  // self-intersecting
  SimplifiedPolygon simple = SimplifyPolygon(bowtie, 0.1);
  EXPECT_FALSE(simple.simplified);
  EXPECT_EQ(simple.points_m, bowtie);
  const std::vector<Eigen::Vector2d> square = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  simple = SimplifyPolygon(square, 0.0);
  EXPECT_FALSE(simple.simplified);
  EXPECT_EQ(simple.points_m, square);
  EXPECT_THROW(SimplifyPolygon(square, -1.0), std::invalid_argument);
  EXPECT_THROW(SimplifyPolygon({{0, 0}, {1, NAN}, {1, 1}, {0, 1}}, 0.1), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::mapping
