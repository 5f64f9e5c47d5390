// RowOutlineDefect: valid rings of either orientation and simple polylines pass; bow-ties, spikes,
// zero-area rings and polylines that retrace themselves are named.
#include "rowloc/geometry/row_outline_validity.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace rowloc::geometry {
namespace {

using ::testing::HasSubstr;

Row MakeRow(std::vector<Eigen::Vector2d> points, bool closed) { return Row{"r", std::move(points), closed, 0.0}; }

TEST(RowOutlineDefect, ValidRingsOfEitherOrientationPass) {
  Row square = MakeRow({{0, 0}, {1, 0}, {1, 1}, {0, 1}}, true);
  EXPECT_EQ(RowOutlineDefect(square), std::nullopt);
  std::reverse(square.points_m.begin(), square.points_m.end());
  EXPECT_EQ(RowOutlineDefect(square), std::nullopt);
  // A concave canopy outline with many vertices.
  std::vector<Eigen::Vector2d> ring;
  for (int i = 0; i < 100; ++i) {
    const double a = 2.0 * std::numbers::pi * i / 100.0;
    ring.emplace_back((1.0 + 0.3 * std::cos(5 * a)) * std::cos(a), (1.0 + 0.3 * std::cos(5 * a)) * std::sin(a));
  }
  EXPECT_EQ(RowOutlineDefect(MakeRow(ring, true)), std::nullopt);
}

TEST(RowOutlineDefect, BowTieIsASelfIntersection) {
  const auto defect = RowOutlineDefect(MakeRow({{0, 0}, {1, 1}, {1, 0}, {0, 1}}, true));
  ASSERT_TRUE(defect.has_value());
  EXPECT_THAT(*defect, HasSubstr("self-intersections"));
  EXPECT_THAT(*defect, HasSubstr("(0.5, 0.5)"));  // the crossing point, local metres
}

TEST(RowOutlineDefect, SpikesAndZeroAreaRingsAreDefects) {
  EXPECT_TRUE(RowOutlineDefect(MakeRow({{0, 0}, {1, 0}, {2, 0}, {1, 0}, {1, 1}}, true)).has_value());
  EXPECT_TRUE(RowOutlineDefect(MakeRow({{0, 0}, {1, 0}, {2, 0}}, true)).has_value());
  // Nearly collinear (rounding noise of 1e-12 m): still no area.
  EXPECT_THAT(RowOutlineDefect(MakeRow({{0, 0}, {1, 1e-12}, {2, 0}}, true)).value_or(""), HasSubstr("encloses no area"));
  // A thin but real sliver (1 mm thick) is an outline.
  EXPECT_EQ(RowOutlineDefect(MakeRow({{0, 0}, {1, 0.002}, {2, 0}}, true)), std::nullopt);
  // Two points alternating: a ring of zero area.
  std::vector<Eigen::Vector2d> zigzag;
  for (int i = 0; i < 1000; ++i) zigzag.emplace_back(i % 2 ? Eigen::Vector2d(1, 0) : Eigen::Vector2d(0, 0));
  EXPECT_TRUE(RowOutlineDefect(MakeRow(zigzag, true)).has_value());
}

TEST(RowOutlineDefect, PolylineThatTurnsBackIsADefect) {
  EXPECT_EQ(RowOutlineDefect(MakeRow({{0, 0}, {1, 0}, {2, 0.001}, {3, 0}}, false)), std::nullopt);
  // A sharp but real turn (170 degrees) is kept.
  EXPECT_EQ(RowOutlineDefect(MakeRow({{0, 0}, {1, 0}, {1.0 - std::cos(0.17), std::sin(0.17)}}, false)), std::nullopt);
  const auto defect = RowOutlineDefect(MakeRow({{0, 0}, {2, 0}, {1, 0}, {3, 0}}, false));
  ASSERT_TRUE(defect.has_value());
  EXPECT_THAT(*defect, HasSubstr("turns back on itself at vertex 1"));
}

}  // namespace
}  // namespace rowloc::geometry
