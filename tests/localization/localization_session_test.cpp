// One localization run: estimate records every period, counted updates, refusals reported (not
// thrown), and the same records for the same messages.
#include "rowloc/localization/localization_session.hpp"

#include "rowloc/formats/sensor_log_reader.hpp"
#include "rowloc/mapio/vehicle_config.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <fstream>

namespace rowloc::localization {
namespace {

struct Replayed {
  std::vector<SessionStep> steps;
  LocalizationSession session;
};

Replayed Replay(double period_s) {
  std::ifstream in(rowloc::test::SourceDir() / "tests/data/logs/agrimaro-tiles-head.ndjson");
  formats::SensorLogReader reader(in, "tiles");
  SessionOptions options;
  options.estimate_period_s = period_s;
  LocalizationSession session(mapio::LoadVehicleConfig(rowloc::test::SourceDir() / "config/vehicles/agrimaro-swerve.json"),
                              FilterConfig{}, reader.header(), options);
  session.SetPose(0.0, Eigen::Vector3d::Zero(), Eigen::Vector3d(0.25, 0.25, 0.04).asDiagonal());
  std::vector<SessionStep> steps;
  while (const auto message = reader.Next()) steps.push_back(session.Process(*message));
  return {std::move(steps), std::move(session)};
}

TEST(LocalizationSession, EstimatesEveryPeriodAndCountsUpdates) {
  const Replayed run = Replay(0.1);
  std::vector<double> times;
  std::size_t updates = 0;
  for (const SessionStep& step : run.steps) {
    if (step.estimate) times.push_back(step.estimate->time_s);
    updates += step.updates.size();
  }
  ASSERT_GE(times.size(), 14u);  // 1.42 s of log
  for (std::size_t i = 1; i < times.size(); ++i) EXPECT_GE(times[i] - times[i - 1], 0.1 - 1e-12);
  std::size_t counted = 0;
  for (const auto& [sensor, c] : run.session.update_counts()) counted += c.accepted + c.gated;
  EXPECT_EQ(counted, updates);
  EXPECT_TRUE(run.session.last_fix_time_s().has_value());
  EXPECT_EQ(run.session.estimates(), times.size());
  EXPECT_EQ(run.session.messages(), run.steps.size());
}

TEST(LocalizationSession, SameMessagesSameRecords) {
  const Replayed a = Replay(0.05), b = Replay(0.05);
  ASSERT_EQ(a.steps.size(), b.steps.size());
  for (std::size_t i = 0; i < a.steps.size(); ++i) {
    ASSERT_EQ(a.steps[i].estimate.has_value(), b.steps[i].estimate.has_value());
    if (a.steps[i].estimate) {
      EXPECT_EQ(a.steps[i].estimate->position_m, b.steps[i].estimate->position_m);
      EXPECT_EQ(*a.steps[i].estimate->covariance, *b.steps[i].estimate->covariance);
    }
  }
}

TEST(LocalizationSession, RefusedMessagesAreReportedNotThrown) {
  Replayed run = Replay(0.1);
  const double t = run.session.filter().time_s();
  const std::string before = std::to_string(run.session.filter().state()(0));
  const SessionStep step = run.session.Process(formats::WheelsMessage{t + 0.01, {500.0, 1.0, 1.0}, {}, {}});
  ASSERT_TRUE(step.error.has_value());
  EXPECT_FALSE(step.changed_state);
  EXPECT_EQ(run.session.refused(), 1u);
  EXPECT_EQ(std::to_string(run.session.filter().state()(0)), before);
  const SessionStep backwards = run.session.Process(formats::ImuMessage{t - 1.0, "imu", 0, 0, 0});
  EXPECT_TRUE(backwards.error.has_value());
}

TEST(LocalizationSession, SkippedTypesAreNotProcessed) {
  std::ifstream in(rowloc::test::SourceDir() / "tests/data/logs/agrimaro-tiles-head.ndjson");
  formats::SensorLogReader reader(in, "tiles");
  SessionOptions options;
  options.skip_types = {"imu"};
  LocalizationSession session(mapio::AgrimaroSwerveConfig(), FilterConfig{}, reader.header(), options);
  std::size_t skipped = 0;
  while (const auto message = reader.Next()) skipped += session.Process(*message).skipped;
  EXPECT_GT(skipped, 0u);
  EXPECT_EQ(session.skipped(), skipped);
  EXPECT_EQ(session.update_counts().count("imu"), 0u);
}

TEST(LocalizationSession, RefusesANonPositivePeriod) {
  formats::LogHeader header;
  header.origin = {45.0, 7.0, 200.0};
  header.wheels = {"left_front", "left_rear", "right"};
  SessionOptions options;
  options.estimate_period_s = 0.0;
  EXPECT_THROW(LocalizationSession(mapio::AgrimaroSwerveConfig(), FilterConfig{}, header, options),
               std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::localization
