#include "rowloc/sim/simulation.hpp"

#include "rowloc/sim/route_builders.hpp"
#include "rowloc/sim/vehicle_model.hpp"
#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <numeric>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace rowloc::sim {
namespace {

using json = nlohmann::json;

Scenario Shipped(const std::string& name) {
  return LoadScenario(test::SourceDir() / "config" / "scenarios" / (name + ".json"));
}

/// The vineyard scenario shortened to one lane (about 115 s).
Scenario ShortVineyard() {
  Scenario scenario = Shipped("vineyard-002-4us");
  const RowWorld world(*scenario.world);
  scenario.route = RowsRoute(world, 1, 1, 3.0, 0.5, 0.5, 0.5);
  return scenario;
}

struct Streams {
  std::ostringstream sensors, truth, gnss, odometry;
  SimulationSummary summary;
};

std::unique_ptr<Streams> Simulate(const Scenario& scenario, SimulationOptions options = {}) {
  auto s = std::make_unique<Streams>();
  s->summary = RunSimulation(scenario, {&s->sensors, &s->truth, &s->gnss, &s->odometry}, options);
  return s;
}

std::vector<json> Lines(const std::string& text, const std::string& type = "") {
  std::vector<json> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    json j = json::parse(line);
    if (type.empty() || j["type"] == type) lines.push_back(std::move(j));
  }
  return lines;
}

std::string LinesOf(const std::string& text, const std::string& type) {
  std::string out;
  for (const json& j : Lines(text, type)) out += j.dump() + "\n";
  return out;
}

TEST(SimulationTest, SameSeedSameBytesOtherSeedOtherNoise) {
  const Scenario scenario = Shipped("agrimaro-grass");
  const auto a = Simulate(scenario);
  const auto b = Simulate(scenario);
  EXPECT_EQ(a->sensors.str(), b->sensors.str());
  EXPECT_EQ(a->truth.str(), b->truth.str());
  EXPECT_EQ(a->gnss.str(), b->gnss.str());
  EXPECT_EQ(a->odometry.str(), b->odometry.str());
  const auto c = Simulate(scenario, {.seed = 12345, .progress = {}});
  EXPECT_NE(a->sensors.str(), c->sensors.str());
  // The motion does not depend on the noise seed (the noise-dependent truth does: IMU biases, GNSS faults).
  const std::vector<json> truth_a = Lines(a->truth.str(), "truth");
  const std::vector<json> truth_c = Lines(c->truth.str(), "truth");
  ASSERT_EQ(truth_a.size(), truth_c.size());
  for (std::size_t i = 0; i < truth_a.size(); ++i) {
    for (const char* key : {"x_m", "y_m", "phi_rad", "velocity_x_mps", "yaw_rate_radps", "wheels"}) {
      ASSERT_EQ(truth_a[i][key], truth_c[i][key]) << key << " at line " << i;
    }
  }
  EXPECT_NE(truth_a.back()["imu_bias"], truth_c.back()["imu_bias"]);
}

TEST(SimulationTest, StreamsAreIndependentOfOtherSensors) {
  Scenario with = ShortVineyard();
  Scenario without = with;
  without.ultrasonic.reset();
  const auto a = Simulate(with);
  const auto b = Simulate(without);
  for (const char* type : {"gps", "imu", "wheels", "steering"}) {
    EXPECT_EQ(LinesOf(a->sensors.str(), type), LinesOf(b->sensors.str(), type)) << type;
  }
  EXPECT_TRUE(LinesOf(b->sensors.str(), "ultrasonic").empty());
}

TEST(SimulationTest, EveryClockTicksAtItsRateInTimeOrder) {
  const Scenario scenario = ShortVineyard();
  const auto s = Simulate(scenario);
  const double duration = s->summary.duration_s;
  const auto count = [&](double rate, double phase) { return static_cast<std::size_t>(std::floor((duration - phase) * rate)) + 1; };
  EXPECT_EQ(Lines(s->sensors.str(), "gps").size(), count(scenario.gnss->config.rate_hz, 0.0));
  EXPECT_EQ(Lines(s->sensors.str(), "imu").size(), count(scenario.imu.rate_hz, 0.0));
  EXPECT_EQ(Lines(s->sensors.str(), "wheels").size(), count(scenario.wheel_encoder.rate_hz, 0.0));
  EXPECT_EQ(Lines(s->truth.str(), "truth").size(), count(scenario.truth_rate_hz, 0.0));
  const std::vector<json> pings = Lines(s->sensors.str(), "ultrasonic");
  std::size_t expected_pings = 0;
  for (std::size_t i = 0; i < 4; ++i) expected_pings += count(10.0, static_cast<double>(i) / 40.0);
  EXPECT_EQ(pings.size(), expected_pings);
  const std::vector<json> all = Lines(s->sensors.str());
  ASSERT_EQ(all.front()["type"], "log_header");
  for (std::size_t i = 2; i < all.size(); ++i) ASSERT_LE(all[i - 1]["t"].get<double>(), all[i]["t"].get<double>()) << i;
  EXPECT_EQ(s->summary.sensor_messages, all.size() - 1);
}

TEST(SimulationTest, RangersSeeTheCanopyAcrossTheLane) {
  // Lane centre 1.25 m from both row centres, canopy half-width 0.25 +- 0.03 m, sensors 0.5 m to
  // the side: echoes come from about 0.5 m, within the width variation and 3 mm noise.
  const auto s = Simulate(ShortVineyard());
  const std::vector<json> truth = Lines(s->truth.str(), "truth");
  std::vector<double> ranges;
  for (const json& ping : Lines(s->sensors.str(), "ultrasonic")) {
    const double t = ping["t"];
    // Only while the vehicle drives along the lane at cruise (x between 5 and 45 m of the 50 m rows).
    const json& state = truth[static_cast<std::size_t>(std::lround(t * 50.0))];
    if (state["x_m"].get<double>() < 5.0 || state["x_m"].get<double>() > 45.0) continue;
    ASSERT_FALSE(ping["range_m"].is_null()) << "missed echo at t = " << t << " (no misses configured)";
    ranges.push_back(ping["range_m"]);
  }
  ASSERT_GT(ranges.size(), 1000u);
  for (double r : ranges) EXPECT_NEAR(r, 0.5, 0.045);
  const double mean = std::accumulate(ranges.begin(), ranges.end(), 0.0) / static_cast<double>(ranges.size());
  EXPECT_NEAR(mean, 0.5, 0.01);
}

TEST(SimulationTest, GnssStopsAfterItsOffTime) {
  Scenario scenario = Shipped("slip-odometry-turns");
  const auto s = Simulate(scenario);
  const std::vector<json> gps = Lines(s->sensors.str(), "gps");
  ASSERT_FALSE(gps.empty());
  EXPECT_LE(gps.back()["t"].get<double>(), 50.0);
  EXPECT_GE(gps.back()["t"].get<double>(), 50.0 - 1.0 / scenario.gnss->config.rate_hz);
  for (const json& t : Lines(s->truth.str(), "truth")) {
    if (t["t"].get<double>() > 50.0 + 1.0 / scenario.gnss->config.rate_hz) {
      ASSERT_FALSE(t["gnss_available"].get<bool>());
    }
  }
}

TEST(SimulationTest, EncodersAverageToTheTrueWheelSpeedAndTruthFollowsTheRoute) {
  const Scenario scenario = Shipped("agrimaro-tiles");
  const auto s = Simulate(scenario);
  const Route route(scenario.route);
  const std::vector<json> truth = Lines(s->truth.str(), "truth");
  for (const json& t : truth) {
    const RoutePoint p = route.At(t["t"]);
    ASSERT_NEAR(t["x_m"].get<double>(), p.position_m.x(), 1e-9);
    ASSERT_NEAR(t["y_m"].get<double>(), p.position_m.y(), 1e-9);
  }
  // Cruise at 1 m/s from t = 3 s to 16 s: mean of the encoder readings = mean true wheel rate.
  std::map<std::string, std::pair<double, int>> measured, exact;
  for (const json& w : Lines(s->sensors.str(), "wheels")) {
    if (w["t"].get<double>() < 4.0 || w["t"].get<double>() > 15.0) continue;
    for (const auto& [name, value] : w["speed_radps"].items()) measured[name].first += value.get<double>(), ++measured[name].second;
  }
  for (const json& t : truth) {
    if (t["t"].get<double>() < 4.0 || t["t"].get<double>() > 15.0) continue;
    for (const auto& [name, w] : t["wheels"].items()) exact[name].first += w["speed_radps"].get<double>(), ++exact[name].second;
  }
  ASSERT_EQ(measured.size(), 3u);
  for (const auto& [name, sum] : measured) {
    const double mean_measured = sum.first / sum.second;
    const double mean_exact = exact[name].first / exact[name].second;
    EXPECT_NEAR(mean_measured, mean_exact, 0.01) << name;  // one tick over 11 s is 0.0006 rad/s
    EXPECT_GT(mean_exact, 1.0 / 0.165) << "driving wheels turn faster than v / R on tiles (slip > 0)";
  }
  // The cumulative angles (angle_rad): what each wheel turned between two messages, to a tick plus the
  // truth's sampling (rectangle rule over 50 Hz samples of a constant rate).
  std::map<std::string, double> angle_at_4s, angle_at_15s;
  for (const json& w : Lines(s->sensors.str(), "wheels")) {
    ASSERT_TRUE(w.contains("angle_rad"));
    const double t = w["t"].get<double>();
    for (const auto& [name, value] : w["angle_rad"].items()) {
      if (std::abs(t - 4.0) < 1e-9) angle_at_4s[name] = value.get<double>();
      if (std::abs(t - 15.0) < 1e-9) angle_at_15s[name] = value.get<double>();
    }
  }
  ASSERT_EQ(angle_at_15s.size(), 3u);
  for (const auto& [name, angle] : angle_at_15s) {
    const double turned = exact[name].first / exact[name].second * 11.0;
    EXPECT_NEAR(angle - angle_at_4s.at(name), turned, 2.0 * std::numbers::pi / 1024.0 + 0.05) << name;
  }
}

TEST(SimulationTest, BaselinesAndProgress) {
  std::vector<double> reported;
  const Scenario scenario = Shipped("agrimaro-tiles");
  const auto s = Simulate(scenario, {.seed = std::nullopt, .progress = [&](double t, double) { reported.push_back(t); }});
  ASSERT_GE(reported.size(), 50u);
  EXPECT_TRUE(std::is_sorted(reported.begin(), reported.end()));
  EXPECT_GE(reported.back(), 0.95 * s->summary.duration_s);
  const std::vector<json> fixes = Lines(s->gnss.str(), "estimate");
  EXPECT_EQ(fixes.size(), s->summary.gps_fixes);
  const std::vector<json> odometry = Lines(s->odometry.str(), "estimate");
  EXPECT_EQ(odometry.size(), s->summary.wheels);
  // Dead reckoning without a slip model on tiles (slip about 2 %) stays within 5 % of 15 m.
  EXPECT_GT(s->summary.baseline_odometry_final_error_m, 0.0);
  EXPECT_LT(s->summary.baseline_odometry_final_error_m, 0.05 * 15.0);
}

TEST(SimulationTest, VisualOdometryIsTheCameraVelocityPlusItsNoise) {
  Scenario scenario = Shipped("tracked-circle");  // yaw rate 0.16 rad/s: the lever arm matters
  scenario.vio = VioScenario{20.0, 0.05, Eigen::Vector3d(0.8, 0.3, 1.0)};
  const auto s = Simulate(scenario);
  const Route route(scenario.route);
  std::vector<double> error_x, error_y;
  for (const json& m : Lines(s->sensors.str(), "vio")) {
    const RoutePoint p = route.At(m["t"]);
    const BodyMotion motion{p.speed_mps, 0.0, p.yaw_rate_radps, p.accel_mps2, 0.0, p.yaw_accel_radps2};
    const Eigen::Vector2d v = PointVelocity(motion, Eigen::Vector2d(0.8, 0.3));
    error_x.push_back(m["velocity_x_mps"].get<double>() - v.x());
    error_y.push_back(m["velocity_y_mps"].get<double>() - v.y());
    EXPECT_EQ(m["sigma_mps"].get<double>(), 0.05);
  }
  ASSERT_EQ(error_x.size(), static_cast<std::size_t>(std::floor(s->summary.duration_s * 20.0)) + 1);
  for (const auto* errors : {&error_x, &error_y}) {
    const double n = static_cast<double>(errors->size());
    const double mean = std::accumulate(errors->begin(), errors->end(), 0.0) / n;
    const double sq = std::inner_product(errors->begin(), errors->end(), errors->begin(), 0.0) / n;
    EXPECT_NEAR(mean, 0.0, 4.0 * 0.05 / std::sqrt(n));               // 4-sigma band of the mean
    EXPECT_NEAR(std::sqrt(sq - mean * mean), 0.05, 4.0 * 0.05 / std::sqrt(2.0 * n));  // and of the std
  }
}

TEST(SimulationTest, MissedEchoesAppearAsNullRangesAtTheConfiguredRate) {
  Scenario scenario = ShortVineyard();
  scenario.ultrasonic->params.miss_probability = 0.3;
  const auto s = Simulate(scenario);
  const std::vector<json> truth = Lines(s->truth.str(), "truth");
  std::size_t pings = 0, missed = 0;
  for (const json& ping : Lines(s->sensors.str(), "ultrasonic")) {
    const json& state = truth[static_cast<std::size_t>(std::lround(ping["t"].get<double>() * 50.0))];
    if (state["x_m"].get<double>() < 5.0 || state["x_m"].get<double>() > 45.0) continue;  // canopy on both sides
    ++pings;
    missed += ping["range_m"].is_null() ? 1 : 0;
  }
  ASSERT_GT(pings, 1000u);
  const double rate = static_cast<double>(missed) / static_cast<double>(pings);
  EXPECT_NEAR(rate, 0.3, 4.0 * std::sqrt(0.3 * 0.7 / static_cast<double>(pings)));
}

TEST(SimulationTest, RefusesMissingOutputs) {
  const Scenario scenario = Shipped("agrimaro-tiles");
  std::ostringstream out;
  EXPECT_THROW(RunSimulation(scenario, {&out, nullptr, nullptr, nullptr}), std::invalid_argument);
  EXPECT_THROW(RunSimulation(scenario, {nullptr, &out, nullptr, nullptr}), std::invalid_argument);
}

TEST(SimulationTest, StreamSeedsDiffer) {
  std::set<std::uint64_t> seeds;
  for (std::uint64_t seed : {0ULL, 1ULL, 2ULL}) {
    for (std::uint64_t stream = 0; stream < 400; ++stream) seeds.insert(StreamSeed(seed, stream));
  }
  EXPECT_EQ(seeds.size(), 1200u);
}

}  // namespace
}  // namespace rowloc::sim

namespace rowloc::sim {
namespace {

// Issue 26: each injected fault reaches the log (and never the truth).
TEST(SimulationTest, InjectedFaultsReachTheLog) {
  Scenario scenario = Shipped("agrimaro-tiles");
  scenario.faults.gnss_outliers = {{0.0, Eigen::Vector2d(111.0, 0.0)}};
  scenario.faults.imu_dead_after_s = 8.0;
  scenario.faults.wheel_encoders_dead = {{"right", 6.0}};
  scenario.faults.clock_jump = ClockJumpFault{10.0, 1e4};
  const auto faulty = Simulate(scenario);
  const auto clean = Simulate(Shipped("agrimaro-tiles"));
  const std::vector<json> gps = Lines(faulty->sensors.str(), "gps"), clean_gps = Lines(clean->sensors.str(), "gps");
  ASSERT_FALSE(gps.empty());
  // The first fix moved by 111 m east (about 1.4e-3 degrees of longitude at 45 deg N); the second not.
  EXPECT_NEAR((gps[0]["longitude_deg"].get<double>() - clean_gps[0]["longitude_deg"].get<double>()) * 78.8e3, 111.0, 1.0);
  EXPECT_EQ(gps[1]["longitude_deg"], clean_gps[1]["longitude_deg"]);
  std::size_t dead_imu = 0, jumped = 0;
  for (const json& imu : Lines(faulty->sensors.str(), "imu")) {
    const double t = imu["t"].get<double>();
    if (t >= 10.0) {
      EXPECT_GE(t, 1e4 + 10.0 - 1e-6);
    }
    jumped += t >= 1e4;
    const bool dead = imu["accel_x_mps2"] == 0.0 && imu["accel_y_mps2"] == 0.0 && imu["gyro_z_radps"] == 0.0;
    dead_imu += dead;
    if (t < 8.0) {
      EXPECT_FALSE(dead) << t;
    }
  }
  EXPECT_GT(dead_imu, 500u);
  EXPECT_GT(jumped, 500u);
  for (const json& wheels : Lines(faulty->sensors.str(), "wheels")) {
    const double t = wheels["t"].get<double>();
    if (t >= 6.0) {
      EXPECT_EQ(wheels["speed_radps"]["right"], 0.0) << t;
    }
  }
  EXPECT_EQ(faulty->truth.str(), clean->truth.str());  // the truth is never faulted
}

TEST(SimulationTest, AGnssOutageInTheMiddleOfARunStopsTheFixesAndTheyComeBack) {
  Scenario scenario = Shipped("agrimaro-tiles");
  scenario.faults.gnss_outages = {{5.0, 9.0}, {12.0, 13.0}};
  const auto run = Simulate(scenario);
  const auto clean = Simulate(Shipped("agrimaro-tiles"));
  std::size_t before = 0, between = 0, after = 0;
  for (const json& gps : Lines(run->sensors.str(), "gps")) {
    const double t = gps["t"].get<double>();
    EXPECT_FALSE(t >= 5.0 && t < 9.0) << t;
    EXPECT_FALSE(t >= 12.0 && t < 13.0) << t;
    before += t < 5.0;
    between += t >= 9.0 && t < 12.0;
    after += t >= 13.0;
  }
  EXPECT_GT(before, 0u);
  EXPECT_GT(between, 0u);
  EXPECT_GT(after, 0u);
  // Nothing else moved: the same drive, the same IMU messages; the truth records the outages.
  EXPECT_EQ(Lines(run->sensors.str(), "imu"), Lines(clean->sensors.str(), "imu"));
  const std::vector<json> truth = Lines(run->truth.str(), "truth"), clean_truth = Lines(clean->truth.str(), "truth");
  ASSERT_EQ(truth.size(), clean_truth.size());
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const double t = truth[i]["t"].get<double>();
    EXPECT_EQ(truth[i]["x_m"], clean_truth[i]["x_m"]);
    if ((t > 5.2 && t < 8.8) || (t > 12.2 && t < 12.8)) {
      EXPECT_FALSE(truth[i]["gnss_available"].get<bool>()) << t;
    }
  }
}

}  // namespace
}  // namespace rowloc::sim
