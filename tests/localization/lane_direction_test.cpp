// RowMapRanging::LaneDirectionAt (map_aided_ranging.hpp), the map-aided initialisation's lane test:
// between two rows it gives their direction, anywhere else (a headland, a canopy, beside the last
// row, between rows that are not parallel) nothing.
#include "rowloc/localization/map_aided_ranging.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rowloc::localization {
namespace {

/// Three closed canopies 0.4 m wide and 50 m long, 2.5 m apart, along direction `angle` (rad) from (0, 0).
geometry::RowMap Rows(double angle) {
  geometry::RowMap map;
  map.origin = {45.0, 7.0, 200.0};
  const Eigen::Vector2d t(std::cos(angle), std::sin(angle)), n(-t.y(), t.x());
  for (int k = 0; k < 3; ++k) {
    geometry::Row row;
    row.id = "row-" + std::to_string(k + 1);
    row.closed = true;
    const Eigen::Vector2d c = 2.5 * k * n;
    row.points_m = {c - 0.2 * n, c + 50.0 * t - 0.2 * n, c + 50.0 * t + 0.2 * n, c + 0.2 * n};
    map.rows.push_back(row);
  }
  return map;
}

TEST(LaneDirection, BetweenTwoRowsItIsTheirDirectionAtAnyAngle) {
  for (const double angle : {0.0, 0.7, 2.0, -2.5}) {
    SCOPED_TRACE(angle);
    const geometry::RowMap map = Rows(angle);
    const RowMapRanging ranging(map, map.origin, 2.0);
    const Eigen::Vector2d t(std::cos(angle), std::sin(angle)), n(-t.y(), t.x());
    for (const double across : {1.25, 0.6, 1.9, 3.75}) {  // both lanes, off their centre
      const auto lane = ranging.LaneDirectionAt(20.0 * t + across * n, 5.0, 0.35);
      ASSERT_TRUE(lane.has_value());
      // The lane runs both ways: the answer is the rows' direction or its reverse.
      EXPECT_NEAR(std::abs(std::remainder(*lane - angle, std::numbers::pi)), 0.0, 1e-9);
    }
  }
}

TEST(LaneDirection, NotInALane) {
  const geometry::RowMap map = Rows(0.0);
  const RowMapRanging ranging(map, map.origin, 2.0);
  EXPECT_FALSE(ranging.LaneDirectionAt({-3.0, 1.25}, 5.0, 0.35));  // the headland before the rows
  EXPECT_FALSE(ranging.LaneDirectionAt({20.0, 2.5}, 5.0, 0.35));   // inside the middle canopy
  EXPECT_FALSE(ranging.LaneDirectionAt({20.0, 6.5}, 5.0, 0.35));   // beside the last row: one side open
  EXPECT_FALSE(ranging.LaneDirectionAt({20.0, 1.25}, 0.5, 0.35));  // rows farther than the half width
  EXPECT_THROW(ranging.LaneDirectionAt({std::nan(""), 1.0}, 5.0, 0.35), std::invalid_argument);
}

TEST(LaneDirection, RowsThatAreNotParallelAreNoLane) {
  geometry::RowMap map = Rows(0.0);
  // The third row turned by 0.6 rad about its start: the lane between rows 2 and 3 is a wedge.
  for (Eigen::Vector2d& p : map.rows[2].points_m) {
    const Eigen::Vector2d q = p - Eigen::Vector2d(0.0, 5.0);
    p = Eigen::Vector2d(0.0, 5.0) + Eigen::Rotation2Dd(0.6) * q;
  }
  const RowMapRanging ranging(map, map.origin, 2.0);
  EXPECT_TRUE(ranging.LaneDirectionAt({20.0, 1.25}, 5.0, 0.35));   // rows 1 and 2 are parallel
  EXPECT_FALSE(ranging.LaneDirectionAt({3.0, 3.9}, 5.0, 0.35));    // between row 2 and the turned row 3
  EXPECT_TRUE(ranging.LaneDirectionAt({3.0, 3.9}, 5.0, 1.0));      // ... a lane if 0.6 rad is allowed
}

}  // namespace
}  // namespace rowloc::localization
