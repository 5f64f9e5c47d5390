#include "rowloc/localization/range_to_line_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace rowloc::localization {
namespace {

constexpr double kPi = std::numbers::pi;

EdgeLine LineAtAngle(double direction_rad, double offset_m) {
  // Unit normal perpendicular to the line direction.
  return EdgeLine{Eigen::Vector2d(-std::sin(direction_rad), std::cos(direction_rad)), offset_m};
}

TEST(RangeToLine, PerpendicularBeamToHorizontalRow) {
  // Row y = 0, vehicle at (3, 1.2) heading east, sensor 0.3 m to the right looking right.
  const EdgeLine row = LineAtAngle(0.0, 0.0);
  const RangeSensorMount mount{Eigen::Vector2d(0.5, -0.3), -kPi / 2};
  const double pose[3] = {3.0, 1.2, 0.0};
  double range = 0.0;
  ASSERT_TRUE(RangeToLine(pose, mount, row, &range));
  EXPECT_NEAR(range, 0.9, 1e-12);
}

TEST(RangeToLine, VerticalRowWorks) {
  // Row x = 5 (parallel to the y axis), where y = m x + q has no representation.
  const EdgeLine row{Eigen::Vector2d(1.0, 0.0), 5.0};
  const RangeSensorMount mount{Eigen::Vector2d(0.0, 0.0), 0.0};
  const double pose[3] = {2.0, 40.0, 0.0};  // looking +x along the beam
  double range = 0.0;
  ASSERT_TRUE(RangeToLine(pose, mount, row, &range));
  EXPECT_NEAR(range, 3.0, 1e-12);
  // Heading tilted by 30 degrees: the slanted beam is longer by 1/cos(30 deg).
  const double tilted[3] = {2.0, 40.0, kPi / 6};
  ASSERT_TRUE(RangeToLine(tilted, mount, row, &range));
  EXPECT_NEAR(range, 3.0 / std::cos(kPi / 6), 1e-12);
}

TEST(RangeToLine, RejectsBeamPointingAwayOrParallel) {
  const EdgeLine row = LineAtAngle(0.0, 0.0);
  double range = -1.0;
  const double pose[3] = {0.0, 1.0, 0.0};
  EXPECT_FALSE(RangeToLine(pose, RangeSensorMount{{0, 0}, kPi / 2}, row, &range));  // away
  EXPECT_FALSE(RangeToLine(pose, RangeSensorMount{{0, 0}, 0.0}, row, &range));      // parallel
  EXPECT_EQ(range, -1.0);
}

// Central differences of RangeToLine<double>.
Eigen::RowVector3d NumericJacobian(const Eigen::Vector3d& pose, const RangeSensorMount& mount,
                                   const EdgeLine& line) {
  Eigen::RowVector3d j;
  const double h = 1e-6;
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector3d plus = pose, minus = pose;
    plus[i] += h;
    minus[i] -= h;
    double rp = 0, rm = 0;
    EXPECT_TRUE(RangeToLine(plus.data(), mount, line, &rp));
    EXPECT_TRUE(RangeToLine(minus.data(), mount, line, &rm));
    j[i] = (rp - rm) / (2 * h);
  }
  return j;
}

TEST(RangeToLine, AnalyticAndJetJacobiansMatchNumericDifferences) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  std::uniform_real_distribution<double> coord(-20.0, 20.0);
  std::uniform_real_distribution<double> arm(-1.0, 1.0);
  int checked = 0;
  for (int trial = 0; trial < 5000 && checked < 1000; ++trial) {
    const EdgeLine line = LineAtAngle(angle(rng), coord(rng));
    const RangeSensorMount mount{Eigen::Vector2d(arm(rng), arm(rng)), angle(rng)};
    const Eigen::Vector3d pose(coord(rng), coord(rng), angle(rng));
    const auto analytic = RangeToLineJacobian(pose, mount, line);
    const auto jet = RangeToLineJacobianAutoDiff(pose, mount, line);
    ASSERT_EQ(analytic.has_value(), jet.has_value());
    // Keep well-conditioned cases (not grazing, not huge) so that central differences are exact
    // to ~1e-6 relative.
    if (!analytic || analytic->range_m > 50.0) continue;
    const Eigen::Vector2d beam(std::cos(pose.z() + mount.beam_angle_rad),
                               std::sin(pose.z() + mount.beam_angle_rad));
    if (std::abs(line.normal.dot(beam)) < 0.2) continue;
    ++checked;
    EXPECT_NEAR(analytic->range_m, jet->range_m, 1e-12);
    const Eigen::RowVector3d numeric = NumericJacobian(pose, mount, line);
    const double scale = 1.0 + numeric.norm();
    EXPECT_LT((analytic->jacobian - numeric).norm() / scale, 1e-6) << "trial " << trial;
    EXPECT_LT((jet->jacobian - analytic->jacobian).norm() / scale, 1e-12) << "trial " << trial;
  }
  EXPECT_GE(checked, 500);
}

}  // namespace
}  // namespace rowloc::localization
