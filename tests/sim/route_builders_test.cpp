#include "rowloc/sim/route_builders.hpp"

#include <boost/math/tools/minima.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace rowloc::sim {
namespace {

using ::testing::HasSubstr;
constexpr double kPi = std::numbers::pi;

double AngleDiff(double a, double b) { return std::remainder(a - b, 2.0 * kPi); }
Eigen::Vector2d Dir(double heading) { return {std::cos(heading), std::sin(heading)}; }
Eigen::Vector2d Left(double heading) { return {-std::sin(heading), std::cos(heading)}; }

TEST(StraightRouteTest, OneLineWithTheGivenMotion) {
  const RouteSpec spec = StraightRoute({3, 4}, 1.0, 25.0, 1.0, 1.0);
  ASSERT_EQ(spec.pieces.size(), 1u);
  EXPECT_EQ(spec.pieces[0], (PathPiece{25.0, 0.0, 0.0}));
  EXPECT_EQ(spec.cruise_speed_mps, 1.0);
  EXPECT_EQ(spec.max_accel_mps2, 1.0);
  const Route route(spec);
  EXPECT_LT((route.At(route.duration_s()).position_m - (Eigen::Vector2d(3, 4) + 25.0 * Dir(1.0))).norm(), 1e-12);
  EXPECT_THROW(StraightRoute({0, 0}, 0.0, 0.0, 1.0, 1.0), std::invalid_argument);
  EXPECT_THROW(StraightRoute({0, 0}, 0.0, 5.0, -1.0, 1.0), std::invalid_argument);
  EXPECT_THROW(StraightRoute({NAN, 0}, 0.0, 5.0, 1.0, 1.0), std::invalid_argument);
}

TEST(CircleRouteTest, ClosesAfterEachLap) {
  for (const double radius : {4.0, -4.0}) {
    const Eigen::Vector2d start(1.0, -2.0);
    const Route route(CircleRoute(start, 0.4, radius, 3, 1.0, 1.0));
    EXPECT_NEAR(route.length_m(), 3 * 2 * kPi * 4.0, 1e-9);
    for (int lap = 1; lap <= 3; ++lap) {
      const RoutePoint p = route.At(route.TimeAtStation(lap * 2 * kPi * 4.0));
      EXPECT_LT((p.position_m - start).norm(), 1e-9) << radius << " lap " << lap;
      EXPECT_NEAR(AngleDiff(p.heading_rad, 0.4), 0.0, 1e-12);
    }
    // Half a lap: diametrically opposite, on the side of the turn.
    const RoutePoint half = route.At(route.TimeAtStation(kPi * 4.0));
    EXPECT_LT((half.position_m - (start + 2 * radius * Left(0.4))).norm(), 1e-9);
    EXPECT_GT(half.yaw_rate_radps * radius, 0.0);  // left turn for R > 0, right for R < 0
  }
  EXPECT_THROW(CircleRoute({0, 0}, 0.0, 0.0, 1, 1.0, 1.0), std::invalid_argument);
  EXPECT_THROW(CircleRoute({0, 0}, 0.0, 4.0, 0, 1.0, 1.0), std::invalid_argument);
}

TEST(ShuttleRouteTest, LegsAlternateDirectionAndEndWhereExpected) {
  const double leg = 20.0, heading = 0.25;
  const Eigen::Vector2d start(5.0, 6.0);
  for (const double transition : {0.0, 2.5}) {
  for (const double radius : {4.0, -4.0}) {  // -4: first turn right, as in Lindgren et al. 2002
    const RouteSpec spec = ShuttleRoute(start, heading, leg, 5, radius, 1.0, 1.0, transition);
    ASSERT_EQ(spec.pieces.size(), transition == 0.0 ? 9u : 17u);
    const Route route(spec);
    const Eigen::Vector2d side = (radius > 0 ? 1.0 : -1.0) * Left(heading);
    const double turn_length = (route.length_m() - 5 * leg) / 4;
    if (transition == 0.0) {
      EXPECT_NEAR(turn_length, kPi * 4.0, 1e-12);
    }
    const double period = leg + turn_length;
    for (int i = 0; i < 5; ++i) {
      const Eigen::Vector2d leg_start = start + i * 8.0 * side + (i % 2 == 0 ? 0.0 : leg) * Dir(heading);
      const double leg_heading = heading + (i % 2 == 0 ? 0.0 : kPi);
      const RoutePoint a = route.At(route.TimeAtStation(i * period));
      const RoutePoint mid = route.At(route.TimeAtStation(i * period + 0.5 * leg));
      const RoutePoint b = route.At(route.TimeAtStation(i * period + leg));
      EXPECT_LT((a.position_m - leg_start).norm(), 1e-9) << radius << " leg " << i;
      EXPECT_LT((b.position_m - (leg_start + leg * Dir(leg_heading))).norm(), 1e-9) << radius << " leg " << i;
      EXPECT_NEAR(AngleDiff(mid.heading_rad, leg_heading), 0.0, 1e-12);
      if (i > 0) {  // the turn before leg i alternates: first turn on `side`
        const RoutePoint turn = route.At(route.TimeAtStation(i * period - 0.5 * turn_length));
        const double expected_sign = (radius > 0 ? 1.0 : -1.0) * (i % 2 == 1 ? 1.0 : -1.0);
        EXPECT_GT(turn.curvature_per_m * expected_sign, 0.0) << i;
      }
    }
    const Eigen::Vector2d end = start + 4 * 8.0 * side + leg * Dir(heading);
    EXPECT_LT((route.At(route.duration_s()).position_m - end).norm(), 1e-9);
    // With transitions the yaw rate is continuous everywhere; without, it steps at the joins.
    double largest_step = 0.0;
    for (const double t : route.BreakTimes()) {
      largest_step = std::max(largest_step, std::abs(route.At(t + 1e-9).yaw_rate_radps - route.At(t - 1e-9).yaw_rate_radps));
    }
    if (transition > 0.0) {
      EXPECT_LT(largest_step, 1e-6);
    } else {
      EXPECT_GT(largest_step, 0.1);
    }
  }
  }
  EXPECT_THROW(ShuttleRoute(start, 0.0, leg, 0, 4.0, 1.0, 1.0), std::invalid_argument);
  EXPECT_THROW(ShuttleRoute(start, 0.0, leg, 3, 0.05, 1.0, 1.0), std::invalid_argument);
  EXPECT_THROW(ShuttleRoute(start, 0.0, -1.0, 3, 4.0, 1.0, 1.0), std::invalid_argument);
  EXPECT_THROW(ShuttleRoute(start, 0.0, leg, 3, 4.0, 1.0, 1.0, 4.5), std::invalid_argument);   // > radius
  EXPECT_THROW(ShuttleRoute(start, 0.0, leg, 3, 4.0, 1.0, 1.0, 0.05), std::invalid_argument);  // < 0.1 m
  try {
    ShuttleRoute(start, 0.0, leg, 3, 0.1, 1.0, 1.0, 0.1);  // needs k > 1/r = 10
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& error) {
    EXPECT_THAT(error.what(), HasSubstr("curvature above 10 /m"));
  }
}

RowWorld MakeWorld(RowCurvature curvature, double radius_m) {
  RowWorldParams params;
  params.curvature = curvature;
  params.curvature_radius_m = radius_m;
  params.heading_rad = 0.6;
  return RowWorld(params);
}

/// Distance from p to the centre line of a row, minimized over the station (scan, then Brent).
/// Also returns whether the nearest station is inside (0, L) (not clamped at an end).
std::pair<double, bool> DistanceToRow(const RowWorld& world, int row, const Eigen::Vector2d& p) {
  const double length = world.params().row_length_m, step = 0.25;
  const auto squared = [&](double s) { return (world.RowCentre(row, s) - p).squaredNorm(); };
  double best_s = 0.0;
  for (double s = 0.0; s <= length; s += step)
    if (squared(s) < squared(best_s)) best_s = s;
  const auto [s, d2] = boost::math::tools::brent_find_minima(squared, std::max(0.0, best_s - step),
                                                             std::min(length, best_s + step), 52);
  return {std::sqrt(d2), s > 1e-6 && s < length - 1e-6};
}

void ExpectMidwayBetweenRows(const RowWorld& world, int first_lane, int lane_count, double transition = 0.0) {
  const double spacing = world.params().row_spacing_m, headland = 3.0;
  const Route route(RowsRoute(world, first_lane, lane_count, headland, 1.0, 1.0, transition));
  std::set<int> lanes_seen;
  for (double s = 0.0; s <= route.length_m(); s += 0.5) {
    const Eigen::Vector2d p = route.geometry().At(s).position_m;
    std::vector<std::pair<double, int>> distances;
    bool inside = true;
    for (int row = 0; row < world.params().row_count; ++row) {
      const auto [d, interior] = DistanceToRow(world, row, p);
      distances.push_back({d, row});
      inside = inside && interior;
    }
    if (!inside) continue;  // headland or turn
    std::sort(distances.begin(), distances.end());
    ASSERT_NEAR(distances[0].first, 0.5 * spacing, 1e-6) << s;
    ASSERT_NEAR(distances[1].first, 0.5 * spacing, 1e-6) << s;
    ASSERT_EQ(std::abs(distances[0].second - distances[1].second), 1) << s;
    lanes_seen.insert(std::min(distances[0].second, distances[1].second));
  }
  std::set<int> expected;
  for (int j = first_lane; j < first_lane + lane_count; ++j) expected.insert(j);
  EXPECT_EQ(lanes_seen, expected);
  // Starts on lane first_lane, headland_m before station 0, heading along the rows.
  const Eigen::Vector2d n0 = world.ReferenceNormal(0.0), t0(n0.y(), -n0.x());
  const RoutePoint start = route.At(0.0);
  EXPECT_LT((start.position_m - (world.ReferencePoint(0.0) + (first_lane + 0.5) * spacing * n0 - headland * t0)).norm(),
            1e-12);
  EXPECT_NEAR(AngleDiff(start.heading_rad, world.params().heading_rad), 0.0, 1e-12);
  // The turns (radius spacing / 2) slow the vehicle to sqrt(0.5 / kappa).
  for (double t = 0.0; t <= route.duration_s(); t += 0.05) {
    const RoutePoint p = route.At(t);
    ASSERT_LE(std::abs(p.curvature_per_m) * p.speed_mps * p.speed_mps, 0.5 * (1 + 1e-9));
  }
}

TEST(RowsRouteTest, StaysMidwayBetweenStraightRows) { ExpectMidwayBetweenRows(MakeWorld(RowCurvature::kStraight, 0.0), 0, 5); }
TEST(RowsRouteTest, StaysMidwayBetweenArcRows) {
  ExpectMidwayBetweenRows(MakeWorld(RowCurvature::kArc, 30.0), 1, 3);
  ExpectMidwayBetweenRows(MakeWorld(RowCurvature::kArc, -30.0), 0, 5, 0.8);
}
TEST(RowsRouteTest, StaysMidwayBetweenSCurveRows) {
  ExpectMidwayBetweenRows(MakeWorld(RowCurvature::kSCurve, 25.0), 0, 5);
  ExpectMidwayBetweenRows(MakeWorld(RowCurvature::kSCurve, -40.0), 2, 2, 1.25);
}

TEST(RowsRouteTest, RejectsLanesOutsideTheWorld) {
  const RowWorld world = MakeWorld(RowCurvature::kStraight, 0.0);  // 6 rows: lanes 0..4
  EXPECT_NO_THROW(RowsRoute(world, 4, 1, 0.0, 1.0, 1.0));
  EXPECT_THROW(RowsRoute(world, -1, 1, 3.0, 1.0, 1.0), std::invalid_argument);
  EXPECT_THROW(RowsRoute(world, 5, 1, 3.0, 1.0, 1.0), std::invalid_argument);
  EXPECT_THROW(RowsRoute(world, 2, 4, 3.0, 1.0, 1.0), std::invalid_argument);
  EXPECT_THROW(RowsRoute(world, 0, 0, 3.0, 1.0, 1.0), std::invalid_argument);
  EXPECT_THROW(RowsRoute(world, 0, 2, -1.0, 1.0, 1.0), std::invalid_argument);
  EXPECT_THROW(RowsRoute(world, 0, 2, 3.0, 1.0, 1.0, 1.3), std::invalid_argument);  // > spacing / 2
}

// ---------------------------------------------------------------------------------------------
// JSON

const std::string kMotion =
    R"("speed_mps": 1.0, "accel_mps2": 1.0, "max_lateral_accel_mps2": 0.8, "start_dwell_s": 2.0, "end_dwell_s": 3.0)";

std::string ErrorOf(const std::string& text, const RowWorld* world = nullptr) {
  try {
    ParseRouteSpec(text, "scenario.json", world, "route");
  } catch (const RouteConfigError& error) {
    return error.what();
  }
  return "(no error)";
}

TEST(ParseRouteSpecTest, EveryTypeEqualsItsBuilder) {
  const auto with_motion = [](RouteSpec spec) {
    spec.max_lateral_accel_mps2 = 0.8;
    spec.start_dwell_s = 2.0;
    spec.end_dwell_s = 3.0;
    return spec;
  };
  EXPECT_EQ(ParseRouteSpec(R"({"type": "straight", "start": [1, 2], "heading_rad": 0.5, "length_m": 30, )" + kMotion + "}",
                           "a.json", nullptr),
            with_motion(StraightRoute({1, 2}, 0.5, 30.0, 1.0, 1.0)));
  EXPECT_EQ(ParseRouteSpec(R"({"type": "circle", "start": [0, 0], "heading_rad": 0, "radius_m": -4, "laps": 2, )" + kMotion + "}",
                           "a.json", nullptr),
            with_motion(CircleRoute({0, 0}, 0.0, -4.0, 2, 1.0, 1.0)));
  EXPECT_EQ(ParseRouteSpec(R"({"type": "shuttle", "start": [0, 0], "heading_rad": 0, "leg_length_m": 15, "legs": 4,
                               "turn_radius_m": -4, "turn_transition_m": 1.5, )" + kMotion + "}",
                           "a.json", nullptr),
            with_motion(ShuttleRoute({0, 0}, 0.0, 15.0, 4, -4.0, 1.0, 1.0, 1.5)));
  const RowWorld world = MakeWorld(RowCurvature::kArc, 30.0);
  EXPECT_EQ(ParseRouteSpec(R"({"type": "rows", "first_lane": 1, "lane_count": 2, "headland_m": 4, "turn_transition_m": 0, )" +
                               kMotion + "}",
                           "a.json", &world),
            with_motion(RowsRoute(world, 1, 2, 4.0, 1.0, 1.0)));
}

TEST(ParseRouteSpecTest, ErrorsNameSourceKeyAndReason) {
  const std::string straight = R"({"type": "straight", "start": [1, 2], "heading_rad": 0.5, "length_m": 30, )";
  EXPECT_EQ(ErrorOf(straight + kMotion + "}"), "(no error)");
  EXPECT_EQ(ErrorOf(R"({"type": "straight", "start": [1, 2], "heading_rad": 0.5, )" + kMotion + "}"),
            "scenario.json: route.length_m: missing key");
  EXPECT_EQ(ErrorOf(straight + kMotion + R"(, "lenght_m": 3})"), "scenario.json: route.lenght_m: unknown key");
  EXPECT_THAT(ErrorOf(straight + kMotion + R"(, "radius_m": 3})"), HasSubstr("route.radius_m: unknown key"));
  EXPECT_THAT(ErrorOf(R"({"type": "straight", "start": [1], "heading_rad": 0.5, "length_m": 30, )" + kMotion + "}"),
              HasSubstr("route.start: must be an array of 2 numbers"));
  EXPECT_THAT(ErrorOf(R"({"type": "straight", "start": [1, 2], "heading_rad": "0", "length_m": 30, )" + kMotion + "}"),
              HasSubstr("route.heading_rad: must be a number"));
  EXPECT_THAT(ErrorOf(R"({"type": "spiral", "start": [1, 2], "heading_rad": 0, )" + kMotion + "}"),
              HasSubstr("route.type: unknown route type \"spiral\""));
  EXPECT_THAT(ErrorOf(R"({"type": "rows", "first_lane": 0, "lane_count": 1, "headland_m": 3, "turn_transition_m": 0, )" +
                      kMotion + "}"),
              HasSubstr("route.type: a \"rows\" route needs a world"));
  const RowWorld world = MakeWorld(RowCurvature::kStraight, 0.0);
  EXPECT_THAT(ErrorOf(R"({"type": "rows", "first_lane": 4, "lane_count": 2, "headland_m": 3, "turn_transition_m": 0, )" +
                      kMotion + "}", &world),
              HasSubstr("scenario.json: route: lane_count must be in"));
  EXPECT_THAT(ErrorOf(R"({"type": "rows", "first_lane": 0.5, "lane_count": 2, "headland_m": 3, "turn_transition_m": 0, )" +
                      kMotion + "}", &world),
              HasSubstr("route.first_lane: must be an integer"));
  EXPECT_THAT(ErrorOf(R"({"type": "rows", "first_lane": 0, "lane_count": 2, "headland_m": 3, )" + kMotion + "}", &world),
              HasSubstr("route.turn_transition_m: missing key"));
  EXPECT_THAT(ErrorOf(R"({"type": "shuttle", "start": [0, 0], "heading_rad": 0, "leg_length_m": 15, "legs": 4,
                          "turn_radius_m": 4, "turn_transition_m": 5, )" + kMotion + "}"),
              HasSubstr("scenario.json: route: turn_transition_m must be 0 or in"));
  EXPECT_THAT(ErrorOf(R"({"type": "circle", "start": [0, 0], "heading_rad": 0, "radius_m": 0, "laps": 2, )" + kMotion + "}"),
              HasSubstr("scenario.json: route: radius_m must be"));
  EXPECT_THAT(ErrorOf(R"({"type": "circle", "start": [0, 0], "heading_rad": 0, "radius_m": 3, "laps": 0, )" + kMotion + "}"),
              HasSubstr("route.laps: must be in [1, 1000]"));
  EXPECT_THAT(ErrorOf(straight + R"("speed_mps": 0, "accel_mps2": 1, "max_lateral_accel_mps2": 1, "start_dwell_s": 0, "end_dwell_s": 0})"),
              HasSubstr("route.speed_mps: must be in"));
  EXPECT_THAT(ErrorOf(straight + R"("speed_mps": 1, "accel_mps2": 1, "max_lateral_accel_mps2": 1, "start_dwell_s": -1, "end_dwell_s": 0})"),
              HasSubstr("route.start_dwell_s: must be in"));
  EXPECT_THAT(ErrorOf(straight + R"("speed_mps": 1, "accel_mps2": 1, "max_lateral_accel_mps2": 1, "start_dwell_s": 0})"),
              HasSubstr("route.end_dwell_s: missing key"));
  EXPECT_THAT(ErrorOf("[1, 2]"), HasSubstr("scenario.json: route: must be an object"));
  EXPECT_THAT(ErrorOf("{\"type\": "), HasSubstr("scenario.json: invalid JSON"));
  // Without a prefix the key path starts at the object.
  try {
    ParseRouteSpec(R"({"type": "straight"})", "r.json", nullptr);
    ADD_FAILURE() << "no error";
  } catch (const RouteConfigError& error) {
    EXPECT_STREQ(error.what(), "r.json: speed_mps: missing key");
  }
}

// "pieces": the PathPieces of a RouteSpec written out.

/// `{"length_m": .., "start_curvature_per_m": .., "end_curvature_per_m": ..}` with exact (17-digit) numbers.
std::string PieceJson(const PathPiece& piece) {
  std::ostringstream out;
  out.precision(17);
  out << R"({"length_m": )" << piece.length_m << R"(, "start_curvature_per_m": )" << piece.start_curvature_per_m
      << R"(, "end_curvature_per_m": )" << piece.end_curvature_per_m << "}";
  return out.str();
}

std::string PiecesRouteJson(const std::vector<PathPiece>& pieces, const std::string& start = "[1, -2]",
                            const std::string& heading = "0.5") {
  std::string list;
  for (const PathPiece& piece : pieces) list += (list.empty() ? "" : ", ") + PieceJson(piece);
  return R"({"type": "pieces", "start": )" + start + R"(, "heading_rad": )" + heading + R"(, "pieces": [)" + list +
         "], " + kMotion + "}";
}

TEST(ParseRouteSpecTest, PiecesTypeEqualsTheSpecBuiltByHand) {
  RouteSpec expected;
  expected.start_position_m = {1.0, -2.0};
  expected.start_heading_rad = 0.5;
  // A line, a clothoid into a left arc and out of it, and a right arc.
  expected.pieces = {{10.0, 0.0, 0.0}, {2.5, 0.0, 0.4}, {3.0, 0.4, 0.4}, {2.5, 0.4, 0.0}, {6.0, -0.25, -0.25}};
  expected.cruise_speed_mps = 1.0;
  expected.max_accel_mps2 = 1.0;
  expected.max_lateral_accel_mps2 = 0.8;
  expected.start_dwell_s = 2.0;
  expected.end_dwell_s = 3.0;
  const std::string text = PiecesRouteJson(expected.pieces);
  EXPECT_EQ(ParseRouteSpec(text, "a.json", nullptr), expected);
  const RowWorld world = MakeWorld(RowCurvature::kStraight, 0.0);  // a world changes nothing for "pieces"
  EXPECT_EQ(ParseRouteSpec(text, "a.json", &world, "route"), expected);
  EXPECT_EQ(ParseRouteSpec(PiecesRouteJson({{30.0, 0.0, 0.0}}), "a.json", nullptr).pieces,
            StraightRoute({1, -2}, 0.5, 30.0, 1.0, 1.0).pieces);
  EXPECT_NEAR(Route(expected).length_m(), 24.0, 1e-12);
}

TEST(ParseRouteSpecTest, PiecesFigureOfEightEndsWhereGeometrySays) {
  // Lindgren et al. 2002: 1.5 loops clockwise, then 1.5 loops anticlockwise, on a 4 m radius: two arcs.
  const double radius = 4.0, heading = 0.3;
  const double loops_m = 1.5 * 2.0 * kPi * radius;
  const Eigen::Vector2d start(2.0, 3.0);
  const RouteSpec spec = ParseRouteSpec(PiecesRouteJson({{loops_m, -1.0 / radius, -1.0 / radius},
                                                         {loops_m, 1.0 / radius, 1.0 / radius}},
                                                        "[2, 3]", "0.3"),
                                        "scenario.json", nullptr, "route");
  ASSERT_EQ(spec.pieces.size(), 2u);
  EXPECT_EQ(spec.pieces[0], (PathPiece{loops_m, -0.25, -0.25}));
  EXPECT_EQ(spec.pieces[1], (PathPiece{loops_m, 0.25, 0.25}));
  const Route route(spec);
  EXPECT_NEAR(route.length_m(), 2.0 * loops_m, 1e-9);
  const PathGeometry& path = route.geometry();
  // First circle (clockwise, centre on the right): back at the start after one loop; after 1.5 loops
  // diametrically opposite, 2 R to the right, heading reversed.
  const Eigen::Vector2d right = -Left(heading);
  EXPECT_LT((path.At(2.0 * kPi * radius).position_m - start).norm(), 1e-9);
  const Eigen::Vector2d middle = start + 2.0 * radius * right;
  EXPECT_LT((path.At(loops_m).position_m - middle).norm(), 1e-9);
  EXPECT_NEAR(AngleDiff(path.At(loops_m).heading_rad, heading + kPi), 0.0, 1e-12);
  EXPECT_NEAR(path.At(loops_m).heading_rad, heading - 3.0 * kPi, 1e-12);  // turned 3 pi clockwise
  // Second circle (anticlockwise, centre further right): tangent to the first where they meet;
  // back at the middle after one loop, 4 R to the right of the start after 1.5, heading as at the start.
  EXPECT_LT((path.At(loops_m + 2.0 * kPi * radius).position_m - middle).norm(), 1e-9);
  const RoutePoint end = route.At(route.duration_s());
  EXPECT_LT((end.position_m - (start + 4.0 * radius * right)).norm(), 1e-9);
  EXPECT_NEAR(AngleDiff(end.heading_rad, heading), 0.0, 1e-12);
  EXPECT_NEAR(path.At(2.0 * loops_m).heading_rad, heading, 1e-12);  // net turn 0
  EXPECT_EQ(end.speed_mps, 0.0);
  // Yaw rate: clockwise on the first circle, anticlockwise on the second.
  EXPECT_LT(route.At(route.TimeAtStation(0.5 * loops_m)).yaw_rate_radps, 0.0);
  EXPECT_GT(route.At(route.TimeAtStation(1.5 * loops_m)).yaw_rate_radps, 0.0);
}

TEST(ParseRouteSpecTest, PiecesErrorsNameSourceAndKeyPath) {
  const PathPiece line{5.0, 0.0, 0.0};
  const std::string head = R"({"type": "pieces", "start": [0, 0], "heading_rad": 0, )";
  const auto with_pieces = [&](const std::string& pieces) {
    return head + R"("pieces": )" + pieces + ", " + kMotion + "}";
  };
  const std::string two_lines = PieceJson(line) + ", " + PieceJson(line) + ", ";
  EXPECT_EQ(ErrorOf(with_pieces("[" + PieceJson(line) + "]")), "(no error)");
  // Missing keys.
  EXPECT_EQ(ErrorOf(head + kMotion + "}"), "scenario.json: route.pieces: missing key");
  EXPECT_EQ(ErrorOf(R"({"type": "pieces", "heading_rad": 0, "pieces": [)" + PieceJson(line) + "], " + kMotion + "}"),
            "scenario.json: route.start: missing key");
  EXPECT_EQ(ErrorOf(with_pieces("[" + PieceJson(line) + R"(, {"length_m": 5, "start_curvature_per_m": 0}])")),
            "scenario.json: route.pieces[1].end_curvature_per_m: missing key");
  // Unknown keys.
  EXPECT_EQ(ErrorOf(with_pieces(
                R"([{"length_m": 5, "start_curvature_per_m": 0, "end_curvature_per_m": 0, "radius_m": 4}])")),
            "scenario.json: route.pieces[0].radius_m: unknown key");
  EXPECT_EQ(ErrorOf(head + R"("pieces": [)" + PieceJson(line) + "], " + kMotion + R"(, "laps": 2})"),
            "scenario.json: route.laps: unknown key");
  // Wrong types.
  EXPECT_EQ(ErrorOf(with_pieces(PieceJson(line))), "scenario.json: route.pieces: must be an array, got object");
  EXPECT_EQ(ErrorOf(with_pieces("[" + PieceJson(line) + ", [5, 0, 0]]")),
            "scenario.json: route.pieces[1]: must be an object, got array");
  EXPECT_EQ(ErrorOf(with_pieces("[" + two_lines +
                                R"({"length_m": "5", "start_curvature_per_m": 0, "end_curvature_per_m": 0}])")),
            "scenario.json: route.pieces[2].length_m: must be a number, got string");
  EXPECT_EQ(ErrorOf(with_pieces(R"([{"length_m": 5, "start_curvature_per_m": null, "end_curvature_per_m": 0}])")),
            "scenario.json: route.pieces[0].start_curvature_per_m: must be a number, got null");
  // An empty list, and RouteSpecProblem's limits: 1e-6 m <= length <= 1e5 m, |kappa| <= 10 /m, total <= 1e6 m.
  EXPECT_EQ(ErrorOf(with_pieces("[]")), "scenario.json: route.pieces: must have 1 to 100000 elements, got 0");
  EXPECT_EQ(ErrorOf(with_pieces("[" + two_lines + PieceJson({0.0, 0.0, 0.0}) + "]")),
            "scenario.json: route.pieces[2].length_m: must be in [1e-06, 100000], got 0");
  EXPECT_EQ(ErrorOf(with_pieces("[" + PieceJson({2e5, 0.0, 0.0}) + "]")),
            "scenario.json: route.pieces[0].length_m: must be in [1e-06, 100000], got 200000");
  EXPECT_EQ(ErrorOf(with_pieces("[" + PieceJson({1.0, 0.5, -12.5}) + "]")),
            "scenario.json: route.pieces[0].end_curvature_per_m: must be in [-10, 10], got -12.5");
  std::string too_long = "[";
  for (int i = 0; i < 11; ++i) too_long += (i == 0 ? "" : ", ") + PieceJson({1e5, 0.0, 0.0});
  EXPECT_EQ(ErrorOf(with_pieces(too_long + "]")), "scenario.json: route: pieces: total length must be <= 1e6 m");
  // Without a prefix the key path starts at the object.
  try {
    ParseRouteSpec(with_pieces("[" + PieceJson({0.0, 0.0, 0.0}) + "]"), "r.json", nullptr);
    ADD_FAILURE() << "no error";
  } catch (const RouteConfigError& error) {
    EXPECT_STREQ(error.what(), "r.json: pieces[0].length_m: must be in [1e-06, 100000], got 0");
  }
}

}  // namespace
}  // namespace rowloc::sim
