// Map-aided ultrasonic measurement (map_aided_ranging.hpp): echo candidates of a row map against
// hand-computed geometry (perpendicular, cone edge, segment end; rows at 0/45/90/135 degrees,
// sensors on both sides), their Jacobians against central differences, the candidate window and
// one-candidate-per-row rule at corners, a map in another WGS84 origin, the three measurement
// methods (range, ellipsoid_cut, ellipsoid_cut_deprior: slab, cut status, heading widening) and
// the range NIS.
#include "rowloc/localization/map_aided_ranging.hpp"

#include "rowloc/mapio/local_frame.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace rowloc::localization {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kHalf = 7.5 * kPi / 180.0;  // cone half aperture
constexpr double kMaxRange = 4.0;
constexpr double kWide = 10.0;  // a window that keeps every row in the cone
const geometry::GeoOrigin kOrigin{45.0703, 7.6869, 240.0};
const double kSmoothing = MapAidedConfig{}.row_smoothing_m;  // the default, 2 m

geometry::Row MakeRow(std::string id, std::vector<Eigen::Vector2d> points, bool closed = false) {
  geometry::Row row;
  row.id = std::move(id);
  row.points_m = std::move(points);
  row.closed = closed;
  return row;
}

RowMapRanging MakeRanging(std::vector<geometry::Row> rows) {
  geometry::RowMap map;
  map.origin = kOrigin;
  map.rows = std::move(rows);
  return RowMapRanging(map, kOrigin, kSmoothing);
}

// Row y = 0 for x in [-10, 10].
RowMapRanging HorizontalRow() { return MakeRanging({MakeRow("h", {{-10, 0}, {10, 0}})}); }

std::size_t RowOf(const RowMapRanging& ranging, const EchoCandidate& c) {
  return ranging.index().entries()[c.entry].row;
}

// Predicted range of `row` at `pose` (its nearest hit), for central differences.
double RowRange(const RowMapRanging& ranging, const Eigen::Vector3d& pose, const RangeSensorMount& mount,
                std::size_t row) {
  for (const EchoCandidate& c : ranging.Candidates(pose, mount, kMaxRange, kWide)) {
    if (RowOf(ranging, c) == row) return c.predicted_range_m;
  }
  ADD_FAILURE() << "row " << row << " is no candidate at " << pose.transpose();
  return std::numeric_limits<double>::quiet_NaN();
}

void ExpectJacobianMatchesCentralDifferences(const RowMapRanging& ranging, const Eigen::Vector3d& pose,
                                             const RangeSensorMount& mount, const EchoCandidate& c) {
  const double h = 1e-6;
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector3d plus = pose, minus = pose;
    plus[i] += h;
    minus[i] -= h;
    const double numeric =
        (RowRange(ranging, plus, mount, RowOf(ranging, c)) - RowRange(ranging, minus, mount, RowOf(ranging, c))) /
        (2 * h);
    EXPECT_NEAR(c.jacobian[i], numeric, 1e-6) << "component " << i << " at " << pose.transpose();
  }
}

// A straight row at angle theta through 2 n (n its left normal), along in [-20, 20]. The vehicle
// drives along it 1.25 m away on side s (+1: on the normal's side, right-looking sensor at
// (0.75, -0.5); -1: left-looking sensor at (0.75, 0.5)): the sensor is 0.75 m from the row.
class StraightRowAtAngle : public ::testing::TestWithParam<double> {
 protected:
  Eigen::Vector2d along() const { return {std::cos(GetParam()), std::sin(GetParam())}; }
  Eigen::Vector2d nrm() const { return {-std::sin(GetParam()), std::cos(GetParam())}; }
  RowMapRanging Ranging() const {
    return MakeRanging({MakeRow("r", {2.0 * nrm() - 20.0 * along(), 2.0 * nrm() + 20.0 * along()})});
  }
  static RangeSensorMount Mount(double s) { return {Eigen::Vector2d(0.75, -0.5 * s), -s * kPi / 2, kHalf}; }
  Eigen::Vector3d Pose(double s, double along_m, double heading_error) const {
    const Eigen::Vector2d p = (2.0 + 1.25 * s) * nrm() + along_m * along();
    return {p.x(), p.y(), GetParam() + heading_error};
  }
};

TEST_P(StraightRowAtAngle, PerpendicularEchoMatchesHandFormulas) {
  const RowMapRanging ranging = Ranging();
  for (double s : {+1.0, -1.0}) {
    for (double delta : {0.0, 0.05, -0.05}) {  // heading error within the cone
      const Eigen::Vector3d pose = Pose(s, 3.0, delta);
      const auto cs = ranging.Candidates(pose, Mount(s), kMaxRange, 0.0);
      ASSERT_EQ(cs.size(), 1u);
      const EchoCandidate& c = cs[0];
      EXPECT_EQ(c.geometry, EchoGeometry::kPerpendicular);
      // Sensor offset from the row: 1.25 + s 0.75 sin(delta) - 0.5 cos(delta) (0.75 at delta = 0).
      EXPECT_NEAR(c.predicted_range_m, 1.25 + s * 0.75 * std::sin(delta) - 0.5 * std::cos(delta), 1e-12);
      // dr/dp = n (towards the sensor, s nrm); dr/dphi = n^T R(phi) (-l_y, l_x).
      const Eigen::RowVector3d h(s * nrm().x(), s * nrm().y(), s * 0.75 * std::cos(delta) + 0.5 * std::sin(delta));
      EXPECT_NEAR((c.jacobian - h).norm(), 0.0, 1e-12);
      EXPECT_NEAR((c.edge.normal - s * nrm()).norm(), 0.0, 1e-12);
      EXPECT_NEAR(c.edge.offset_m, 2.0 * s, 1e-12);
      ExpectJacobianMatchesCentralDifferences(ranging, pose, Mount(s), c);
    }
  }
}

TEST_P(StraightRowAtAngle, ConeEdgeAndSegmentEndMatchHandFormulas) {
  const RowMapRanging ranging = Ranging();
  for (double s : {+1.0, -1.0}) {
    for (double delta : {0.3, -0.3}) {  // beyond the half aperture: the nearest cone edge hits
      const Eigen::Vector3d pose = Pose(s, 3.0, delta);
      const auto cs = ranging.Candidates(pose, Mount(s), kMaxRange, 0.0);
      ASSERT_EQ(cs.size(), 1u);
      EXPECT_EQ(cs[0].geometry, EchoGeometry::kConeEdge);
      const double height = 1.25 + s * 0.75 * std::sin(delta) - 0.5 * std::cos(delta);
      const double cos_edge = std::cos(0.3 - kHalf);
      EXPECT_NEAR(cs[0].predicted_range_m, height / cos_edge, 1e-12);
      EXPECT_NEAR((cs[0].jacobian.head<2>() - s * nrm().transpose() / cos_edge).norm(), 0.0, 1e-12);
      ExpectJacobianMatchesCentralDifferences(ranging, pose, Mount(s), cs[0]);
    }
    // Sensor 5 cm past the row's end (along 20): the end is 3.8 deg off the beam, in the cone.
    const auto cs = ranging.Candidates(Pose(s, 20.05 - 0.75, 0.0), Mount(s), kMaxRange, 0.0);
    ASSERT_EQ(cs.size(), 1u);
    EXPECT_EQ(cs[0].geometry, EchoGeometry::kSegmentEnd);
    EXPECT_NEAR(cs[0].predicted_range_m, std::sqrt(0.05 * 0.05 + 0.75 * 0.75), 1e-12);
  }
}

// The end of an open row is a corner: the echo comes from that point, r = |p_s - q|, whose
// Jacobian is u = (p_s - q) / r and u^T R(phi) (-l_y, l_x) (real along-row information).
TEST_P(StraightRowAtAngle, SegmentEndJacobianMatchesHandFormulaAndCentralDifferences) {
  const RowMapRanging ranging = Ranging();
  for (double s : {+1.0, -1.0}) {
    const Eigen::Vector3d pose = Pose(s, 20.05 - 0.75, 0.0);
    const auto cs = ranging.Candidates(pose, Mount(s), kMaxRange, 0.0);
    ASSERT_EQ(cs.size(), 1u);
    const double r = std::sqrt(0.05 * 0.05 + 0.75 * 0.75);
    const Eigen::Vector2d u = (0.05 * along() + s * 0.75 * nrm()) / r;  // from the end to the sensor
    const Eigen::RowVector3d h(u.x(), u.y(), s * (0.05 * 0.5 + 0.75 * 0.75) / r);
    EXPECT_NEAR((cs[0].jacobian - h).norm(), 0.0, 1e-12);
    ExpectJacobianMatchesCentralDifferences(ranging, pose, Mount(s), cs[0]);
  }
}

INSTANTIATE_TEST_SUITE_P(RowDirections, StraightRowAtAngle, ::testing::Values(0.0, kPi / 4, kPi / 2, 3 * kPi / 4));

TEST(MapAidedRanging, LeverArmShiftTowardsTheRowShortensTheRange) {
  const double theta = kPi / 4, phi = theta + 0.05;
  const Eigen::Vector2d nrm(-std::sin(theta), std::cos(theta));
  const RowMapRanging ranging =
      MakeRanging({MakeRow("r", {Eigen::Vector2d(-10, -10), Eigen::Vector2d(10, 10)})});  // n^T x = 0
  const Eigen::Vector3d pose(1.25 * nrm.x(), 1.25 * nrm.y(), phi);
  const Eigen::Vector2d n_body = Eigen::Rotation2Dd(-phi) * nrm;  // the row normal in the body frame
  const RangeSensorMount base{Eigen::Vector2d(0.75, -0.5), -kPi / 2, kHalf};
  const auto c0 = ranging.Candidates(pose, base, kMaxRange, 0.0);
  ASSERT_EQ(c0.size(), 1u);
  for (double d : {0.1, 0.25, -0.2}) {
    RangeSensorMount moved = base;
    moved.lever_arm_m -= d * n_body;  // d towards the row
    const auto c = ranging.Candidates(pose, moved, kMaxRange, 0.0);
    ASSERT_EQ(c.size(), 1u);
    EXPECT_NEAR(c[0].predicted_range_m - c0[0].predicted_range_m, -d, 1e-12);
  }
  RangeSensorMount slid = base;  // along the row: same perpendicular range
  slid.lever_arm_m += 0.4 * Eigen::Vector2d(-n_body.y(), n_body.x());
  const auto c = ranging.Candidates(pose, slid, kMaxRange, 0.0);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_NEAR(c[0].predicted_range_m, c0[0].predicted_range_m, 1e-12);
}

// Sensor at (0, 1) looking down (-y): pose (-0.75, 1.5, 0), lever arm (0.75, -0.5).
const Eigen::Vector3d kAbove(-0.75, 1.5, 0.0);
const RangeSensorMount kDown{Eigen::Vector2d(0.75, -0.5), -kPi / 2, kHalf};

TEST(MapAidedRanging, ConvexVertexOfAPolylineIsASegmentEnd) {
  // Roof (-5, -1) - (0, 0) - (5, -1): both feet of the perpendicular are off the segments.
  const RowMapRanging ranging = MakeRanging({MakeRow("roof", {{-5, -1}, {0, 0}, {5, -1}})});
  const auto cs = ranging.Candidates(kAbove, kDown, kMaxRange, 0.0);
  ASSERT_EQ(cs.size(), 1u);  // two segments meet at the vertex, one row: one candidate
  EXPECT_EQ(cs[0].geometry, EchoGeometry::kSegmentEnd);
  EXPECT_NEAR(cs[0].predicted_range_m, 1.0, 1e-12);  // the distance to the vertex
}

TEST(MapAidedRanging, PolygonCornerGivesOneCandidatePerRow) {
  // Diamond with its top vertex at the origin; its far sides are in the cone too (about 3 m).
  const RowMapRanging ranging = MakeRanging({MakeRow("diamond", {{0, 0}, {1, -1}, {0, -2}, {-1, -1}}, true)});
  for (double window : {0.0, 5.0}) {
    const auto cs = ranging.Candidates(kAbove, kDown, kMaxRange, window);
    ASSERT_EQ(cs.size(), 1u) << "window " << window;
    EXPECT_EQ(cs[0].geometry, EchoGeometry::kSegmentEnd);
    EXPECT_NEAR(cs[0].predicted_range_m, 1.0, 1e-12);
  }
}

// At a convex vertex straight below the sensor the range is |p_s - q|, so dr/d(X, Y, phi) =
// (0, 1, l_x): the point model at a corner (the diamond's 90 degree vertex), the smoothed row
// direction at a vertex that turns less than 45 degrees (the roof), equal here; and never the line
// of whichever segment has the lower entry index.
TEST(MapAidedRanging, VertexJacobianMatchesHandFormulaAndCentralDifferences) {
  for (const geometry::Row& row : {MakeRow("roof", {{-5, -1}, {0, 0}, {5, -1}}),
                                   MakeRow("diamond", {{0, 0}, {1, -1}, {0, -2}, {-1, -1}}, true)}) {
    const RowMapRanging ranging = MakeRanging({row});
    const auto cs = ranging.Candidates(kAbove, kDown, kMaxRange, 0.0);
    ASSERT_EQ(cs.size(), 1u);
    EXPECT_NEAR((cs[0].jacobian - Eigen::RowVector3d(0.0, 1.0, 0.75)).norm(), 0.0, 1e-12) << row.id;
    ExpectJacobianMatchesCentralDifferences(ranging, kAbove, kDown, cs[0]);
  }
}

TEST(MapAidedRanging, WindowSelectsRowsNearestFirst) {
  // Row 0 at y = -0.3 (1.3 m), row 1 at y = 0 (1 m): both cross the cone (no occlusion).
  const RowMapRanging ranging = MakeRanging({MakeRow("far", {{-10, -0.3}, {10, -0.3}}),
                                             MakeRow("near", {{-10, 0}, {10, 0}})});
  const auto both = ranging.Candidates(kAbove, kDown, kMaxRange, 0.5);
  ASSERT_EQ(both.size(), 2u);
  EXPECT_EQ(RowOf(ranging, both[0]), 1u);
  EXPECT_EQ(RowOf(ranging, both[1]), 0u);
  EXPECT_NEAR(both[0].predicted_range_m, 1.0, 1e-12);
  EXPECT_NEAR(both[1].predicted_range_m, 1.3, 1e-12);
  for (const EchoCandidate& c : both) EXPECT_EQ(c.geometry, EchoGeometry::kPerpendicular);
  for (double window : {0.0, 0.2}) {
    const auto nearest = ranging.Candidates(kAbove, kDown, kMaxRange, window);
    ASSERT_EQ(nearest.size(), 1u) << "window " << window;
    EXPECT_EQ(RowOf(ranging, nearest[0]), 1u);
  }
}

TEST(MapAidedRanging, ReusedBuffersGiveTheSameCandidatesAsFreshOnes) {
  // One Buffers object through queries with 2, 1 and 0 candidates (and back): each result is the
  // value version's, nothing left over from the call before.
  const RowMapRanging ranging = MakeRanging({MakeRow("far", {{-10, -0.3}, {10, -0.3}}),
                                             MakeRow("near", {{-10, 0}, {10, 0}})});
  RowMapRanging::Buffers buffers;
  const Eigen::Vector3d away(0.0, 5.0, kPi);  // beyond the 4 m range of both rows
  for (const auto& [pose, window] : std::vector<std::pair<Eigen::Vector3d, double>>{
           {kAbove, 0.5}, {kAbove, 0.0}, {away, 0.5}, {kAbove, 0.5}}) {
    const std::vector<EchoCandidate> fresh = ranging.Candidates(pose, kDown, kMaxRange, window);
    const std::vector<EchoCandidate>& reused = ranging.Candidates(pose, kDown, kMaxRange, window, buffers);
    EXPECT_EQ(&reused, &buffers.candidates);
    ASSERT_EQ(reused.size(), fresh.size()) << pose.transpose() << " window " << window;
    for (std::size_t i = 0; i < fresh.size(); ++i) {
      EXPECT_EQ(reused[i].entry, fresh[i].entry);
      EXPECT_EQ(reused[i].predicted_range_m, fresh[i].predicted_range_m);
      EXPECT_EQ(reused[i].jacobian, fresh[i].jacobian);
    }
  }
  EXPECT_EQ(ranging.Candidates(away, kDown, kMaxRange, 0.5, buffers).size(), 0u);
}

TEST(MapAidedRanging, DenseStraightRowCostsWhatItsOneSegmentCosts) {
  // 10^5 vertices along y = 0 (and a second row with a kink that must stay): indexed as the
  // geometry they carry, and every query answers as the two-vertex row does.
  std::vector<Eigen::Vector2d> dense;
  constexpr int kVertices = 100000;
  for (int i = 0; i < kVertices; ++i) dense.emplace_back(-10.0 + 20.0 * i / (kVertices - 1), 0.0);
  const std::vector<Eigen::Vector2d> kinked = {{-10, -1.3}, {0, -1.3}, {0.5, -1.2}, {10, -1.2}};
  const RowMapRanging dense_ranging = MakeRanging({MakeRow("h", dense), MakeRow("k", kinked)});
  const RowMapRanging sparse_ranging = MakeRanging({MakeRow("h", {{-10, 0}, {10, 0}}), MakeRow("k", kinked)});
  EXPECT_EQ(dense_ranging.index().entries().size(), 1u + 3u);
  const RangeSensorMount forward{Eigen::Vector2d(0.75, 0.0), 0.0, kHalf};
  for (double x = -9.0; x <= 9.0; x += 0.37) {
    for (const double phi : {-kPi / 2, -kPi / 2 + 0.3, -kPi / 2 - 0.5}) {
      const Eigen::Vector3d pose(x, 2.0, phi);
      const auto dense_hits = dense_ranging.Candidates(pose, forward, kMaxRange, kWide);
      const auto sparse_hits = sparse_ranging.Candidates(pose, forward, kMaxRange, kWide);
      ASSERT_EQ(dense_hits.size(), sparse_hits.size()) << pose.transpose();
      for (std::size_t i = 0; i < dense_hits.size(); ++i) {
        EXPECT_EQ(RowOf(dense_ranging, dense_hits[i]), RowOf(sparse_ranging, sparse_hits[i]));
        EXPECT_NEAR(dense_hits[i].predicted_range_m, sparse_hits[i].predicted_range_m, 1e-9) << pose.transpose();
        EXPECT_LT((dense_hits[i].jacobian - sparse_hits[i].jacobian).norm(), 1e-9) << pose.transpose();
      }
    }
  }
}

TEST(MapAidedRanging, BeamTiltedBeyondTheHalfAngleHitsWithTheConeEdge) {
  // Row y = 0, sensor at (0.75, 1): h = 1, dh/dphi = l_x = 0.75.
  const RowMapRanging ranging = HorizontalRow();
  const Eigen::Vector3d pose(0.0, 1.5, 0.0);
  for (double sign : {+1.0, -1.0}) {
    const double tilt = sign * 20.0 * kPi / 180.0;
    const RangeSensorMount mount{Eigen::Vector2d(0.75, -0.5), -kPi / 2 + tilt, kHalf};
    const auto cs = ranging.Candidates(pose, mount, kMaxRange, 0.0);
    ASSERT_EQ(cs.size(), 1u);
    EXPECT_EQ(cs[0].geometry, EchoGeometry::kConeEdge);
    const double e = 12.5 * kPi / 180.0;  // the edge ray's angle to the normal
    EXPECT_NEAR(cs[0].predicted_range_m, 1.0 / std::cos(e), 1e-12);
    // r = h / cos(|phi + tilt| - a): dr/dphi = h' / cos(e) + sign h sin(e) / cos(e)^2.
    const Eigen::RowVector3d expected(0.0, 1.0 / std::cos(e),
                                      0.75 / std::cos(e) + sign * std::sin(e) / std::pow(std::cos(e), 2));
    EXPECT_NEAR((cs[0].jacobian - expected).norm(), 0.0, 1e-12);
    ExpectJacobianMatchesCentralDifferences(ranging, pose, mount, cs[0]);
    // Tilted 5 degrees: inside the half angle the echo is the perpendicular distance.
    const RangeSensorMount inside{Eigen::Vector2d(0.75, -0.5), -kPi / 2 + sign * 5.0 * kPi / 180.0, kHalf};
    const auto ci = ranging.Candidates(pose, inside, kMaxRange, 0.0);
    ASSERT_EQ(ci.size(), 1u);
    EXPECT_EQ(ci[0].geometry, EchoGeometry::kPerpendicular);
    EXPECT_NEAR(ci[0].predicted_range_m, 1.0, 1e-12);
    EXPECT_NEAR((ci[0].jacobian - Eigen::RowVector3d(0.0, 1.0, 0.75)).norm(), 0.0, 1e-12);
  }
}

TEST(MapAidedRanging, NothingInRangeAndInvalidInput) {
  const RowMapRanging ranging = HorizontalRow();
  EXPECT_TRUE(ranging.Candidates({0.0, 5.5, 0.0}, kDown, kMaxRange, 0.0).empty());  // 5 m > 4 m
  const RangeSensorMount up{Eigen::Vector2d(0.75, 0.5), kPi / 2, kHalf};
  EXPECT_TRUE(ranging.Candidates({0.0, 1.5, 0.0}, up, kMaxRange, 0.0).empty());  // looking away
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_THROW(ranging.Candidates({nan, 1.5, 0.0}, kDown, kMaxRange, 0.0), std::invalid_argument);
  EXPECT_THROW(ranging.Candidates({0.0, 1.5, inf}, kDown, kMaxRange, 0.0), std::invalid_argument);
  EXPECT_THROW(ranging.Candidates({0.0, 1.5, 0.0}, kDown, kMaxRange, -0.1), std::invalid_argument);
  EXPECT_THROW(ranging.Candidates({0.0, 1.5, 0.0}, kDown, kMaxRange, nan), std::invalid_argument);
  EXPECT_THROW(MakeRanging({}), std::invalid_argument);
  geometry::RowMap map;
  map.origin = kOrigin;
  map.rows = {MakeRow("h", {{-10, 0}, {10, 0}})};
  EXPECT_THROW(static_cast<void>(RowMapRanging(map, {100.0, 7.0, 0.0}, kSmoothing)), std::invalid_argument);
  EXPECT_THROW(static_cast<void>(RowMapRanging(map, kOrigin, -1.0)), std::invalid_argument);
}

TEST(MapAidedRanging, MapInAnotherOriginGivesTheSameCandidates) {
  // Rows at 45 degrees, 2.5 m apart (polylines with a middle vertex, and a closed outline).
  const Eigen::Vector2d along(std::sqrt(0.5), std::sqrt(0.5)), nrm(-std::sqrt(0.5), std::sqrt(0.5));
  std::vector<geometry::Row> rows;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector2d o = 2.5 * i * nrm;
    rows.push_back(MakeRow("r" + std::to_string(i), {o - 20 * along, o + 3 * along, o + 20 * along}));
  }
  const Eigen::Vector2d o = 7.5 * nrm, w = 0.4 * nrm;
  rows.push_back(MakeRow("box", {o - 20 * along, o + 20 * along, o + 20 * along + w, o - 20 * along + w}, true));
  const mapio::LocalFrame filter(kOrigin);
  geometry::RowMap shifted, naive;
  shifted.origin = naive.origin = filter.ToGeodetic(Eigen::Vector3d(100.0, 0.0, 0.0));
  shifted.rows = naive.rows = rows;
  const mapio::LocalFrame map_frame(shifted.origin);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    for (std::size_t k = 0; k < rows[r].points_m.size(); ++k) {
      const Eigen::Vector2d& p = rows[r].points_m[k];
      const geometry::GeoOrigin g = filter.ToGeodetic(Eigen::Vector3d(p.x(), p.y(), 0.0));
      shifted.rows[r].points_m[k] = map_frame.ToEnu(g.latitude_deg, g.longitude_deg, g.altitude_m).head<2>();
      naive.rows[r].points_m[k] = p - Eigen::Vector2d(100.0, 0.0);  // ignores the meridian convergence
    }
  }
  const RowMapRanging direct = MakeRanging(rows);
  const RowMapRanging converted(shifted, kOrigin, kSmoothing);
  const RowMapRanging wrong(naive, kOrigin, kSmoothing);
  double naive_error = 0.0;
  int compared = 0;
  for (double s : {+1.0, -1.0}) {
    for (double a : {-8.0, 0.0, 9.0}) {
      for (double delta : {0.0, 0.3}) {
        const Eigen::Vector2d p = (2.5 + 1.25 * s) * nrm + a * along;
        const Eigen::Vector3d pose(p.x(), p.y(), kPi / 4 + delta);
        const RangeSensorMount mount{Eigen::Vector2d(0.75, -0.5 * s), -s * kPi / 2, kHalf};
        const auto expected = direct.Candidates(pose, mount, kMaxRange, kWide);
        const auto got = converted.Candidates(pose, mount, kMaxRange, kWide);
        const auto off = wrong.Candidates(pose, mount, kMaxRange, kWide);
        ASSERT_FALSE(expected.empty());
        ASSERT_EQ(got.size(), expected.size());
        ASSERT_EQ(off.size(), expected.size());
        for (std::size_t i = 0; i < got.size(); ++i) {
          EXPECT_EQ(RowOf(converted, got[i]), RowOf(direct, expected[i]));
          EXPECT_EQ(got[i].geometry, expected[i].geometry);
          EXPECT_NEAR(got[i].predicted_range_m, expected[i].predicted_range_m, 1e-6);
          EXPECT_NEAR((got[i].jacobian - expected[i].jacobian).norm(), 0.0, 1e-6);
          naive_error = std::max(naive_error, std::abs(off[i].predicted_range_m - expected[i].predicted_range_m));
          ++compared;
        }
      }
    }
  }
  EXPECT_GE(compared, 12);
  EXPECT_GT(naive_error, 1e-4);  // the 1e-6 tolerance does tell a naive shift from the conversion
}

// Row y = 0; vehicle at (0, 1.25) heading east; right-looking sensor at (0.75, -0.5): range 0.75,
// n = (0, 1), n^T p = 1.25 + (d - 0.75) for a range d, d bound / d phi = -l_x = -0.75.
struct CutSetup {
  RowMapRanging ranging = HorizontalRow();
  Eigen::Vector3d pose{0.0, 1.25, 0.0};
  RangeSensorMount mount{Eigen::Vector2d(0.75, -0.5), -kPi / 2, kHalf};
  EchoCandidate candidate = ranging.Candidates(pose, mount, kMaxRange, 0.0).at(0);
};

MapAidedConfig Config(MapAidedMethod method) {
  MapAidedConfig config;
  config.method = method;
  config.range_sigma_m = 0.003;
  config.k_sigma = 3.0;
  return config;
}

TEST(MapAidedMeasurement, EllipsoidCutMovesTheCentreIntoTheSlabAndDepriorFusesBackToIt) {
  const CutSetup f;
  const Eigen::Matrix3d P = Eigen::Vector3d(0.09, 0.09, 1e-6).asDiagonal();  // sigma 0.3 m, 1 mrad
  const double measured = 0.80;
  const MapAidedMeasurement cut =
      MakeMapAidedMeasurement(f.candidate, f.mount, f.pose, P, measured, Config(MapAidedMethod::kEllipsoidCut));
  ASSERT_EQ(cut.cut_status, geometry::CutStatus::kUpdated);
  ASSERT_EQ(cut.innovation.size(), 2);
  EXPECT_TRUE(cut.jacobian.isApprox((Eigen::Matrix<double, 2, 3>() << 1, 0, 0, 0, 1, 0).finished()));
  // Slab on y: 1.25 + 0.05 -+ 3 * 0.003, widened by 3 * 0.001 rad * 0.75 m.
  const double lo = 1.30 - 0.009 - 0.00225, hi = 1.30 + 0.009 + 0.00225;
  // Parallel cut of the 3-sigma circle (radius 0.9) by hand (published form of sigma, n = 2).
  const double a = (1.25 - hi) / 0.9, ah = (lo - 1.25) / 0.9;
  const double rho = std::sqrt(4 * (1 - a * a) * (1 - ah * ah) + 4 * std::pow(ah * ah - a * a, 2));
  const double sigma = (2 + 2 * (1 - a * ah - rho / 2) / ((a - ah) * (a - ah))) / 3;
  const double tau = sigma * (a - ah) / 2;
  const double delta = 4.0 / 3.0 * (1 - (a * a + ah * ah - rho / 2) / 2);
  EXPECT_NEAR(cut.innovation[0], 0.0, 1e-12);
  EXPECT_NEAR(cut.innovation[1], -tau * 0.9, 1e-9);
  const double y_post = 1.25 + cut.innovation[1];
  EXPECT_GT(y_post, lo);
  EXPECT_LT(y_post, hi);
  EXPECT_NEAR(cut.noise(0, 0), delta * 0.09, 1e-9);
  EXPECT_NEAR(cut.noise(1, 1), delta * (1 - sigma) * 0.09, 1e-9);
  EXPECT_NEAR(cut.noise(0, 1), 0.0, 1e-12);
  EXPECT_LT(cut.noise(1, 1), 0.09 / 100);  // a 2.25 cm slab: far below the prior 0.09 m^2
  // The 3-sigma posterior ellipse contains the corners of slab ∩ prior ellipse.
  const Eigen::Matrix2d shape_inverse = (9.0 * cut.noise).inverse();
  for (double y : {lo, hi}) {
    for (double sx : {-1.0, 1.0}) {
      const Eigen::Vector2d d(sx * std::sqrt(0.81 - (y - 1.25) * (y - 1.25)), y - y_post);
      EXPECT_LE(d.dot(shape_inverse * d), 1.0 + 1e-9);
    }
  }
  // Deprior: one row on n^T p; fused with the prior along n it gives the cut's variance and mean.
  const MapAidedMeasurement dp = MakeMapAidedMeasurement(f.candidate, f.mount, f.pose, P, measured,
                                                         Config(MapAidedMethod::kEllipsoidCutDeprior));
  ASSERT_EQ(dp.cut_status, geometry::CutStatus::kUpdated);
  ASSERT_EQ(dp.innovation.size(), 1);
  EXPECT_NEAR((dp.jacobian - Eigen::RowVector3d(0.0, 1.0, 0.0)).norm(), 0.0, 1e-12);
  const double v_prior = 0.09, v_post = cut.noise(1, 1), r = dp.noise(0, 0);
  EXPECT_GT(r, 0.0);
  EXPECT_NEAR((1 / v_prior + 1 / r) * v_post, 1.0, 1e-9);
  EXPECT_NEAR(1.25 + v_prior / (v_prior + r) * dp.innovation[0], y_post, 1e-9);
}

TEST(MapAidedMeasurement, ContradictingEchoIsEmptyAndUninformativeEchoIsUnchanged) {
  const CutSetup f;
  for (MapAidedMethod method : {MapAidedMethod::kEllipsoidCut, MapAidedMethod::kEllipsoidCutDeprior}) {
    // Prior sigma 1 cm (y in 1.25 +- 0.03), range 0.95: slab around 1.45. Never clipped.
    const Eigen::Matrix3d small = Eigen::Vector3d(1e-4, 1e-4, 1e-6).asDiagonal();
    const auto empty = MakeMapAidedMeasurement(f.candidate, f.mount, f.pose, small, 0.95, Config(method));
    EXPECT_EQ(empty.cut_status, geometry::CutStatus::kEmpty);
    EXPECT_TRUE(empty.innovation.size() == 0 && empty.jacobian.rows() == 0 && empty.noise.size() == 0);
    // Prior sigma 1 mm (+-3 mm) inside a slab +-9 mm: the echo adds nothing.
    const Eigen::Matrix3d tiny = Eigen::Vector3d(1e-6, 1e-6, 1e-8).asDiagonal();
    const auto same = MakeMapAidedMeasurement(f.candidate, f.mount, f.pose, tiny, 0.75, Config(method));
    EXPECT_EQ(same.cut_status, geometry::CutStatus::kUnchanged);
    EXPECT_TRUE(same.innovation.size() == 0 && same.jacobian.rows() == 0 && same.noise.size() == 0);
  }
}

TEST(MapAidedMeasurement, HeadingUncertaintyWidensTheSlab) {
  // Row y = 0, vehicle at (0, -1.25) heading east, left-looking sensor: n = (0, -1), and
  // n^T p in [0.5 + d_lo, 0.5 + d_hi] widened by 3 sigma_phi |n^T R'(0) l| = 3 sigma_phi |l_x|.
  const RowMapRanging ranging = HorizontalRow();
  const Eigen::Vector3d pose(0.0, -1.25, 0.0);
  // Returns the cut's variance along n, after checking it against the cut of the slab widened by hand.
  const auto noise_along_n = [&](const Eigen::Vector2d& lever, double var_phi) {
    const RangeSensorMount mount{lever, kPi / 2, kHalf};
    const auto cs = ranging.Candidates(pose, mount, kMaxRange, 0.0);
    EXPECT_EQ(cs.size(), 1u);
    const Eigen::Matrix3d P = Eigen::Vector3d(0.09, 0.09, var_phi).asDiagonal();
    const double measured = 1.25 - lever.y() + 0.01;  // n^T p = 1.26 +- 0.009 (+- w)
    const auto m = MakeMapAidedMeasurement(cs.at(0), mount, pose, P, measured, Config(MapAidedMethod::kEllipsoidCut));
    EXPECT_EQ(m.cut_status, geometry::CutStatus::kUpdated);
    const double w = 3.0 * std::sqrt(var_phi) * std::abs(lever.x());
    const auto e = geometry::Ellipsoid<2>::FromCovariance(pose.head<2>(), P.topLeftCorner<2, 2>(), 3.0);
    const auto hand = geometry::ParallelCut(e, Eigen::Vector2d(0, -1), 1.26 - 0.009 - w, 1.26 + 0.009 + w);
    EXPECT_EQ(hand.status, geometry::CutStatus::kUpdated);
    EXPECT_NEAR((hand.ellipsoid.shape() / 9.0 - m.noise).norm(), 0.0, 1e-9) << lever.transpose() << " " << var_phi;
    EXPECT_NEAR((hand.ellipsoid.center() - pose.head<2>() - m.innovation).norm(), 0.0, 1e-9);
    return m.noise(1, 1);
  };
  const Eigen::Vector2d lever(0.75, 0.5);
  EXPECT_GT(noise_along_n(lever, 4e-4), 2.0 * noise_along_n(lever, 1e-6));  // sigma_phi 0.02: +-4.5 cm
  // A lever arm across the row only (l_x = 0): the bounds do not move with phi, no widening.
  EXPECT_NEAR(noise_along_n({0.0, 0.5}, 4e-4), noise_along_n({0.0, 0.5}, 1e-6), 1e-12);
}

TEST(MapAidedMeasurement, RangeMethodAndNisMatchHandValues) {
  const CutSetup f;  // H = (0, 1, 0.75), predicted 0.75
  Eigen::Matrix3d P;
  P << 0.04, 0.01, 0.002,  //
      0.01, 0.09, 0.003,   //
      0.002, 0.003, 0.0004;
  // y = 0.03; H P H^T = 0.09 + 2 * 0.75 * 0.003 + 0.75^2 * 0.0004 = 0.094725; + R (below).
  const double r = 9e-6 + 0.5 * std::pow(std::sqrt(0.8125) + 0.75, 2) * 0.0004 * 0.0004;
  EXPECT_NEAR(RangeNoiseVariance(f.candidate, f.mount, P, 0.003), r, 1e-18);
  EXPECT_NEAR(RangeNis(f.candidate, f.mount, 0.78, P, 0.003), 0.0009 / (0.094725 + r), 1e-12);
  EXPECT_NEAR(RangeNis(f.candidate, f.mount, 0.75, P, 0.003), 0.0, 1e-20);
  const auto m = MakeMapAidedMeasurement(f.candidate, f.mount, f.pose, P, 0.78, Config(MapAidedMethod::kRange));
  EXPECT_EQ(m.cut_status, geometry::CutStatus::kUpdated);
  ASSERT_EQ(m.innovation.size(), 1);
  EXPECT_NEAR(m.innovation[0], 0.03, 1e-12);
  EXPECT_NEAR((m.jacobian - Eigen::RowVector3d(0.0, 1.0, 0.75)).norm(), 0.0, 1e-12);
  // R = sigma^2 + (|l| + r)^2 sigma_phi^4 / 2 (second-order heading term): |l| = sqrt(0.8125).
  EXPECT_NEAR(m.noise(0, 0), 9e-6 + 0.5 * std::pow(std::sqrt(0.8125) + 0.75, 2) * 0.0004 * 0.0004, 1e-18);
}

TEST(MapAidedMeasurement, TheRowsOutlineAccuracyAddsToTheRangeNoiseAndWidensTheSlab) {
  // The same row with outline_sigma_m 4 mm: the candidate carries it, R grows by its square, the
  // cut's slab by k sqrt(sigma^2 + sigma_map^2) instead of k sigma.
  geometry::Row row = MakeRow("r", {{-10.0, 0.0}, {10.0, 0.0}});
  row.outline_sigma_m = 0.004;
  const RowMapRanging ranging = MakeRanging({row});
  EXPECT_EQ(ranging.max_outline_sigma_m(), 0.004);
  const CutSetup exact;
  const Eigen::Vector3d pose = exact.pose;
  const EchoCandidate candidate = ranging.Candidates(pose, exact.mount, kMaxRange, 0.0).at(0);
  EXPECT_EQ(candidate.map_sigma_m, 0.004);
  EXPECT_EQ(exact.candidate.map_sigma_m, 0.0);
  const Eigen::Matrix3d P = Eigen::Vector3d(0.01, 0.01, 1e-8).asDiagonal();
  EXPECT_NEAR(RangeNoiseVariance(candidate, exact.mount, P, 0.003) -
                  RangeNoiseVariance(exact.candidate, exact.mount, P, 0.003),
              0.004 * 0.004, 1e-15);
  const auto ranged = MakeMapAidedMeasurement(candidate, exact.mount, pose, P, 0.78, Config(MapAidedMethod::kRange));
  EXPECT_NEAR(ranged.noise(0, 0), RangeNoiseVariance(candidate, exact.mount, P, 0.003), 1e-18);
  // Deprior: the information the slab adds is smaller with the map's sigma (a wider slab).
  const auto with_map =
      MakeMapAidedMeasurement(candidate, exact.mount, pose, P, 0.78, Config(MapAidedMethod::kEllipsoidCutDeprior));
  const auto without =
      MakeMapAidedMeasurement(exact.candidate, exact.mount, pose, P, 0.78, Config(MapAidedMethod::kEllipsoidCutDeprior));
  ASSERT_EQ(with_map.cut_status, geometry::CutStatus::kUpdated);
  ASSERT_EQ(without.cut_status, geometry::CutStatus::kUpdated);
  EXPECT_GT(with_map.noise(0, 0), without.noise(0, 0));
}

}  // namespace
}  // namespace rowloc::localization
