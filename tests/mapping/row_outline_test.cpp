// TraceOutline: the outline of a box row and of an arc row traced from face and cap samples.
#include "rowloc/mapping/row_outline.hpp"

#include "rowloc/geometry/row_map.hpp"
#include "rowloc/geometry/segment_index.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

namespace rowloc::mapping {
namespace {

/// Largest distance of any point of `points` from the closed polygon.
double WorstDistance(const std::vector<Eigen::Vector2d>& polygon, const std::vector<Eigen::Vector2d>& points) {
  geometry::RowMap map;
  map.rows.push_back(geometry::Row{"r", polygon, true});
  const auto index = geometry::SegmentIndex::FromRowMap(map);
  double worst = 0.0;
  for (const auto& p : points) worst = std::max(worst, index.Nearest(p, 1).front().first);
  return worst;
}

TEST(RowOutlineTest, BoxRowGivesItsRectangle) {
  // Faces at y = +-0.3 over x in [2, 12], caps at x = 2 and 12, 5 mm noise, several heights.
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.005);
  std::vector<Eigen::Vector2d> points;
  for (double x = 2.0; x <= 12.0; x += 0.05) {
    for (int h = 0; h < 6; ++h) {
      points.emplace_back(x, 0.3 + noise(rng));
      points.emplace_back(x, -0.3 + noise(rng));
    }
  }
  for (double y = -0.25; y <= 0.25; y += 0.05) {
    for (int h = 0; h < 6; ++h) {
      points.emplace_back(2.0 + noise(rng), y);
      points.emplace_back(12.0 + noise(rng), y);
    }
  }
  const PartOutline outline = TraceOutline(points, OutlineParams{});
  ASSERT_GE(outline.polygon_m.size(), 4U);
  EXPECT_NEAR(outline.length_m, 10.0, 0.03);
  EXPECT_GT(geometry::OutlineSignedArea(geometry::Row{"r", outline.polygon_m, true}), 0.0);  // counter-clockwise
  EXPECT_NEAR(geometry::OutlineSignedArea(geometry::Row{"r", outline.polygon_m, true}), 6.0, 0.1);
  // Every vertex within 1.5 cm of the true rectangle, and the rectangle's corners within 2 cm.
  const std::vector<Eigen::Vector2d> rectangle = {{2, -0.3}, {12, -0.3}, {12, 0.3}, {2, 0.3}};
  EXPECT_LT(WorstDistance(rectangle, outline.polygon_m), 0.015);
  EXPECT_LT(WorstDistance(outline.polygon_m, rectangle), 0.02);
}

TEST(RowOutlineTest, ArcRowFollowsTheCurve) {
  // A 60-degree arc of radius 20 m, canopy 0.5 m wide; the chord would be 2.7 m off at mid-arc.
  std::vector<Eigen::Vector2d> points;
  const double r = 20.0;
  for (double a = 0.0; a <= M_PI / 3; a += 0.02 / r) {
    for (double w : {-0.25, 0.25}) points.emplace_back((r + w) * std::cos(a), (r + w) * std::sin(a));
  }
  const PartOutline outline = TraceOutline(points, OutlineParams{});
  ASSERT_GE(outline.polygon_m.size(), 4U);
  EXPECT_NEAR(outline.length_m, r * M_PI / 3, 0.1);
  double worst = 0.0;
  for (const auto& p : outline.polygon_m) {
    const double d = p.norm();
    worst = std::max(worst, std::min(std::abs(d - (r - 0.25)), std::abs(d - (r + 0.25))));
  }
  EXPECT_LT(worst, 0.01);
}

TEST(RowOutlineTest, TooFewPointsGiveNoOutlineAndBadParametersThrow) {
  EXPECT_TRUE(TraceOutline({{0, 0}, {1, 0}}, OutlineParams{}).polygon_m.empty());
  // A lone face (5 mm noise across): narrower than min_width_m, no outline.
  std::vector<Eigen::Vector2d> line;
  for (double x = 0.0; x < 5.0; x += 0.01) line.emplace_back(x, 0.005 * std::sin(37.0 * x));
  const PartOutline lone = TraceOutline(line, OutlineParams{});
  EXPECT_TRUE(lone.polygon_m.empty());
  EXPECT_LT(lone.median_width_m, 0.02);
  OutlineParams bad;
  bad.edge_quantile = 2.0;
  EXPECT_THROW(TraceOutline(line, bad), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::mapping
