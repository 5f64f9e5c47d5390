// The association checks of the map-aided update (map_aided_ranging.hpp, checks 1-3; check 4 has
// map_aided_along_check_test.cpp): the lane clearance of every segment and the inside-an-outline
// test of RowMapRanging, then each check in VehicleEkf on both sides of its threshold, and the
// twelve-seed failures they were made for (vineyard-002-4us seed 3: a heading locked 0.2-0.4 rad
// off; vineyard-002-north-4us seed 5: the far side of a canopy taken for the near one; issue 28's
// gappy and leafy rows), replayed from the simulator.
#include "rowloc/formats/sensor_log_reader.hpp"
#include "rowloc/formats/trajectory_streams.hpp"
#include "rowloc/localization/map_aided_ranging.hpp"
#include "rowloc/localization/vehicle_ekf.hpp"
#include "rowloc/mapio/vehicle_config.hpp"
#include "rowloc/sim/row_world.hpp"
#include "rowloc/sim/scenario.hpp"
#include "rowloc/sim/simulation.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace rowloc::localization {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
const geometry::GeoOrigin kOrigin{45.0, 7.0, 200.0};
const std::vector<std::string> kWheels{"front_left", "front_right", "rear_left", "rear_right"};

/// A canopy outline along x in [0, 50], centred on y = centre, 0.5 m wide (counter-clockwise, or
/// clockwise when `reversed`).
geometry::Row Canopy(const std::string& id, double centre, bool reversed = false) {
  geometry::Row row{id, {{0.0, centre - 0.25}, {50.0, centre - 0.25}, {50.0, centre + 0.25}, {0.0, centre + 0.25}}, true};
  if (reversed) std::reverse(row.points_m.begin(), row.points_m.end());
  return row;
}

/// Three canopies 2.5 m apart (centres y = -1.25, 1.25, 3.75): two lanes of 2.0 m free width.
geometry::RowMap ThreeCanopies(bool reversed = false) {
  geometry::RowMap map;
  map.origin = kOrigin;
  for (int i = 0; i < 3; ++i) map.rows.push_back(Canopy("row-" + std::to_string(i), -1.25 + 2.5 * i, reversed));
  return map;
}

TEST(RowMapRangingClearance, IsTheFreeWidthToTheNextRowAndInfiniteOutside) {
  for (const bool reversed : {false, true}) {
    const RowMapRanging ranging(ThreeCanopies(reversed), kOrigin, 2.0);
    const RangeSensorMount left{Eigen::Vector2d(0.0, 0.5), std::numbers::pi / 2, 0.13};
    const RangeSensorMount right{Eigen::Vector2d(0.0, -0.5), -std::numbers::pi / 2, 0.13};
    // In the lane between the first two rows (y = 0): both sides see a 2.0 m free lane.
    for (const RangeSensorMount& mount : {left, right}) {
      const auto candidates = ranging.Candidates(Eigen::Vector3d(20.0, 0.0, 0.0), mount, 4.0, 0.0);
      ASSERT_EQ(candidates.size(), 1u) << reversed;
      EXPECT_NEAR(candidates[0].lane_clearance_m, 2.0, 1e-9) << reversed;
    }
    // Outside the field (y = -3): the first row's outer side has no row beyond it.
    const auto outside = ranging.Candidates(Eigen::Vector3d(20.0, -3.0, 0.0), left, 4.0, 0.0);
    ASSERT_EQ(outside.size(), 1u);
    EXPECT_EQ(outside[0].lane_clearance_m, kInf);
    // A farther row beyond the search: infinite too.
    geometry::RowMap far = ThreeCanopies(reversed);
    far.rows[1] = Canopy("far", 60.0, reversed);
    far.rows.pop_back();
    const RowMapRanging sparse(far, kOrigin, 2.0);
    const auto lone = sparse.Candidates(Eigen::Vector3d(20.0, 0.0, 0.0), right, 4.0, 0.0);
    ASSERT_EQ(lone.size(), 1u);
    EXPECT_EQ(lone[0].lane_clearance_m, kInf);
  }
}

TEST(RowMapRangingClearance, OpenRowsMeasureBothSidesAndSkipTheirOwnFolds) {
  geometry::RowMap map;
  map.origin = kOrigin;
  map.rows.push_back({"a", {{0.0, 0.0}, {50.0, 0.0}}, false});
  map.rows.push_back({"b", {{0.0, 3.0}, {50.0, 3.0}}, false});
  // A row that folds back under itself: its own second leg at y = -0.5 is not another row.
  map.rows.push_back({"c", {{0.0, -1.0}, {50.0, -1.0}, {50.0, -0.5}, {0.0, -0.5}}, false});
  const RowMapRanging ranging(map, kOrigin, 2.0);
  const RangeSensorMount up{Eigen::Vector2d::Zero(), std::numbers::pi / 2, 0.13};
  const RangeSensorMount down{Eigen::Vector2d::Zero(), -std::numbers::pi / 2, 0.13};
  const auto above_a = ranging.Candidates(Eigen::Vector3d(20.0, 1.0, 0.0), down, 4.0, 0.0);
  ASSERT_EQ(above_a.size(), 1u);
  EXPECT_NEAR(above_a[0].lane_clearance_m, 3.0, 1e-9);  // from a up to b
  const auto below_b = ranging.Candidates(Eigen::Vector3d(20.0, 2.0, 0.0), up, 4.0, 0.0);
  ASSERT_EQ(below_b.size(), 1u);
  EXPECT_NEAR(below_b[0].lane_clearance_m, 3.0, 1e-9);
  // Below a: the fold of c at y = -0.5 is the nearest other row (0.5 m).
  const auto below_a = ranging.Candidates(Eigen::Vector3d(20.0, -0.25, 0.0), up, 4.0, 0.0);
  ASSERT_EQ(below_a.size(), 1u);
  EXPECT_NEAR(below_a[0].lane_clearance_m, 0.5, 1e-9);
  // Between c's legs, looking down at its lower leg (y = -1): up through its own upper leg
  // (skipped) to a at y = 0.
  const auto inside_c = ranging.Candidates(Eigen::Vector3d(20.0, -0.75, 0.0), down, 4.0, 0.0);
  ASSERT_EQ(inside_c.size(), 1u);
  EXPECT_NEAR(inside_c[0].lane_clearance_m, 1.0, 1e-9);
  // Below c's lower leg: nothing below c.
  const auto below_c = ranging.Candidates(Eigen::Vector3d(20.0, -2.0, 0.0), up, 4.0, 0.0);
  ASSERT_EQ(below_c.size(), 1u);
  EXPECT_EQ(below_c[0].lane_clearance_m, kInf);
}

TEST(RowMapRangingInside, ASensorInsideACanopyHasNoCandidates) {
  for (const bool reversed : {false, true}) {
    const RowMapRanging ranging(ThreeCanopies(reversed), kOrigin, 2.0);
    const RangeSensorMount left{Eigen::Vector2d(0.0, 0.5), std::numbers::pi / 2, 0.13};
    RowMapRanging::Buffers buffers;
    // Vehicle at y = 0.6: the left sensor at y = 1.1 is inside the canopy [1.0, 1.5].
    EXPECT_TRUE(ranging.Candidates(Eigen::Vector3d(20.0, 0.6, 0.0), left, 4.0, 10.0, buffers).empty());
    EXPECT_TRUE(buffers.sensor_inside_outline) << reversed;
    // At y = 0.4 (the sensor 0.1 m short of the canopy): one candidate, the near side.
    const auto& outside = ranging.Candidates(Eigen::Vector3d(20.0, 0.4, 0.0), left, 4.0, 0.0, buffers);
    EXPECT_FALSE(buffers.sensor_inside_outline);
    ASSERT_EQ(outside.size(), 1u);
    EXPECT_NEAR(outside[0].predicted_range_m, 0.1, 1e-9);
  }
}

TEST(RowMapRangingInside, ACornerSeenFromOutsideIsNotInside) {
  // The beam aims at the corner (50, 1.0) of a canopy from outside but on the inner side of the
  // end cap's line (x < 50): a test by that line alone would call the sensor inside.
  const RowMapRanging ranging(ThreeCanopies(), kOrigin, 2.0);
  const double bearing = std::atan2(1.0 - 0.2, 50.0 - 49.8);  // from (49.8, 0.2) to the corner
  const RangeSensorMount towards{Eigen::Vector2d::Zero(), bearing, 0.01};
  RowMapRanging::Buffers buffers;
  const auto& candidates = ranging.Candidates(Eigen::Vector3d(49.8, 0.2, 0.0), towards, 4.0, 0.0, buffers);
  EXPECT_FALSE(buffers.sensor_inside_outline);
  ASSERT_FALSE(candidates.empty());
  // The nearest point in the cone is on the canopy's near side, just short of the corner.
  EXPECT_GT(candidates[0].predicted_range_m, 0.8);
  EXPECT_LE(candidates[0].predicted_range_m, std::hypot(0.2, 0.8));
}

// --- The checks in the filter -----------------------------------------------------------------

/// A 4WS UGV filter at pose (20, y, phi) with the given 1-sigmas, the three canopies attached.
/// The echoes weighted with the configured 3 mm (the adaptation to the canopy is tested apart).
VehicleEkf FilterAt(double y, double phi, double position_sigma_m, double heading_sigma_rad) {
  FilterConfig config;
  config.map_aided.adaptive_range_sigma.enabled = false;
  VehicleEkf ekf(mapio::VineyardUgv4wsConfig(), config, kOrigin, kWheels);
  ekf.AttachRowMap(ThreeCanopies());
  const double p = position_sigma_m * position_sigma_m;
  ekf.SetPose(1.0, Eigen::Vector3d(20.0, y, phi),
              Eigen::Vector3d(p, p, heading_sigma_rad * heading_sigma_rad).asDiagonal());
  return ekf;
}

/// The outcome of one echo of the front-left ranger (0.5 m left of the centre line) at t = 1.01 s.
std::string EchoOutcome(VehicleEkf& ekf, double range_m) {
  const ProcessResult r = ekf.Process(formats::UltrasonicMessage{1.01, "us_front_left", 0, range_m});
  return r.echo ? r.echo->outcome : "no trace";
}

TEST(VehicleEkfAssociation, AnUncertainHeadingDefersTheEchoes) {
  // k sigma_phi against the cone's half aperture (7.5 degrees = 0.1309 rad, k = 3).
  VehicleEkf uncertain = FilterAt(0.0, 0.0, 0.05, 0.045);  // 0.135 rad
  EXPECT_EQ(EchoOutcome(uncertain, 0.5), "heading_uncertain");
  EXPECT_EQ(uncertain.map_aided_stats().heading_uncertain, 1u);
  EXPECT_EQ(uncertain.state()(1), 0.0);
  VehicleEkf known = FilterAt(0.0, 0.0, 0.05, 0.042);  // 0.126 rad
  EXPECT_EQ(EchoOutcome(known, 0.5), "accepted");
  EXPECT_EQ(known.map_aided_stats().heading_uncertain, 0u);
}

TEST(VehicleEkfAssociation, AnEchoFromInsideACanopyIsNoMeasurement) {
  VehicleEkf inside = FilterAt(0.6, 0.0, 0.05, 0.01);  // the ranger at y = 1.1, in the canopy [1.0, 1.5]
  EXPECT_EQ(EchoOutcome(inside, 0.45), "inside_outline");  // the far side would be 0.4 m away
  EXPECT_EQ(inside.map_aided_stats().inside_outline, 1u);
  EXPECT_EQ(inside.state()(1), 0.6);
  VehicleEkf outside = FilterAt(0.4, 0.0, 0.05, 0.01);
  EXPECT_EQ(EchoOutcome(outside, 0.1), "accepted");
}

TEST(VehicleEkfAssociation, AnAmbiguousLaneDefersTheEchoes) {
  // Free lane 2.0 m: an echo is used while k sigma_r <= 1.0 m (sigma_r ~ the across sigma here).
  VehicleEkf ambiguous = FilterAt(0.0, 0.0, 0.36, 0.005);
  EXPECT_EQ(EchoOutcome(ambiguous, 0.5), "lane_ambiguous");
  EXPECT_EQ(ambiguous.map_aided_stats().lane_ambiguous, 1u);
  EXPECT_NEAR(ambiguous.covariance()(1, 1), 0.36 * 0.36, 1e-3);  // only the 10 ms prediction
  VehicleEkf unambiguous = FilterAt(0.0, 0.0, 0.32, 0.005);
  EXPECT_EQ(EchoOutcome(unambiguous, 0.5), "accepted");
  EXPECT_LT(unambiguous.covariance()(1, 1), 1e-4);
}

// --- The twelve-seed failures ------------------------------------------------------------------

struct RunResult {
  double max_position_error_m = 0.0;  ///< from 30 s after initialisation on
  double max_across_error_m = 0.0;    ///< the same across rows that run along x (the y error)
  MapAidedStats stats;
};

/// Simulates `scenario` with `seed` for its first `duration_s` (`lanes` lanes of its route),
/// replays it with the world's row map and `config`, and returns the largest position error.
RunResult SimulateAndReplay(const std::string& scenario, int seed, double duration_s, int lanes = 1,
                            const FilterConfig& config = FilterConfig{}) {
  const auto path = test::SourceDir() / "config/scenarios" / (scenario + ".json");
  std::ifstream in(path);
  nlohmann::json document = nlohmann::json::parse(in);
  document["seed"] = seed;
  document["route"]["lane_count"] = lanes;
  const sim::Scenario parsed = sim::ParseScenario(document.dump(), scenario, path.parent_path());
  const sim::RowWorld world(*parsed.world);
  const geometry::RowMap map = world.TrueRowMap(parsed.row_map_height_m, world.StepForTolerance(1e-3));
  std::stringstream sensors, truth_text;
  sim::RunSimulation(parsed, {&sensors, &truth_text, nullptr, nullptr});
  const formats::TruthStream truth = formats::ParseTruthStream(truth_text, "truth");
  std::map<long, const formats::TruthSample*> by_ms;
  for (const auto& s : truth.samples) by_ms[std::lround(s.t_s * 1000)] = &s;
  formats::SensorLogReader reader(sensors, "sensors");
  VehicleEkf ekf(parsed.vehicle, config, reader.header().origin, reader.header().wheels);
  ekf.AttachRowMap(map);
  RunResult result;
  std::optional<double> initialised_at;
  while (const auto m = reader.Next()) {
    if (formats::TimeOf(*m) > duration_s) break;
    ekf.Process(*m);
    if (ekf.initialised() && !initialised_at) initialised_at = ekf.time_s();
    const auto it = by_ms.find(std::lround(formats::TimeOf(*m) * 1000));
    if (!initialised_at || ekf.time_s() < *initialised_at + 30.0 || it == by_ms.end()) continue;
    const Eigen::Vector2d error = ekf.state().head<2>() - it->second->position_m.head<2>();
    result.max_position_error_m = std::max(result.max_position_error_m, error.norm());
    result.max_across_error_m = std::max(result.max_across_error_m, std::abs(error.y()));
  }
  result.stats = ekf.map_aided_stats();
  return result;
}

TEST(VehicleEkfAssociation, SeedThreeNoLongerLocksOntoAWrongHeading) {
  // Before the checks: 3.7 m off after 40 s, 6 m before the first GNSS re-acquisition.
  const RunResult run = SimulateAndReplay("vineyard-002-4us", 3, 110.0);
  EXPECT_LT(run.max_position_error_m, 0.3);
  EXPECT_GT(run.stats.heading_uncertain, 0u);
}

TEST(VehicleEkfAssociation, NorthSeedFiveNoLongerTakesTheFarSideOfACanopy) {
  // With the heading check alone: held 0.56 m across the row, 2.8 m off at the lane's end.
  const RunResult run = SimulateAndReplay("vineyard-002-north-4us", 5, 110.0);
  EXPECT_LT(run.max_position_error_m, 0.3);
  EXPECT_GT(run.stats.inside_outline, 0u);
}

// Issue 28: a third of the plants missing and 3 cm of leaves. Seed 1 lost its lane at 119 s (across
// 1.9 m; every one of 12 seeds lost it): the first echoes after the GNSS initialisation, weighted
// at 3 mm against 3 cm of leaves, and corner echoes whose along-row slope holds over 6 cm used
// against a 0.1 m along sigma, made the filter certain of an along position 0.5-0.8 m off.
TEST(VehicleEkfAssociation, GappyLeafyRowsKeepTheirLane) {
  // Two lanes (240 s): 1.9 cm across and 0.5 m in all at most today; with the range sigma fixed at
  // 3 mm (adaptive_range_sigma off) the along error reaches 1.6 m.
  const RunResult run = SimulateAndReplay("vineyard-002-gappy-leafy-4us", 1, 240.0, 2);
  EXPECT_LT(run.max_across_error_m, 0.05);
  EXPECT_LT(run.max_position_error_m, 0.75);
  EXPECT_GT(run.stats.along_ambiguous, 0u);
}

}  // namespace
}  // namespace rowloc::localization
