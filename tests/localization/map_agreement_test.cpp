// MapAgreementMonitor (map_agreement.hpp): the no-segment fraction over its window and its
// threshold, bad configurations; through VehicleEkf, a map of the wrong place reported as the
// health of "map" on a simulated vineyard drive, and the right map never.
#include "rowloc/localization/map_agreement.hpp"

#include "rowloc/formats/sensor_log_reader.hpp"
#include "rowloc/localization/vehicle_ekf.hpp"
#include "rowloc/sim/row_world.hpp"
#include "rowloc/sim/scenario.hpp"
#include "rowloc/sim/simulation.hpp"
#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>

namespace rowloc::localization {
namespace {

using ::testing::HasSubstr;

TEST(MapAgreementMonitor, TheMapIsSuspectWhenMostEchoesOfAFullWindowFindNoRow) {
  MapAgreementMonitor monitor(MapAgreementConfig{10, 0.6});
  for (int i = 0; i < 9; ++i) monitor.ObserveEcho(false);
  EXPECT_FALSE(monitor.MapProblem().has_value());  // the window is not full yet
  monitor.ObserveEcho(true);
  ASSERT_TRUE(monitor.MapProblem().has_value());  // 9 of 10
  EXPECT_THAT(*monitor.MapProblem(), HasSubstr("9 of the last 10 echoes found no row of the map"));
  for (int i = 0; i < 4; ++i) monitor.ObserveEcho(true);  // 5 of 10 (the oldest left the window)
  EXPECT_FALSE(monitor.MapProblem().has_value());
  // At the threshold: 6 of 10 is suspect, 5 of 10 not.
  for (const int without : {5, 6}) {
    MapAgreementMonitor fresh(MapAgreementConfig{10, 0.6});
    for (int i = 0; i < 10; ++i) fresh.ObserveEcho(i >= without);
    EXPECT_EQ(fresh.MapProblem().has_value(), without == 6) << without;
  }
}

TEST(MapAgreementMonitor, BadConfigurationsAreRefused) {
  EXPECT_THROW(MapAgreementMonitor(MapAgreementConfig{1, 0.5}), std::invalid_argument);
  EXPECT_THROW(MapAgreementMonitor(MapAgreementConfig{10, 0.0}), std::invalid_argument);
  EXPECT_THROW(MapAgreementMonitor(MapAgreementConfig{10, 1.5}), std::invalid_argument);
  EXPECT_NO_THROW(MapAgreementMonitor(MapAgreementConfig{10, 1.0}));
}

struct MapRun {
  std::optional<double> first_echo_used_s;  ///< the first echo past the heading check
  std::optional<double> map_suspect_s;      ///< the first notice "map suspect"
  std::string notice;
};

/// Simulates vineyard-002-4us (one lane, its first 90 s) and replays it with the world's row map
/// moved by `shift_m` across the rows (0: the right map) and the default filter.
MapRun ReplayWithMapShifted(double shift_m) {
  const auto path = test::SourceDir() / "config/scenarios/vineyard-002-4us.json";
  std::ifstream in(path);
  nlohmann::json document = nlohmann::json::parse(in);
  document["route"]["lane_count"] = 1;
  const sim::Scenario scenario = sim::ParseScenario(document.dump(), "vineyard-002-4us", path.parent_path());
  const sim::RowWorld world(*scenario.world);
  geometry::RowMap map = world.TrueRowMap(scenario.row_map_height_m, world.StepForTolerance(1e-3));
  for (geometry::Row& row : map.rows) {
    for (Eigen::Vector2d& p : row.points_m) p.y() += shift_m;
  }
  std::stringstream sensors, truth;
  sim::RunSimulation(scenario, {&sensors, &truth, nullptr, nullptr});
  formats::SensorLogReader reader(sensors, "sensors");
  VehicleEkf ekf(scenario.vehicle, FilterConfig{}, reader.header().origin, reader.header().wheels);
  ekf.AttachRowMap(map);
  MapRun run;
  while (const auto m = reader.Next()) {
    if (formats::TimeOf(*m) > 90.0) break;
    const std::size_t used_before = ekf.map_aided_stats().echoes - ekf.map_aided_stats().heading_uncertain;
    const ProcessResult result = ekf.Process(*m);
    if (!run.first_echo_used_s && ekf.map_aided_stats().echoes - ekf.map_aided_stats().heading_uncertain > used_before) {
      run.first_echo_used_s = ekf.time_s();
    }
    if (!run.map_suspect_s && result.notice && result.notice->find("map suspect") != std::string::npos) {
      run.map_suspect_s = ekf.time_s();
      run.notice = *result.notice;
    }
  }
  return run;
}

TEST(VehicleEkfMapAgreement, AMapOfTheWrongPlaceIsReportedAndTheRightOneNever) {
  const MapRun right = ReplayWithMapShifted(0.0);
  ASSERT_TRUE(right.first_echo_used_s.has_value());
  EXPECT_FALSE(right.map_suspect_s.has_value()) << right.notice;
  // The field next door (40 m away): no echo finds a row.
  const MapRun next_door = ReplayWithMapShifted(40.0);
  ASSERT_TRUE(next_door.first_echo_used_s.has_value());
  ASSERT_TRUE(next_door.map_suspect_s.has_value());
  EXPECT_LT(*next_door.map_suspect_s - *next_door.first_echo_used_s, 10.0);
  EXPECT_THAT(next_door.notice, HasSubstr("map suspect: "));
  EXPECT_THAT(next_door.notice, HasSubstr("echoes found no row of the map where they point"));
  // Moved by half a row spacing (2.5 m rows): the canopies stand where the lanes are. The echoes
  // that do find a row pull the filter towards the wrong lane, which slows the report (39 s).
  const MapRun half_spacing = ReplayWithMapShifted(1.25);
  ASSERT_TRUE(half_spacing.map_suspect_s.has_value());
  EXPECT_LT(*half_spacing.map_suspect_s - *half_spacing.first_echo_used_s, 60.0);
}

}  // namespace
}  // namespace rowloc::localization
