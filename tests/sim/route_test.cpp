#include "rowloc/sim/route.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

namespace rowloc::sim {
namespace {

using ::testing::HasSubstr;
constexpr double kPi = std::numbers::pi;

double AngleDiff(double a, double b) { return std::remainder(a - b, 2.0 * kPi); }

RouteSpec LineSpec(double length_m) {
  RouteSpec spec;
  spec.start_position_m = {1.0, 2.0};
  spec.start_heading_rad = 0.3;
  spec.pieces = {{length_m, 0.0, 0.0}};
  return spec;
}

/// Lines, arcs of both signs and clothoids, joined with curvature jumps and continuous ramps.
RouteSpec MixedSpec() {
  RouteSpec spec;
  spec.start_position_m = {-3.0, 5.0};
  spec.start_heading_rad = 2.5;
  spec.pieces = {{4.0, 0.0, 0.0},  {2.0, 0.0, 0.5},   {3.0, 0.5, 0.5},  {1.5, 0.5, -0.8}, {2.5, -0.8, -0.8},
                 {1.0, 0.0, 0.0},  {6.0, 0.25, 0.25}, {0.7, 1.2, 0.0},  {5.0, 0.0, 0.0}};
  spec.cruise_speed_mps = 1.5;
  spec.max_accel_mps2 = 0.8;
  spec.max_lateral_accel_mps2 = 0.6;
  spec.start_dwell_s = 2.0;
  spec.end_dwell_s = 1.0;
  return spec;
}

/// Reference position of a single clothoid by composite Simpson quadrature with tiny steps.
Eigen::Vector2d SimpsonClothoid(double heading, double k0, double rate, double length_m) {
  const int n = 200000;
  const double h = length_m / n;
  Eigen::Vector2d sum(0, 0);
  for (int i = 0; i <= n; ++i) {
    const double u = h * i;
    const double th = heading + k0 * u + 0.5 * rate * u * u;
    const double w = (i == 0 || i == n) ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
    sum += w * Eigen::Vector2d(std::cos(th), std::sin(th));
  }
  return sum * h / 3.0;
}

TEST(RouteTest, StraightLineIsExactWithTrapezoidalSpeed) {
  RouteSpec spec = LineSpec(10.0);
  spec.start_dwell_s = 3.0;
  spec.end_dwell_s = 2.0;
  const Route route(spec);
  // 1 s accelerating (0.5 m), 9 m at 1 m/s, 1 s braking (0.5 m).
  EXPECT_NEAR(route.duration_s(), 3.0 + 1.0 + 9.0 + 1.0 + 2.0, 1e-12);
  EXPECT_DOUBLE_EQ(route.length_m(), 10.0);
  const Eigen::Vector2d dir(std::cos(0.3), std::sin(0.3));
  for (double t = 0.0; t <= route.duration_s(); t += 0.0625) {
    const double m = t - 3.0;  // motion time
    const double s = m <= 0 ? 0.0 : m <= 1 ? 0.5 * m * m : m <= 10 ? m - 0.5 : m <= 11 ? 10 - 0.5 * (11 - m) * (11 - m) : 10.0;
    const double v = m <= 0 ? 0.0 : m <= 1 ? m : m <= 10 ? 1.0 : m <= 11 ? 11 - m : 0.0;
    const RoutePoint p = route.At(t);
    ASSERT_NEAR(p.station_m, s, 1e-12) << t;
    ASSERT_NEAR(p.speed_mps, v, 1e-12) << t;
    ASSERT_LT((p.position_m - (spec.start_position_m + s * dir)).norm(), 1e-12) << t;
    ASSERT_NEAR(p.heading_rad, 0.3, 1e-15);
    ASSERT_EQ(p.yaw_rate_radps, 0.0);
  }
  EXPECT_EQ(route.At(-5.0).position_m, spec.start_position_m);
  EXPECT_LT((route.At(1e9).position_m - (spec.start_position_m + 10.0 * dir)).norm(), 1e-12);
  EXPECT_EQ(route.At(1e9).speed_mps, 0.0);
}

TEST(RouteTest, ShortLineHasTriangularSpeed) {
  const Route route(LineSpec(0.5));  // cruise 1 m/s never reached with a = 1
  EXPECT_NEAR(route.duration_s(), 2.0 * std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(route.PeakSpeed_mps(), std::sqrt(0.5), 1e-12);
}

TEST(RouteTest, ArcsAreExactCircles) {
  for (const double radius : {4.0, -2.5, 0.3}) {
    RouteSpec spec;
    spec.start_position_m = {10.0, -7.0};
    spec.start_heading_rad = -1.0;
    spec.pieces = {{1.7 * 2 * kPi * std::abs(radius), 1 / radius, 1 / radius}};
    spec.max_lateral_accel_mps2 = 20.0;
    const Route route(spec);
    const double h0 = spec.start_heading_rad;
    for (double t = 0.0; t <= route.duration_s(); t += 0.01) {
      const RoutePoint p = route.At(t);
      const double th = h0 + p.station_m / radius;
      const Eigen::Vector2d exact =
          spec.start_position_m + radius * Eigen::Vector2d(std::sin(th) - std::sin(h0), std::cos(h0) - std::cos(th));
      ASSERT_LT((p.position_m - exact).norm(), 1e-9) << radius << " " << t;
      ASSERT_NEAR(AngleDiff(p.heading_rad, th), 0.0, 1e-12);
      ASSERT_GT(p.heading_rad, -kPi);
      ASSERT_LE(p.heading_rad, kPi);
      ASSERT_NEAR(p.yaw_rate_radps, p.speed_mps / radius, 1e-12);
    }
  }
}

TEST(RouteTest, ClothoidMatchesFineQuadrature) {
  RouteSpec spec;
  spec.start_heading_rad = 0.7;
  spec.pieces = {{2.0, 0.0, 1.0}, {3.0, 1.0, -2.0}, {25.0, -0.3, 0.0}};
  const Route route(spec);
  Eigen::Vector2d start = spec.start_position_m;
  double heading = spec.start_heading_rad, station = 0.0;
  for (const PathPiece& piece : spec.pieces) {
    const double rate = (piece.end_curvature_per_m - piece.start_curvature_per_m) / piece.length_m;
    for (const double fraction : {0.1, 0.37, 0.5, 0.93, 1.0}) {
      const double u = fraction * piece.length_m;
      const PathGeometry::Pose pose = route.geometry().At(station + u);
      const Eigen::Vector2d exact = start + SimpsonClothoid(heading, piece.start_curvature_per_m, rate, u);
      EXPECT_LT((pose.position_m - exact).norm(), 1e-9) << station + u;
      EXPECT_NEAR(pose.heading_rad, heading + piece.start_curvature_per_m * u + 0.5 * rate * u * u, 1e-12);
      if (fraction < 1.0) {  // at the end the next piece applies
        EXPECT_NEAR(pose.curvature_per_m, piece.start_curvature_per_m + rate * u, 1e-12);
      }
    }
    start += SimpsonClothoid(heading, piece.start_curvature_per_m, rate, piece.length_m);
    heading += 0.5 * (piece.start_curvature_per_m + piece.end_curvature_per_m) * piece.length_m;
    station += piece.length_m;
  }
}

TEST(RouteTest, DerivativesAreConsistentAtRandomTimes) {
  const Route route(MixedSpec());
  const std::vector<double> breaks = route.BreakTimes();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uniform(0.0, route.duration_s());
  const double h = 1e-5;
  int checked = 0;
  while (checked < 2000) {
    const double t = uniform(rng);
    const auto next = std::lower_bound(breaks.begin(), breaks.end(), t - 2 * h);
    if (next != breaks.end() && *next < t + 2 * h) continue;  // a jump of accel or curvature rate nearby
    const RoutePoint p = route.At(t), before = route.At(t - h), after = route.At(t + h);
    const Eigen::Vector2d velocity = (after.position_m - before.position_m) / (2 * h);
    const Eigen::Vector2d tangent(std::cos(p.heading_rad), std::sin(p.heading_rad));
    ASSERT_LT((velocity - p.speed_mps * tangent).norm(), 1e-7) << t;
    ASSERT_NEAR(AngleDiff(after.heading_rad, before.heading_rad) / (2 * h), p.yaw_rate_radps, 1e-7) << t;
    ASSERT_NEAR((after.station_m - before.station_m) / (2 * h), p.speed_mps, 1e-7) << t;
    ASSERT_NEAR((after.speed_mps - before.speed_mps) / (2 * h), p.accel_mps2, 1e-7) << t;
    ASSERT_NEAR((after.yaw_rate_radps - before.yaw_rate_radps) / (2 * h), p.yaw_accel_radps2, 1e-6) << t;
    ++checked;
  }
}

TEST(RouteTest, PathIsContinuousAcrossJoinsAndBreaks) {
  const Route route(MixedSpec());
  for (const double t : route.BreakTimes()) {
    const RoutePoint a = route.At(t - 1e-9), b = route.At(t + 1e-9);
    EXPECT_LT((a.position_m - b.position_m).norm(), 1e-8) << t;
    EXPECT_NEAR(AngleDiff(a.heading_rad, b.heading_rad), 0.0, 1e-8) << t;
    EXPECT_NEAR(a.speed_mps, b.speed_mps, 1e-8) << t;
  }
}

TEST(RouteTest, SpeedRespectsEveryLimit) {
  const RouteSpec spec = MixedSpec();
  const Route route(spec);
  for (double t = 0.0; t <= route.duration_s(); t += 0.003) {
    const RoutePoint p = route.At(t);
    ASSERT_GE(p.speed_mps, 0.0);
    ASSERT_LE(p.speed_mps, spec.cruise_speed_mps * (1 + 1e-12));
    ASSERT_LE(std::abs(p.accel_mps2), spec.max_accel_mps2 * (1 + 1e-12));
    ASSERT_LE(std::abs(p.curvature_per_m) * p.speed_mps * p.speed_mps, spec.max_lateral_accel_mps2 * (1 + 1e-9)) << t;
  }
  EXPECT_LE(route.PeakSpeed_mps(), spec.cruise_speed_mps * (1 + 1e-12));
  EXPECT_GT(route.PeakSpeed_mps(), 0.9 * spec.cruise_speed_mps);  // the long line allows cruising
  // Standing still during the dwells, moving in between.
  EXPECT_EQ(route.At(1.999).speed_mps, 0.0);
  EXPECT_EQ(route.At(1.999).position_m, spec.start_position_m);
  EXPECT_EQ(route.At(route.duration_s() - 0.5).speed_mps, 0.0);
  EXPECT_GT(route.At(2.5).speed_mps, 0.0);
}

TEST(RouteTest, TimeAtStationInvertsTheMotion) {
  const Route route(MixedSpec());
  for (double s = 0.0; s <= route.length_m(); s += 0.173) {
    const double t = route.TimeAtStation(s);
    EXPECT_NEAR(route.At(t).station_m, s, 1e-9) << s;
  }
  EXPECT_NEAR(route.At(route.duration_s()).station_m, route.length_m(), 1e-12);
  EXPECT_THROW(route.TimeAtStation(std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
  EXPECT_THROW(route.At(std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
}

TEST(RouteTest, TotalTimeMatchesIntegratedSpeed) {
  const Route route(MixedSpec());
  // Trapezoid rule on v(t): the integral must equal the length.
  const int n = 200000;
  const double dt = route.duration_s() / n;
  double distance = 0.0;
  for (int i = 0; i < n; ++i) distance += 0.5 * dt * (route.At(i * dt).speed_mps + route.At((i + 1) * dt).speed_mps);
  EXPECT_NEAR(distance, route.length_m(), 1e-5);
}

TEST(RouteTest, RejectsBadSpecsNamingTheField) {
  const auto error_of = [](const RouteSpec& spec) -> std::string {
    try {
      Route route(spec);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "(no error)";
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  RouteSpec spec = LineSpec(5.0);
  spec.pieces.clear();
  EXPECT_THAT(error_of(spec), HasSubstr("at least one piece"));
  spec = LineSpec(5.0);
  spec.start_position_m.x() = nan;
  EXPECT_THAT(error_of(spec), HasSubstr("start_position_m"));
  spec = LineSpec(5.0);
  spec.start_heading_rad = std::numeric_limits<double>::infinity();
  EXPECT_THAT(error_of(spec), HasSubstr("start_heading_rad"));
  spec = LineSpec(-1.0);
  EXPECT_THAT(error_of(spec), HasSubstr("pieces[0].length_m"));
  spec = LineSpec(5.0);
  spec.pieces.push_back({1.0, 0.0, 10.5});
  EXPECT_THAT(error_of(spec), HasSubstr("pieces[1]"));
  spec = LineSpec(5.0);
  spec.pieces.push_back({1.0, nan, 0.0});
  EXPECT_THAT(error_of(spec), HasSubstr("pieces[1]"));
  spec = LineSpec(5.0);
  spec.pieces = {{1e5, 0.0, 10.0}};  // 1e7 quadrature sub-intervals of 1 cm
  EXPECT_THAT(error_of(spec), HasSubstr("more than 1e7 sub-intervals"));
  spec = LineSpec(5.0);
  spec.pieces = {{1e5, 0.0, 0.0}, {1e5, 0.01, 0.01}};  // long lines and arcs need no sub-intervals
  EXPECT_EQ(error_of(spec), "(no error)");
  spec = LineSpec(5.0);
  spec.cruise_speed_mps = 0.0;
  EXPECT_THAT(error_of(spec), HasSubstr("cruise_speed_mps"));
  spec = LineSpec(5.0);
  spec.max_accel_mps2 = nan;
  EXPECT_THAT(error_of(spec), HasSubstr("max_accel_mps2"));
  spec = LineSpec(5.0);
  spec.max_lateral_accel_mps2 = -1.0;
  EXPECT_THAT(error_of(spec), HasSubstr("max_lateral_accel_mps2"));
  spec = LineSpec(5.0);
  spec.start_dwell_s = -1.0;
  EXPECT_THAT(error_of(spec), HasSubstr("start_dwell_s"));
  spec = LineSpec(5.0);
  spec.end_dwell_s = nan;
  EXPECT_THAT(error_of(spec), HasSubstr("end_dwell_s"));
  EXPECT_EQ(error_of(LineSpec(5.0)), "(no error)");
  EXPECT_EQ(RouteSpecProblem(LineSpec(5.0)), std::nullopt);
}

}  // namespace
}  // namespace rowloc::sim
