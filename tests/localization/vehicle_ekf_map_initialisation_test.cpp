// The map-aided initialisation (vehicle_ekf_initialisation.cpp; initialisation.map_heading_sigma_rad):
// a vehicle switched on inside a lane of the Donati 2021 vineyard (vineyard-002-4us's world, vehicle
// and sensors, a straight 36 m drive along the second lane) initialises on the lane's direction
// after a few metres and is at millimetres across the row seconds later; without it, the filter
// waits for the long GNSS baseline and then for the heading. Outside a lane it changes nothing.
#include "rowloc/formats/sensor_log_reader.hpp"
#include "rowloc/formats/trajectory_streams.hpp"
#include "rowloc/localization/vehicle_ekf.hpp"
#include "one_lane_drive.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <map>
#include <optional>
#include <sstream>

namespace rowloc::localization {
namespace {

using ::testing::HasSubstr;

using InLaneRun = test::OneLaneDrive;

/// Switched on inside the second lane, 8 m into the rows, 2 s standing, then 36 m along the lane.
const InLaneRun& SwitchedOnInALane() {
  static const InLaneRun run = test::SimulateVineyard0024us([](nlohmann::json& document) {
    document["route"] = {{"type", "straight"}, {"start", {8.0, 3.75}}, {"heading_rad", 0.0}, {"length_m", 36.0},
                         {"speed_mps", 0.5}, {"accel_mps2", 0.5}, {"max_lateral_accel_mps2", 0.5},
                         {"start_dwell_s", 2.0}, {"end_dwell_s", 2.0}};
  });
  return run;
}

struct ColdStart {
  std::optional<double> initialised_s;
  std::string notice;
  std::optional<double> below_2cm_s;  ///< from then on the across-row error stays below 2 cm
  double final_across_m = 0.0;
};

ColdStart Replay(const InLaneRun& run, double map_heading_sigma_rad) {
  std::istringstream log(run.sensors);
  formats::SensorLogReader reader(log, "sensors");
  FilterConfig config;
  config.initialisation.map_heading_sigma_rad = map_heading_sigma_rad;
  VehicleEkf ekf(run.scenario.vehicle, config, reader.header().origin, reader.header().wheels);
  ekf.AttachRowMap(run.map);
  std::map<long, const formats::TruthSample*> by_ms;
  for (const auto& s : run.truth.samples) by_ms[std::lround(s.t_s * 1000)] = &s;
  ColdStart c;
  while (const auto m = reader.Next()) {
    const ProcessResult result = ekf.Process(*m);
    if (result.notice && result.notice->find("initialised at") != std::string::npos && !c.initialised_s) {
      c.initialised_s = ekf.time_s();
      c.notice = *result.notice;
    }
    const auto it = by_ms.find(std::lround(formats::TimeOf(*m) * 1000));
    if (!ekf.initialised() || it == by_ms.end()) continue;
    const double across = std::abs(ekf.state()(1) - it->second->position_m.y());  // the lane runs along +x
    if (across >= 0.02) c.below_2cm_s.reset();
    else if (!c.below_2cm_s) c.below_2cm_s = ekf.time_s();
    c.final_across_m = across;
  }
  return c;
}

TEST(VehicleEkfMapInitialisation, InALaneTheHeadingIsTheLanesAndTheEchoesStartAtOnce) {
  const ColdStart c = Replay(SwitchedOnInALane(), 0.03);
  ASSERT_TRUE(c.initialised_s.has_value());
  EXPECT_THAT(c.notice, HasSubstr("from the lane of the row map, its direction from"));
  EXPECT_LT(*c.initialised_s, 11.0);  // 2 s standing, then about 4 m at 0.5 m/s
  ASSERT_TRUE(c.below_2cm_s.has_value());
  EXPECT_LT(*c.below_2cm_s, 13.0);
  EXPECT_LT(c.final_across_m, 0.005);
}

TEST(VehicleEkfMapInitialisation, OffItWaitsForTheLongBaselineAndTheHeading) {
  const ColdStart c = Replay(SwitchedOnInALane(), 0.0);
  ASSERT_TRUE(c.initialised_s.has_value());
  EXPECT_THAT(c.notice, HasSubstr("from a GNSS baseline of"));
  ASSERT_TRUE(c.below_2cm_s.has_value());
  EXPECT_GT(*c.below_2cm_s, 20.0);  // the heading check holds the echoes about 13 s after the baseline
  EXPECT_LT(c.final_across_m, 0.005);
}

}  // namespace
}  // namespace rowloc::localization
