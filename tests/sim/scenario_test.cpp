#include "rowloc/sim/scenario.hpp"
#include "rowloc/sim/sensor_config.hpp"

#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <numbers>
#include <set>
#include <string>

namespace rowloc::sim {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using json = nlohmann::json;

std::filesystem::path ScenarioDir() { return test::SourceDir() / "config" / "scenarios"; }

json ShippedJson(const std::string& name) {
  std::ifstream in(ScenarioDir() / (name + ".json"));
  return json::parse(in);
}

/// Parses a shipped scenario after a change to its JSON, as if it lived in config/scenarios.
Scenario ParseModified(const std::string& name, const std::function<void(json&)>& change) {
  json document = ShippedJson(name);
  change(document);
  return ParseScenario(document.dump(), "test.json", ScenarioDir());
}

/// The message of the ScenarioError thrown by ParseModified (fails the test if none is thrown).
std::string ErrorOf(const std::string& name, const std::function<void(json&)>& change) {
  try {
    ParseModified(name, change);
  } catch (const ScenarioError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no ScenarioError";
  return {};
}

TEST(ScenarioTest, EveryShippedScenarioLoads) {
  std::set<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(ScenarioDir())) {
    if (entry.path().extension() != ".json") continue;
    SCOPED_TRACE(entry.path().string());
    const Scenario scenario = LoadScenario(entry.path());
    EXPECT_EQ(scenario.name, entry.path().stem().string());
    EXPECT_FALSE(scenario.description.empty());
    EXPECT_FALSE(RouteSpecProblem(scenario.route).has_value());
    if (scenario.ultrasonic) {
      ASSERT_TRUE(scenario.world.has_value());
      for (const SensorMount& mount : scenario.ultrasonic->mounts) {
        // Inside the canopy band of the world, so that the rangers see the rows.
        EXPECT_GT(mount.position_m.z(), scenario.world->canopy.bottom_m + scenario.world->canopy.height_variation_m);
        EXPECT_LT(mount.position_m.z(), scenario.world->canopy.top_m - scenario.world->canopy.height_variation_m);
      }
    }
    names.insert(scenario.name);
  }
  for (const char* expected : {"vineyard-002-1us", "vineyard-002-2us", "vineyard-002-4us", "vineyard-002-8us",
                               "vineyard-002-rough-4us", "agrimaro-tiles", "agrimaro-grass", "agrimaro-gravel",
                               "slip-odometry-loops", "slip-odometry-turns", "tracked-straight", "tracked-circle",
                               "vineyard-002-north-4us", "vineyard-002-4us-miss30", "vineyard-002-4us-gnss-loss",
                               "vineyard-curved-4us", "tracked-circle-gnss-loss", "tracked-turns-gnss-loss",
                               "agrimaro-tiles-white-encoder", "agrimaro-grass-white-encoder",
                               "agrimaro-gravel-white-encoder", "slip-odometry-loops-white-encoder",
                               "slip-odometry-turns-white-encoder"}) {
    EXPECT_TRUE(names.contains(expected)) << expected;
  }
}

TEST(ScenarioTest, VineyardScenariosDifferOnlyInTheirRangers) {
  const std::map<std::string, std::size_t> expected{
      {"vineyard-002-1us", 1}, {"vineyard-002-2us", 2}, {"vineyard-002-4us", 4}, {"vineyard-002-8us", 8}};
  for (const auto& [name, count] : expected) {
    const Scenario scenario = LoadScenario(ScenarioDir() / (name + ".json"));
    ASSERT_TRUE(scenario.ultrasonic.has_value());
    EXPECT_EQ(scenario.ultrasonic->mounts.size(), count) << name;
    EXPECT_DOUBLE_EQ(scenario.ultrasonic->params.range_sigma_m, 0.003);
    EXPECT_NEAR(scenario.ultrasonic->params.half_aperture_rad, 7.5 * std::numbers::pi / 180.0, 1e-15);
    ASSERT_TRUE(scenario.gnss.has_value());
    EXPECT_DOUBLE_EQ(scenario.gnss->config.sigma_horizontal_m, 0.6);
    EXPECT_DOUBLE_EQ(scenario.world->row_spacing_m, 2.5);
  }
}

TEST(ScenarioTest, RobustnessVariantsChangeOneThingOfTheFourSensorRun) {
  const Scenario base = LoadScenario(ScenarioDir() / "vineyard-002-4us.json");
  const Scenario miss = LoadScenario(ScenarioDir() / "vineyard-002-4us-miss30.json");
  EXPECT_DOUBLE_EQ(miss.ultrasonic->params.miss_probability, 0.3);
  EXPECT_EQ(miss.ultrasonic->mounts, base.ultrasonic->mounts);
  const Scenario loss = LoadScenario(ScenarioDir() / "vineyard-002-4us-gnss-loss.json");
  ASSERT_TRUE(loss.gnss->off_after_s.has_value());
  EXPECT_DOUBLE_EQ(*loss.gnss->off_after_s, 540.0);
  const Scenario north = LoadScenario(ScenarioDir() / "vineyard-002-north-4us.json");
  EXPECT_NEAR(north.world->heading_rad, std::numbers::pi / 2, 1e-15);  // rows along y
  EXPECT_EQ(LoadScenario(ScenarioDir() / "vineyard-002-8us.json").vehicle.ultrasonic.size(), 8u);
}

// The whiteness controls (docs/notes/2026-12-02-localization-filter.md §5.11) are their base runs with the control
// encoder: nothing else may differ, or the comparison of the wheel innovations would not isolate it.
TEST(ScenarioTest, WhiteEncoderVariantsChangeOnlyTheEncoder) {
  for (const std::string base :
       {"agrimaro-tiles", "agrimaro-grass", "agrimaro-gravel", "slip-odometry-loops", "slip-odometry-turns"}) {
    SCOPED_TRACE(base);
    json variant = json::parse(ExpandedScenarioJson(ScenarioDir() / (base + "-white-encoder.json")));
    EXPECT_EQ(ShippedJson(base + "-white-encoder")["extends"], base + ".json");  // an overlay of its base
    EXPECT_EQ(variant["sensors"]["wheel_encoder"]["profile"], "wheel_encoder_white");
    const Scenario loaded = LoadScenario(ScenarioDir() / (base + "-white-encoder.json"));
    EXPECT_EQ(loaded.wheel_encoder, WhiteWheelEncoderConfig());
    ASSERT_EQ(loaded.filter_files.size(), 1u);  // the filter file with the simulated sensors' noises
    EXPECT_EQ(loaded.filter_files[0].filename(), "white-encoder.json");
    json expected = ShippedJson(base);
    for (json* document : {&variant, &expected}) {
      document->erase("name");
      document->erase("description");
      document->erase("filters");
      (*document)["sensors"].erase("wheel_encoder");
    }
    EXPECT_EQ(variant, expected);
  }
}

TEST(ScenarioTest, FiltersAreOptionalAndNameExistingFiles) {
  EXPECT_TRUE(LoadScenario(ScenarioDir() / "agrimaro-tiles.json").filter_files.empty());
  const Scenario named = ParseModified("agrimaro-tiles", [](json& s) {
    s["filters"] = json::array({"../filters/differential.json", "../filters/wheel-angles.json"});
  });
  ASSERT_EQ(named.filter_files.size(), 2u);
  EXPECT_EQ(named.filter_files[0], ScenarioDir() / "../filters/differential.json");
  EXPECT_TRUE(std::filesystem::is_regular_file(named.filter_files[1]));
  EXPECT_THAT(ErrorOf("agrimaro-tiles", [](json& s) { s["filters"] = "../filters/default.json"; }),
              HasSubstr("test.json: filters: must be an array"));
  EXPECT_THAT(ErrorOf("agrimaro-tiles", [](json& s) { s["filters"] = json::array({"../filters/absent.json"}); }),
              AllOf(HasSubstr("test.json: filters[0]: no such file: "), HasSubstr("absent.json")));
  EXPECT_THAT(ErrorOf("agrimaro-tiles", [](json& s) { s["filters"] = json::array({"../filters", 3}); }),
              HasSubstr("test.json: filters[0]: no such file: "));  // a directory is not a file
  EXPECT_THAT(ErrorOf("agrimaro-tiles", [](json& s) { s["filters"] = json::array({"../filters/default.json", 3}); }),
              HasSubstr("test.json: filters[1]: must name a filter file, got 3"));
  EXPECT_THAT(ErrorOf("agrimaro-tiles", [](json& s) { s["filters"] = json::array({""}); }),
              HasSubstr("test.json: filters[0]: must name a filter file, got \"\""));
}

TEST(ScenarioTest, MountsReferToTheVehicleOrAreGiven) {
  const Scenario all = ParseModified("vineyard-002-4us", [](json& s) { s["sensors"]["ultrasonic"]["mounts"] = nullptr; });
  EXPECT_EQ(all.ultrasonic->mounts, all.vehicle.ultrasonic);
  const Scenario named = ParseModified("vineyard-002-4us", [](json& s) {
    s["sensors"]["ultrasonic"]["mounts"] = json::array({"us_rear_right", json::parse(
        R"({"name": "extra", "position_m": [0.1, 0.2, 1.1], "yaw_deg": 180})")});
  });
  ASSERT_EQ(named.ultrasonic->mounts.size(), 2u);
  EXPECT_EQ(named.ultrasonic->mounts[0], named.vehicle.ultrasonic[3]);
  EXPECT_EQ(named.ultrasonic->mounts[1].name, "extra");
  EXPECT_NEAR(named.ultrasonic->mounts[1].yaw_rad, std::numbers::pi, 1e-15);
}

TEST(ScenarioTest, OpenFieldTakesItsOrigin) {
  const Scenario scenario = LoadScenario(ScenarioDir() / "agrimaro-tiles.json");
  EXPECT_FALSE(scenario.world.has_value());
  EXPECT_DOUBLE_EQ(scenario.origin.latitude_deg, 45.0628);
  EXPECT_EQ(scenario.terrain_map.default_terrain(), TerrainClass::kTiles);
  EXPECT_TRUE(scenario.torque.has_value());
  EXPECT_FALSE(scenario.gnss->off_after_s.has_value());
  const Scenario turns = LoadScenario(ScenarioDir() / "slip-odometry-turns.json");
  ASSERT_TRUE(turns.gnss->off_after_s.has_value());
  EXPECT_DOUBLE_EQ(*turns.gnss->off_after_s, 50.0);
}

TEST(ScenarioTest, ErrorsNameFileKeyAndReason) {
  const std::string v = "vineyard-002-4us";
  EXPECT_THAT(ErrorOf(v, [](json& s) { s.erase("seed"); }), AllOf(HasSubstr("test.json: seed"), HasSubstr("missing key")));
  EXPECT_THAT(ErrorOf(v, [](json& s) { s["sede"] = 1; }), AllOf(HasSubstr("test.json: sede"), HasSubstr("unknown key")));
  EXPECT_THAT(ErrorOf(v, [](json& s) { s["seed"] = -1; }), HasSubstr("seed: must be a non-negative integer"));
  EXPECT_THAT(ErrorOf(v, [](json& s) { s["vehicle"] = "missing-vehicle.json"; }),
              AllOf(HasSubstr("test.json: vehicle: "), HasSubstr("missing-vehicle.json")));
  EXPECT_THAT(ErrorOf(v, [](json& s) { s["world"] = nullptr; }), HasSubstr("origin: required for an open field"));
  EXPECT_THAT(ErrorOf(v, [](json& s) { s["origin"] = json::parse(R"({"latitude_deg": 1, "longitude_deg": 2, "altitude_m": 3})"); }),
              HasSubstr("origin: must be null with a world"));
  EXPECT_THAT(ErrorOf(v, [](json& s) { s["route"]["speed_mps"] = "fast"; }), HasSubstr("test.json: route.speed_mps"));
  EXPECT_THAT(ErrorOf(v, [](json& s) { s["terrain_map"]["default"] = "ice"; }), HasSubstr("test.json: terrain_map.default"));
  EXPECT_THAT(ErrorOf(v, [](json& s) { s["sensors"]["gnss"]["profile"] = "gnss_unknown"; }),
              AllOf(HasSubstr("sensors.gnss.profile"), HasSubstr("gnss_rtk")));
  EXPECT_THAT(ErrorOf(v, [](json& s) { s["sensors"]["ultrasonic"]["mounts"] = json::array({"us_nose"}); }),
              HasSubstr("sensors.ultrasonic.mounts[0]: the vehicle has no ultrasonic sensor \"us_nose\""));
  EXPECT_THAT(ErrorOf(v, [](json& s) { s["sensors"]["ultrasonic"]["mounts"] = json::array({"us_front_left", "us_front_left"}); }),
              HasSubstr("mounts[1]: duplicate sensor name"));
  EXPECT_THAT(ErrorOf(v, [](json& s) { s["sensors"]["ultrasonic"]["range_sigma_m"] = -0.1; }),
              HasSubstr("sensors.ultrasonic"));
  EXPECT_THAT(ErrorOf(v, [](json& s) { s["sensors"]["ultrasonic"]["rate_hz"] = 0; }), HasSubstr("sensors.ultrasonic.rate_hz"));
  EXPECT_THAT(ErrorOf(v, [](json& s) { s["truth_rate_hz"] = std::nan(""); }), HasSubstr("truth_rate_hz"));
  EXPECT_THAT(ErrorOf("agrimaro-tiles", [](json& s) { s["sensors"]["ultrasonic"] = ShippedJson("vineyard-002-4us")["sensors"]["ultrasonic"]; }),
              HasSubstr("sensors.ultrasonic: needs a world"));
  EXPECT_THAT(ErrorOf("tracked-straight", [](json& s) { s["sensors"]["steering_encoder"] = json::parse(R"({"profile": "steering_encoder_12bit"})"); }),
              HasSubstr("sensors.steering_encoder: the vehicle has no steerable wheel"));
}

TEST(ScenarioTest, MalformedOrMissingFileIsAnError) {
  EXPECT_THAT([] { ParseScenario("{\"name\": ", "bad.json", ScenarioDir()); },
              ::testing::ThrowsMessage<ScenarioError>(HasSubstr("bad.json: invalid JSON")));
  EXPECT_THAT([] { LoadScenario(ScenarioDir() / "no-such-scenario.json"); },
              ::testing::ThrowsMessage<ScenarioError>(HasSubstr("no-such-scenario.json: cannot open scenario file")));
}

}  // namespace
}  // namespace rowloc::sim

namespace rowloc::sim {
namespace {

// Issue 26: the simulator makes each fault the filter must survive (sensor_faults.hpp).
TEST(ScenarioTest, FaultScenariosParseTheirFaults) {
  EXPECT_TRUE(LoadScenario(ScenarioDir() / "agrimaro-tiles.json").faults.empty());
  const Scenario outlier = LoadScenario(ScenarioDir() / "fault-gnss-outlier-before-init.json");
  ASSERT_EQ(outlier.faults.gnss_outliers.size(), 1u);
  EXPECT_EQ(outlier.faults.gnss_outliers[0].offset_m, Eigen::Vector2d(111.0, 0.0));
  EXPECT_EQ(LoadScenario(ScenarioDir() / "fault-dead-imu.json").faults.imu_dead_after_s, 20.0);
  const Scenario jump = LoadScenario(ScenarioDir() / "fault-clock-offset-1e18.json");
  ASSERT_TRUE(jump.faults.clock_jump.has_value());
  EXPECT_EQ(jump.faults.Stamp(7.0), 7.0);
  EXPECT_EQ(jump.faults.Stamp(9.0), 9.0 + 1e18);
  const Scenario wheel = LoadScenario(ScenarioDir() / "fault-dead-wheel-encoder.json");
  ASSERT_EQ(wheel.faults.wheel_encoders_dead.size(), 1u);
  EXPECT_EQ(wheel.faults.wheel_encoders_dead[0].wheel, "right");
}

TEST(ScenarioTest, BadFaultsAreNamed) {
  EXPECT_THAT(ErrorOf("agrimaro-tiles", [](json& d) { d["faults"] = {{"wheel_encoders_dead", {{{"wheel", "x"}, {"after_s", 1.0}}}}}; }),
              HasSubstr("test.json: faults.wheel_encoders_dead[0].wheel: 'x' is not a wheel of the vehicle"));
  EXPECT_THAT(ErrorOf("agrimaro-tiles", [](json& d) { d["faults"] = {{"imu_dead", 1.0}}; }),
              HasSubstr("faults.imu_dead"));
  EXPECT_THAT(ErrorOf("agrimaro-tiles", [](json& d) { d["faults"] = {{"clock_jump", {{"after_s", 1.0}, {"jump_s", -5.0}}}}; }),
              HasSubstr("faults.clock_jump.jump_s"));
  EXPECT_THAT(ErrorOf("agrimaro-tiles",
                      [](json& d) { d["faults"] = {{"gnss_outliers", {{{"t_s", 1.0}, {"offset_m", {1e300, 0.0}}}}}}; }),
              HasSubstr("faults.gnss_outliers[0].offset_m"));
  EXPECT_THAT(ErrorOf("agrimaro-tiles", [](json& d) { d["faults"] = 3; }), HasSubstr("faults"));
}

TEST(ScenarioTest, GnssOutagesAreIntervalsInTimeOrder) {
  SensorFaults faults = ParseSensorFaults(
      R"({"gnss_outages": [{"start_s": 10, "end_s": 20}, {"start_s": 20, "end_s": 25.5}, {"start_s": 60, "end_s": 120}]})",
      "f.json", "faults", {});
  ASSERT_EQ(faults.gnss_outages.size(), 3u);
  EXPECT_FALSE(faults.empty());
  for (const double t : {0.0, 9.999, 25.5, 59.9, 120.0, 1e6}) EXPECT_FALSE(faults.GnssOut(t)) << t;
  for (const double t : {10.0, 15.0, 20.0, 25.49, 60.0, 119.9}) EXPECT_TRUE(faults.GnssOut(t)) << t;
  const auto error = [](const char* text) {
    try {
      ParseSensorFaults(text, "f.json", "faults", {});
    } catch (const ScenarioError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_THAT(error(R"({"gnss_outages": [{"start_s": 10, "end_s": 10}]})"),
              HasSubstr("faults.gnss_outages[0].end_s: must be after start_s"));
  EXPECT_THAT(error(R"({"gnss_outages": [{"start_s": 10, "end_s": 30}, {"start_s": 20, "end_s": 40}]})"),
              HasSubstr("outage 1 starts before outage 0 ends"));
  EXPECT_THAT(error(R"({"gnss_outages": [{"start_s": -1, "end_s": 3}]})"), HasSubstr("faults.gnss_outages[0].start_s"));
  EXPECT_THAT(error(R"({"gnss_outages": [{"start_s": 1}]})"), HasSubstr("faults.gnss_outages[0].end_s"));
  EXPECT_THAT(error(R"({"gnss_outages": [{"start_s": 1, "end_s": 2, "x": 0}]})"), HasSubstr("faults.gnss_outages[0].x"));
  EXPECT_THAT(error(R"({"gnss_outages": []})"), HasSubstr("faults.gnss_outages"));
}

}  // namespace
}  // namespace rowloc::sim
