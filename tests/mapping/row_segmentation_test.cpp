// SelectCanopyBand and DetectRows: two box rows, a gap bridged, a gap too long, clutter, curved
// rows, no rows.
#include "rowloc/mapping/row_segmentation.hpp"

#include "synthetic_rows.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace rowloc::mapping {
namespace {

/// The band points of a field (flat ground: height = z).
std::vector<Eigen::Vector2d> Band(const test::SyntheticField& field) {
  const PointCloud cloud = field.Cloud();
  std::vector<double> h;
  for (const auto& p : cloud.points_m) h.push_back(p.z() - field.Ground(p.x(), p.y()));
  return SelectCanopyBand(cloud, h, CanopyBandParams{});
}

test::SyntheticField Field(std::vector<test::BoxRow> rows) {
  test::SyntheticField field;
  field.rows = std::move(rows);
  field.ground = false;
  return field;
}

TEST(RowSegmentationTest, BandKeepsThePointsAroundTheReferenceHeight) {
  PointCloud cloud;
  cloud.points_m = {{0, 0, 5.0}, {1, 0, 5.9}, {2, 0, 6.14}, {3, 0, 6.2}};
  const std::vector<double> h = {0.0, 0.9, 1.14, 1.2};
  const auto band = SelectCanopyBand(cloud, h, CanopyBandParams{1.0, 0.15});
  ASSERT_EQ(band.size(), 2U);
  EXPECT_EQ(band[0], Eigen::Vector2d(1, 0));
  EXPECT_EQ(band[1], Eigen::Vector2d(2, 0));
  EXPECT_THROW(SelectCanopyBand(cloud, {1.0}, CanopyBandParams{}), std::invalid_argument);
}

TEST(RowSegmentationTest, TwoBoxesAreTwoRowsOrderedAcross) {
  const RowDetection rows = DetectRows(Band(Field({{0, 10, 2.5, 0.25}, {0, 10, 0.0, 0.25}})), RowParams{});
  ASSERT_EQ(rows.rows.size(), 2U);
  EXPECT_NEAR(std::abs(rows.direction.x()), 1.0, 1e-6);
  EXPECT_GT(rows.direction.x(), 0.0);  // turned to +x
  ASSERT_EQ(rows.rows[0].parts.size(), 1U);
  ASSERT_EQ(rows.rows[1].parts.size(), 1U);
  // Left normal of +x is +y: the row at y = 0 comes first.
  EXPECT_NEAR(rows.rows[0].parts[0].centroid_m.y(), 0.0, 0.01);
  EXPECT_NEAR(rows.rows[1].parts[0].centroid_m.y(), 2.5, 0.01);
  EXPECT_NEAR(rows.rows[0].parts[0].length_m, 10.0, 0.05);
  EXPECT_EQ(rows.links, 0U);
}

TEST(RowSegmentationTest, AGapOfMissingPlantsIsBridgedIntoOneRowOfTwoParts) {
  // Row at y = 0 with a 1.5 m gap; a second row 2.5 m away without a gap.
  const RowDetection rows =
      DetectRows(Band(Field({{0, 8, 0.0, 0.25}, {9.5, 20, 0.0, 0.25}, {0, 20, 2.5, 0.25}})), RowParams{});
  ASSERT_EQ(rows.rows.size(), 2U);
  ASSERT_EQ(rows.rows[0].parts.size(), 2U);
  EXPECT_LT(rows.rows[0].parts[0].centroid_m.x(), rows.rows[0].parts[1].centroid_m.x());  // in order
  EXPECT_EQ(rows.rows[1].parts.size(), 1U);
  EXPECT_EQ(rows.links, 1U);
}

TEST(RowSegmentationTest, AGapLongerThanMaxGapSplitsTheRow) {
  RowParams params;
  params.max_gap_m = 1.0;
  const RowDetection rows = DetectRows(Band(Field({{0, 8, 0.0, 0.25}, {9.5, 20, 0.0, 0.25}})), params);
  EXPECT_EQ(rows.rows.size(), 2U);
  EXPECT_EQ(rows.links, 0U);
}

TEST(RowSegmentationTest, PartsOfNeighbouringRowsAreNotLinked) {
  // The end of one row faces the start of the next row's part, but 2.5 m to the side.
  const RowDetection rows = DetectRows(Band(Field({{0, 8, 0.0, 0.25}, {9, 20, 2.5, 0.25}})), RowParams{});
  EXPECT_EQ(rows.rows.size(), 2U);
  EXPECT_EQ(rows.links, 0U);
}

TEST(RowSegmentationTest, ClutterIsDroppedAndNothingIsNoRows) {
  std::vector<Eigen::Vector2d> band;
  for (int k = 0; k < 30; ++k) band.emplace_back(5.0 + 0.01 * k, 5.0);  // 30 points, 0.3 m
  RowDetection rows = DetectRows(band, RowParams{});
  EXPECT_TRUE(rows.rows.empty());
  EXPECT_EQ(rows.parts_found, 1U);
  EXPECT_EQ(rows.parts_dropped, 1U);
  EXPECT_EQ(rows.points_dropped, 30U);
  rows = DetectRows({}, RowParams{});
  EXPECT_TRUE(rows.rows.empty());
  RowParams bad;
  bad.raster_cell_m = 0.0;
  EXPECT_THROW(DetectRows(band, bad), std::invalid_argument);
}

TEST(RowSegmentationTest, RowsFarApartCostTheirCellsNotTheirBoundingBox) {
  // Two short rows 30 km apart: a dense 5 cm raster of their bounding box would have 3.6 * 10^11
  // cells; the sparse one holds only the occupied cells.
  test::SyntheticField field = Field({{0, 6, 0.0, 0.25}});
  std::vector<Eigen::Vector2d> band = Band(field);
  const std::size_t one_row = band.size();
  for (std::size_t k = 0; k < one_row; ++k) band.push_back(band[k] + Eigen::Vector2d(30000.0, 30000.0));
  const RowDetection rows = DetectRows(band, RowParams{});
  ASSERT_EQ(rows.rows.size(), 2U);
  EXPECT_EQ(rows.rows[0].parts.front().points_m.size(), one_row);
  EXPECT_EQ(rows.rows[1].parts.front().points_m.size(), one_row);
}

TEST(RowSegmentationTest, PointsGoToThePartTheyLieNear) {
  // Two rows 2.5 m apart; points of another height 10 cm beside each row's faces go to that row's
  // part, points in the lane (1.25 m from both) to none.
  const test::SyntheticField field = Field({{0, 6, 0.0, 0.25}, {0, 6, 2.5, 0.25}});
  const RowDetection rows = DetectRows(Band(field), RowParams{});
  ASSERT_EQ(rows.rows.size(), 2U);
  const std::vector<Eigen::Vector2d> others = {{3.0, -0.35}, {3.0, 0.35}, {3.0, 2.15}, {3.0, 1.25}, {20.0, 0.0}};
  const auto assigned = AssignPointsToParts(rows, others, 0.25);
  ASSERT_EQ(assigned.size(), 2U);
  const double y0 = rows.rows[0].parts[0].centroid_m.y();
  const std::size_t near_first = y0 < 1.0 ? 0 : 1;  // rows are ordered across, in either direction
  EXPECT_EQ(assigned[near_first].size(), 2U);
  EXPECT_EQ(assigned[1 - near_first].size(), 1U);
  EXPECT_THROW(AssignPointsToParts(rows, others, 0.0), std::invalid_argument);
}

TEST(RowSegmentationTest, CurvedRowsWithAGapAreFollowed) {
  // Three concentric arcs (radius 30, 32.5, 35 m, a quarter turn each) sampled on both faces and
  // the end caps; the middle one has a 1.2 m gap. Chords would cross the neighbouring rows.
  std::vector<Eigen::Vector2d> band;
  const auto face = [&](double radius, double a0, double a1) {
    for (double a = a0; a <= a1; a += 0.05 / radius) {
      for (double w : {-0.25, 0.25}) band.emplace_back((radius + w) * std::cos(a), (radius + w) * std::sin(a));
    }
    for (double w = -0.2; w <= 0.2; w += 0.05) {
      band.emplace_back((radius + w) * std::cos(a0), (radius + w) * std::sin(a0));
      band.emplace_back((radius + w) * std::cos(a1), (radius + w) * std::sin(a1));
    }
  };
  face(30.0, 0.0, M_PI / 2);
  face(32.5, 0.0, 0.7);
  face(32.5, 0.7 + 1.2 / 32.5, M_PI / 2);
  face(35.0, 0.0, M_PI / 2);
  const RowDetection rows = DetectRows(band, RowParams{});
  ASSERT_EQ(rows.rows.size(), 3U);
  EXPECT_EQ(rows.rows[0].parts.size(), 1U);
  EXPECT_EQ(rows.rows[1].parts.size(), 2U);
  EXPECT_EQ(rows.rows[2].parts.size(), 1U);
  EXPECT_EQ(rows.links, 1U);
}

}  // namespace
}  // namespace rowloc::mapping
