// The along check of the map-aided update (map_aided_ranging.hpp, check 4): the corners of the row
// outlines with their along clearance, the decision CheckAlong takes for an echo near a corner,
// and the updater that applies it (counted in MapAidedStats::along_ambiguous).
#include "rowloc/localization/map_aided_ranging.hpp"
#include "rowloc/localization/map_aided_updater.hpp"
#include "rowloc/mapio/vehicle_config.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <string>

namespace rowloc::localization {
namespace {

const geometry::GeoOrigin kOrigin{45.0, 7.0, 200.0};
constexpr double kConeHalfAngle = 0.1308996938995747;  // 7.5 degrees, the default

geometry::Row Part(const std::string& id, double x0, double x1, double y0) {
  return geometry::Row{id, {{x0, y0}, {x1, y0}, {x1, y0 + 0.5}, {x0, y0 + 0.5}}, true};
}

/// A row with missing plants, y in [1.0, 1.5]: parts x in [0, 10], [11, 20] and [21.5, 30] (gaps
/// of 1.0 and 1.5 m), and a whole row y in [-1.5, -1.0] across a 2.0 m lane.
geometry::RowMap GappyRow() {
  geometry::RowMap map;
  map.origin = kOrigin;
  map.rows = {Part("a", 0.0, 10.0, 1.0), Part("b", 11.0, 20.0, 1.0), Part("c", 21.5, 30.0, 1.0),
              Part("whole", 0.0, 30.0, -1.5)};
  return map;
}

const RangeSensorMount kLeft{Eigen::Vector2d(0.0, 0.5), std::numbers::pi / 2, kConeHalfAngle};

TEST(AlongClearance, IsTheDistanceToTheNearestOtherCanopyEndAlongTheRow) {
  const RowMapRanging ranging(GappyRow(), kOrigin, 2.0);
  // The sensor (0.5 m left of the pose) 3 cm past part a's end: the echo comes from its corner.
  const auto past_a = ranging.Candidates(Eigen::Vector3d(10.03, 0.0, 0.0), kLeft, 4.0, 0.0);
  ASSERT_EQ(past_a.size(), 1u);
  EXPECT_EQ(past_a[0].geometry, EchoGeometry::kSegmentEnd);
  EXPECT_NEAR(past_a[0].along_clearance_m, 1.0, 1e-9);  // part b begins 1.0 m on
  EXPECT_NEAR(std::abs(past_a[0].row_tangent.x()), 1.0, 1e-9);
  // Part c's far end: its own near end 8.5 m back; part c's side, one segment, holds both of its
  // ends and takes the smaller clearance, 1.5 m (the gap to part b).
  const auto end_c = ranging.Candidates(Eigen::Vector3d(29.9, 0.0, 0.0), kLeft, 4.0, 0.0);
  ASSERT_EQ(end_c.size(), 1u);
  EXPECT_NEAR(end_c[0].along_clearance_m, 1.5, 1e-9);
  // Past c's end (3 cm): the echo comes from its corner.
  const auto past_c = ranging.Candidates(Eigen::Vector3d(30.03, 0.0, 0.0), kLeft, 4.0, 0.0);
  ASSERT_EQ(past_c.size(), 1u);
  EXPECT_EQ(past_c[0].geometry, EchoGeometry::kSegmentEnd);
  // The whole row's ends are 30 m apart, beyond the search: no along feature to confuse.
  const RangeSensorMount right{Eigen::Vector2d(0.0, -0.5), -std::numbers::pi / 2, kConeHalfAngle};
  const auto whole = ranging.Candidates(Eigen::Vector3d(0.5, 0.0, 0.0), right, 4.0, 0.0);
  ASSERT_EQ(whole.size(), 1u);
  EXPECT_EQ(whole[0].along_clearance_m, std::numeric_limits<double>::infinity());
}

TEST(AlongClearance, TheAcrossModelIsTheRangeToTheRowsLine) {
  const RowMapRanging ranging(GappyRow(), kOrigin, 2.0);
  const auto past_a = ranging.Candidates(Eigen::Vector3d(10.03, 0.0, 0.0), kLeft, 4.0, 0.0);
  ASSERT_EQ(past_a.size(), 1u);
  const EchoCandidate& c = past_a[0];
  // The corner's point model: r = |p_s - q|, q = (10, 1): dr/dX = 0.03 / r, dr/dY = -0.5 / r.
  const double r = std::hypot(0.03, 0.5);
  EXPECT_NEAR(c.predicted_range_m, r, 1e-9);
  EXPECT_NEAR(c.jacobian(0), 0.03 / r, 1e-9);
  // Across only: dr/dX = 0, dr/dY = -1, dr/dphi = n . d p_s / d phi = -(0.0) ... the lever arm is
  // (0, 0.5): d p_s / d phi = (-0.5, 0), n = (0, -1): 0.
  const EchoCandidate across = AcrossOnly(c, Eigen::Vector3d(10.03, 0.0, 0.0), kLeft);
  EXPECT_NEAR((across.jacobian - Eigen::RowVector3d(0.0, -1.0, 0.0)).norm(), 0.0, 1e-9);
  EXPECT_EQ(across.predicted_range_m, c.predicted_range_m);
  EXPECT_NEAR(across.edge.normal.dot(Eigen::Vector2d(0.0, -1.0)), 1.0, 1e-12);
}

Eigen::Matrix3d Covariance(double along_sigma_m, double across_sigma_m) {
  return Eigen::Vector3d(along_sigma_m * along_sigma_m, across_sigma_m * across_sigma_m, 1e-6).asDiagonal();
}

TEST(CheckAlong, ThePointOfACornerMustStayInTheConeOverTheAlongUncertainty) {
  const RowMapRanging ranging(GappyRow(), kOrigin, 2.0);
  const EchoCandidate c = ranging.Candidates(Eigen::Vector3d(10.03, 0.0, 0.0), kLeft, 4.0, 0.0).at(0);
  // The footprint r tan(a) = 0.5 * 0.1317 = 6.6 cm: k = 3 sigma within it, and beyond it.
  const double footprint = c.predicted_range_m * std::tan(kConeHalfAngle);
  EXPECT_EQ(CheckAlong(c, kLeft, Covariance(0.99 * footprint / 3.0, 0.05), 3.0), AlongUse::kFull);
  EXPECT_EQ(CheckAlong(c, kLeft, Covariance(1.01 * footprint / 3.0, 0.05), 3.0), AlongUse::kAcrossOnly);
  // The across sigma does not matter, the along one (the row's direction) does.
  EXPECT_EQ(CheckAlong(c, kLeft, Covariance(0.01, 1.0), 3.0), AlongUse::kFull);
}

TEST(CheckAlong, AnEchoAlongTheRowIsDroppedAndOneAlongASideOnlyBeyondHalfTheClearance) {
  EchoCandidate c;
  c.along_clearance_m = 1.0;
  c.row_tangent = Eigen::Vector2d::UnitX();
  c.predicted_range_m = 0.6;
  c.geometry = EchoGeometry::kPerpendicular;  // a side near a canopy's end: the clearance's scale only
  c.jacobian << 0.05, -1.0, 0.0;
  EXPECT_EQ(CheckAlong(c, kLeft, Covariance(0.16, 0.01), 3.0), AlongUse::kFull);        // 0.48 <= 0.5
  EXPECT_EQ(CheckAlong(c, kLeft, Covariance(0.17, 0.01), 3.0), AlongUse::kAcrossOnly);  // 0.51 > 0.5
  c.jacobian << -0.97, 0.25, 0.1;  // a canopy's end face seen from the gap: the range is along-row
  EXPECT_EQ(CheckAlong(c, kLeft, Covariance(0.17, 0.01), 3.0), AlongUse::kNone);
  EXPECT_EQ(CheckAlong(c, kLeft, Covariance(0.01, 0.01), 3.0), AlongUse::kFull);
  c.along_clearance_m = std::numeric_limits<double>::infinity();  // no corner near: never checked
  EXPECT_EQ(CheckAlong(c, kLeft, Covariance(10.0, 0.01), 3.0), AlongUse::kFull);
}

TEST(MapAidedUpdaterAlongCheck, UsesACornerEchoAcrossTheRowOnlyWhileTheAlongPositionIsUncertain) {
  MapAidedConfig config;
  config.adaptive_range_sigma.enabled = false;  // the configured 3 mm
  MapAidedUpdater updater(mapio::VineyardUgv4wsConfig(), config, kOrigin);
  updater.AttachRowMap(GappyRow());
  // The 4WS UGV's front-left ranger sits at (0.75, 0.5) looking +90 degrees: pose x 9.28 puts it
  // 3 cm past part a's end, 0.5 m from the row.
  const Eigen::Vector3d pose(9.28, 0.0, 0.0);
  const formats::UltrasonicMessage ping{1.0, "us_front_left", 0, 0.5};
  const MapAidedEcho known = updater.Measure(ping, pose, Covariance(0.005, 0.05));
  ASSERT_TRUE(known.measurement.has_value());
  EXPECT_GT(std::abs(known.measurement->jacobian(0, 0)), 0.05);  // along-row information
  EXPECT_EQ(updater.stats().along_ambiguous, 0u);
  const MapAidedEcho uncertain = updater.Measure(ping, pose, Covariance(0.1, 0.05));
  ASSERT_TRUE(uncertain.measurement.has_value());
  EXPECT_EQ(uncertain.measurement->jacobian(0, 0), 0.0);  // across only
  EXPECT_NEAR(uncertain.measurement->jacobian(0, 1), -1.0, 1e-12);
  EXPECT_EQ(updater.stats().along_ambiguous, 1u);
  EXPECT_TRUE(uncertain.trace.outcome.empty());  // the filter's update decides it
}

}  // namespace
}  // namespace rowloc::localization
