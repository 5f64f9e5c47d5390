// TraceOutline: the outline of a box row and of an arc row traced from face and cap samples;
// TraceOneSidedOutline: the same rows seen from one side, their hidden face from the canopy top.
#include "rowloc/mapping/row_outline.hpp"

#include "rowloc/geometry/row_map.hpp"
#include "rowloc/geometry/segment_index.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace rowloc::mapping {
namespace {

/// Largest distance of any point of `points` from the closed polygon.
double WorstDistance(const std::vector<Eigen::Vector2d>& polygon, const std::vector<Eigen::Vector2d>& points) {
  geometry::RowMap map;
  map.rows.push_back(geometry::Row{"r", polygon, true, 0.0});
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
  EXPECT_GT(geometry::OutlineSignedArea(geometry::Row{"r", outline.polygon_m, true, 0.0}), 0.0);  // counter-clockwise
  EXPECT_NEAR(geometry::OutlineSignedArea(geometry::Row{"r", outline.polygon_m, true, 0.0}), 6.0, 0.1);
  // Every vertex within 1.5 cm of the true rectangle, and the rectangle's corners within 2 cm.
  const std::vector<Eigen::Vector2d> rectangle = {{2, -0.3}, {12, -0.3}, {12, 0.3}, {2, 0.3}};
  EXPECT_LT(WorstDistance(rectangle, outline.polygon_m), 0.015);
  EXPECT_LT(WorstDistance(outline.polygon_m, rectangle), 0.02);
}

/// A 10 m row whose faces at +-0.3 m move by a random offset of `station_sigma_m` per 5 cm of
/// length (a leafy canopy), 12 points per station and face with 2 mm noise.
std::vector<Eigen::Vector2d> RoughRow(double station_sigma_m, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> offset(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.002);
  std::vector<Eigen::Vector2d> points;
  for (double x = 2.0; x <= 12.0; x += 0.05) {
    const double left = 0.3 + station_sigma_m * offset(rng);
    const double right = -0.3 + station_sigma_m * offset(rng);
    for (int h = 0; h < 12; ++h) {
      points.emplace_back(x + 0.004 * h, left + noise(rng));
      points.emplace_back(x + 0.004 * h, right + noise(rng));
    }
  }
  return points;
}

TEST(RowOutlineTest, TheEdgeNoiseGrowsWithTheCanopysRoughness) {
  // Smooth faces: the edges' estimates scatter by about a millimetre. Rough faces: the estimate
  // is the roughness that the median of three stations leaves (0.67 of it).
  const double smooth = TraceOutline(RoughRow(0.0, 3), OutlineParams{}).edge_noise_m;
  EXPECT_LT(smooth, 0.0015);
  double previous = smooth;
  for (const double sigma : {0.01, 0.02, 0.04}) {
    const PartOutline outline = TraceOutline(RoughRow(sigma, 5), OutlineParams{});
    ASSERT_FALSE(outline.polygon_m.empty());
    EXPECT_GT(outline.edge_noise_m, 0.55 * sigma) << sigma;
    EXPECT_LT(outline.edge_noise_m, 0.8 * sigma) << sigma;
    EXPECT_GT(outline.edge_noise_m, previous);
    previous = outline.edge_noise_m;
    EXPECT_FALSE(outline.one_sided);
    EXPECT_EQ(outline.width_sigma_m, 0.0);  // both faces seen: the width is measured, not inferred
  }
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

/// A scan from one side of a box row over x in [2, 12]: its face at y = face_y (band points, 5 mm
/// noise, and the caps' band points across the canopy) and the top's cells over y in [lo, hi]
/// (one point in each 5 cm cell), plus the tops of the neighbouring rows 2.5 m away on both sides.
struct OneSidedScan {
  std::vector<Eigen::Vector2d> face;
  std::vector<Eigen::Vector2d> top;
};

OneSidedScan ScanFromOneSide(double face_y, double lo, double hi, double top_until_x = 12.0) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 0.005);
  OneSidedScan scan;
  for (double x = 2.0; x <= 12.0; x += 0.02) {
    for (int h = 0; h < 4; ++h) scan.face.emplace_back(x, face_y + noise(rng));
  }
  for (double y = lo + 0.05; y <= hi - 0.05; y += 0.05) {
    for (int h = 0; h < 4; ++h) {
      scan.face.emplace_back(2.0 + noise(rng), y);
      scan.face.emplace_back(12.0 + noise(rng), y);
    }
  }
  // The top as the map build keeps it: one point of each 5 cm cell, anywhere in the cell.
  std::uniform_real_distribution<double> in_cell(0.0, 0.05);
  for (double shift : {-2.5, 0.0, 2.5}) {
    for (double x = 2.0; x < top_until_x; x += 0.05) {
      for (double y = lo; y < hi - 1e-9; y += 0.05) scan.top.emplace_back(x + in_cell(rng), y + in_cell(rng) + shift);
    }
  }
  return scan;
}

TEST(RowOneSidedOutlineTest, TheHiddenFaceComesFromTheTopOnEitherSide) {
  const std::vector<Eigen::Vector2d> rectangle = {{2, -0.3}, {12, -0.3}, {12, 0.3}, {2, 0.3}};
  for (const double face_y : {0.3, -0.3}) {
    SCOPED_TRACE(face_y);
    const OneSidedScan scan = ScanFromOneSide(face_y, -0.3, 0.3);
    // The two-sided route sees one face, too narrow to be a canopy.
    EXPECT_TRUE(TraceOutline(scan.face, OutlineParams{}).polygon_m.empty());
    const PartOutline outline = TraceOneSidedOutline(scan.face, scan.top, OutlineParams{});
    ASSERT_GE(outline.polygon_m.size(), 4U);
    EXPECT_TRUE(outline.one_sided);
    EXPECT_NEAR(outline.median_width_m, 0.6, 0.02);
    EXPECT_LT(outline.width_spread_m, 0.02);
    // The width is inferred from the top's points: its stated sigma is positive and small.
    EXPECT_GT(outline.width_sigma_m, 0.0);
    EXPECT_LT(outline.width_sigma_m, 0.02);
    EXPECT_NEAR(outline.length_m, 10.0, 0.03);
    EXPECT_NEAR(geometry::OutlineSignedArea(geometry::Row{"r", outline.polygon_m, true, 0.0}), 6.0, 0.15);
    EXPECT_LT(WorstDistance(rectangle, outline.polygon_m), 0.025);
    EXPECT_LT(WorstDistance(outline.polygon_m, rectangle), 0.03);
  }
}

TEST(RowOneSidedOutlineTest, ArcRowSeenFromOutsideFollowsTheCurve) {
  // A 60-degree arc of radius 20 m, canopy 0.5 m wide, seen from outside (its face at r + 0.25).
  const double r = 20.0;
  std::vector<Eigen::Vector2d> face;
  std::vector<Eigen::Vector2d> top;
  for (double a = 0.0; a <= M_PI / 3; a += 0.02 / r) face.emplace_back((r + 0.25) * std::cos(a), (r + 0.25) * std::sin(a));
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> in_cell(0.0, 0.05);
  for (double a = 0.0; a < M_PI / 3; a += 0.05 / r) {  // one point in each cell of about 5 cm
    for (double w = -0.25; w < 0.25 - 1e-9; w += 0.05) {
      const double b = a + in_cell(rng) / r;
      const double u = w + in_cell(rng);
      top.emplace_back((r + u) * std::cos(b), (r + u) * std::sin(b));
    }
  }
  const PartOutline outline = TraceOneSidedOutline(face, top, OutlineParams{});
  ASSERT_GE(outline.polygon_m.size(), 4U);
  double worst = 0.0;
  for (const auto& p : outline.polygon_m) {
    const double d = p.norm();
    const double a = std::atan2(p.y(), p.x());
    const double to_faces = std::min(std::abs(d - (r - 0.25)), std::abs(d - (r + 0.25)));
    const double to_caps = std::min(std::abs(a), std::abs(a - M_PI / 3)) * r;
    worst = std::max(worst, std::min(to_faces, to_caps));
  }
  EXPECT_LT(worst, 0.02);
}

TEST(RowOneSidedOutlineTest, WithoutEnoughOfTheTopOrWithTheRouteOffThereIsNoOutline) {
  const OneSidedScan scan = ScanFromOneSide(0.3, -0.3, 0.3);
  EXPECT_TRUE(TraceOneSidedOutline(scan.face, {}, OutlineParams{}).polygon_m.empty());
  // The top seen along less than half of the part: its width would be guessed.
  const OneSidedScan partial = ScanFromOneSide(0.3, -0.3, 0.3, 6.0);
  EXPECT_TRUE(TraceOneSidedOutline(partial.face, partial.top, OutlineParams{}).polygon_m.empty());
  OutlineParams off;
  off.one_sided_max_width_m = 0.0;
  EXPECT_TRUE(TraceOneSidedOutline(scan.face, scan.top, off).polygon_m.empty());
  EXPECT_TRUE(TraceOneSidedOutline({{0, 0}, {1, 0}}, scan.top, OutlineParams{}).polygon_m.empty());
  // A top narrower than min_width_m is no canopy.
  const OneSidedScan thin = ScanFromOneSide(0.3, 0.25, 0.3);
  EXPECT_TRUE(TraceOneSidedOutline(thin.face, thin.top, OutlineParams{}).polygon_m.empty());
  OutlineParams bad;
  bad.one_sided_window_m = 0.0;
  EXPECT_THROW(TraceOneSidedOutline(scan.face, scan.top, bad), std::invalid_argument);
  bad = OutlineParams{};
  bad.one_sided_max_width_m = -1.0;
  EXPECT_THROW(TraceOutline(scan.face, bad), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::mapping
