// The filter on the simulator's fault scenarios (config/scenarios/fault-*.json; issue 26): each
// simulated log runs through a LocalizationSession (as `rowloc replay` and the service do), and the
// outcome is asserted against the truth: error bounded and covered by the covariance, notices and
// refusals reported, the faulty sensor's health flagged in the estimates.
#include "rowloc/formats/sensor_log_reader.hpp"
#include "rowloc/formats/trajectory_streams.hpp"
#include "rowloc/localization/localization_session.hpp"
#include "rowloc/sim/scenario.hpp"
#include "rowloc/sim/simulation.hpp"
#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace rowloc::localization {
namespace {

using ::testing::HasSubstr;

struct Outcome {
  std::vector<std::string> notices, errors;
  std::vector<formats::EstimateRecord> estimates;
  double worst_error_m = 0.0;        ///< over the estimates from settle_s on (truth time)
  double worst_normalized = 0.0;     ///< the largest position error / sqrt(trace of its covariance)
  double last_estimate_truth_s = 0.0;
  std::size_t refused = 0;
};

/// Simulates the scenario and runs its log through a session with the default filter; errors are
/// compared from settle_s (truth time; a stamp beyond time_jump_s is the truth's time + time_jump_s).
Outcome RunScenario(const std::string& name, double settle_s, double time_jump_s = 0.0) {
  const sim::Scenario scenario = sim::LoadScenario(test::SourceDir() / "config/scenarios" / (name + ".json"));
  std::stringstream sensors, truth_text;
  sim::RunSimulation(scenario, {&sensors, &truth_text, nullptr, nullptr});
  const formats::TruthStream truth = formats::ParseTruthStream(truth_text, "truth");
  std::map<long, const formats::TruthSample*> by_ms;
  for (const auto& s : truth.samples) by_ms[std::lround(s.t_s * 1000)] = &s;
  formats::SensorLogReader reader(sensors, name);
  LocalizationSession session(scenario.vehicle, FilterConfig{}, reader.header(), {.record_updates = false, .skip_types = {}});
  Outcome out;
  while (const auto m = reader.Next()) {
    SessionStep step = session.Process(*m);
    if (step.notice) out.notices.push_back(*step.notice);
    if (step.error) out.errors.push_back(*step.error);
    if (!step.estimate) continue;
    const formats::EstimateRecord& e = *step.estimate;
    out.estimates.push_back(e);
    const double t = time_jump_s > 0.0 && e.time_s >= time_jump_s ? e.time_s - time_jump_s : e.time_s;
    const auto it = by_ms.find(std::lround(t * 1000));
    if (it == by_ms.end() || t < settle_s) continue;
    out.last_estimate_truth_s = t;
    const double error = (e.position_m - it->second->position_m).norm();
    out.worst_error_m = std::max(out.worst_error_m, error);
    const double sigma = std::sqrt((*e.covariance)(0, 0) + (*e.covariance)(1, 1));
    out.worst_normalized = std::max(out.worst_normalized, error / sigma);
  }
  out.refused = session.refused();
  return out;
}

const formats::SensorHealthRecord* HealthOf(const formats::EstimateRecord& e, const std::string& sensor) {
  for (const auto& h : e.sensor_health) {
    if (h.sensor == sensor) return &h;
  }
  return nullptr;
}

// One fix 111 m off before initialisation: discarded by the consensus; RTK accuracy from the start.
TEST(FaultScenarios, GnssOutlierBeforeInitialisation) {
  const Outcome out = RunScenario("fault-gnss-outlier-before-init", 5.0);
  ASSERT_FALSE(out.notices.empty());
  EXPECT_THAT(out.notices.front(), testing::AllOf(HasSubstr("initialised at t="), HasSubstr("disagreeing")));
  EXPECT_THAT(out.notices.front(), testing::Not(HasSubstr(" 0 disagreeing")));
  EXPECT_LT(out.worst_error_m, 0.05);
  EXPECT_LT(out.worst_normalized, 5.0);
  EXPECT_GT(out.last_estimate_truth_s, 15.0);
}

// 4,000 km outliers (before and after initialisation) never abort the run.
TEST(FaultScenarios, GnssOutlierOf4000KmDoesNotAbortTheRun) {
  const Outcome out = RunScenario("fault-gnss-outlier-4000km", 5.0);
  EXPECT_LT(out.worst_error_m, 0.05);
  EXPECT_GT(out.last_estimate_truth_s, 15.0);
  for (const std::string& error : out.errors) EXPECT_THAT(error, HasSubstr("gps"));
}

// A dead IMU from 20 s on a circle: excluded (named in the estimates), the estimate stays on the fixes.
TEST(FaultScenarios, DeadImuIsExcludedAndReported) {
  const Outcome out = RunScenario("fault-dead-imu", 5.0);
  EXPECT_THAT(out.notices, testing::Contains(HasSubstr("imu excluded")));
  ASSERT_FALSE(out.estimates.empty());
  const formats::SensorHealthRecord* imu = HealthOf(out.estimates.back(), "imu");
  ASSERT_NE(imu, nullptr);
  EXPECT_EQ(imu->state, "excluded");
  EXPECT_GT(imu->skipped, 1000u);
  // Measured (seed 0, 2026-12-04): the IMU excluded at 20.6 s, re-initialised at 23.1 s; worst error
  // 0.042 m, and 9.1 sigma at the final stop, where the filter without its IMU is overconfident
  // (0.04 m against 4 mm). The clean run: 0.024 m, 2.1 sigma. Issue 26 before: 2.2 m at 0.23 m sigma.
  EXPECT_LT(out.worst_error_m, 0.1);
  EXPECT_LT(out.worst_normalized, 12.0);
  EXPECT_GT(out.last_estimate_truth_s, 70.0);
}

// The logger's clock jumps 10^4 s: the first jumped messages are refused with the reason, then the
// time base moves (notice), and the estimate follows the drive on the new clock (not frozen).
TEST(FaultScenarios, ClockJumpMovesTheTimeBase) {
  const Outcome out = RunScenario("fault-clock-jump", 5.0, 1e4);
  ASSERT_FALSE(out.errors.empty());
  EXPECT_THAT(out.errors.front(), testing::AllOf(HasSubstr("ahead of the filter's time"), HasSubstr("max_time_jump_s")));
  EXPECT_THAT(out.notices, testing::Contains(HasSubstr("time base moved")));
  EXPECT_GT(out.last_estimate_truth_s, 15.0);
  EXPECT_LT(out.worst_error_m, 0.1);
}

// Stamps offset by 1e18 s: every such message is refused with its key and counted; no estimate
// claims a time it cannot resolve.
TEST(FaultScenarios, ClockOffsetOf1e18IsRefusedAndCounted) {
  const Outcome out = RunScenario("fault-clock-offset-1e18", 5.0);
  ASSERT_FALSE(out.errors.empty());
  EXPECT_EQ(out.refused, out.errors.size());
  EXPECT_GT(out.refused, 1000u);
  EXPECT_THAT(out.errors.front(), HasSubstr(".t = 1e+18 is outside [-1e+12, 1e+12]"));
  for (const auto& e : out.estimates) EXPECT_LT(e.time_s, 8.0);
  ASSERT_FALSE(out.estimates.empty());
}

// A sibling: a dead wheel encoder is flagged in the estimates; the RTK fixes keep the accuracy.
TEST(FaultScenarios, DeadWheelEncoderIsReported) {
  const Outcome out = RunScenario("fault-dead-wheel-encoder", 5.0);
  ASSERT_FALSE(out.estimates.empty());
  const formats::SensorHealthRecord* right = HealthOf(out.estimates.back(), "wheels.right");
  ASSERT_NE(right, nullptr);
  EXPECT_NE(right->state, "ok");
  EXPECT_LT(out.worst_error_m, 0.1);
  EXPECT_GT(out.last_estimate_truth_s, 15.0);
}

}  // namespace
}  // namespace rowloc::localization
