// The session's check of the ranger mounts (ranger_mount_monitor.hpp) on a simulated drive: a
// ranger written 5 cm off is reported in the estimates' sensor_health and as a notice within 30 s
// of the first echo the filter uses; right mounts are not; the check can be turned off.
#include "rowloc/formats/sensor_log_reader.hpp"
#include "rowloc/localization/localization_session.hpp"
#include "one_lane_drive.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <optional>
#include <sstream>

namespace rowloc::localization {
namespace {

using ::testing::HasSubstr;

struct Outcome {
  std::optional<double> first_echo_used_s;
  std::optional<double> first_report_s;  ///< the first estimate whose sensor_health names us_front_left's mount
  std::string report;                    ///< its reason
  std::string notice;                    ///< the notice that announced it
  std::size_t other_reports = 0;         ///< estimates that name another ranger's mount
  bool monitor = false;
};

Outcome Drive(const mapio::VehicleConfig& vehicle, bool check) {
  const test::OneLaneDrive& drive = test::SimulatedOneLaneDrive();
  std::istringstream log(drive.sensors);
  formats::SensorLogReader reader(log, "drive");
  SessionOptions options;
  options.check_ranger_mounts = check;
  LocalizationSession session(vehicle, FilterConfig{}, reader.header(), options);
  session.AttachRowMap(drive.map);
  Outcome o;
  o.monitor = session.ranger_mount_monitor() != nullptr;
  while (const auto message = reader.Next()) {
    const SessionStep step = session.Process(*message);
    if (step.echo && !o.first_echo_used_s && (step.echo->outcome == "accepted" || step.echo->outcome == "gated")) {
      o.first_echo_used_s = session.filter().time_s();
    }
    if (step.notice && step.notice->find("fit the map") != std::string::npos && o.notice.empty()) o.notice = *step.notice;
    if (!step.estimate) continue;
    for (const formats::SensorHealthRecord& h : step.estimate->sensor_health) {
      if (h.reason.find("fit the map") == std::string::npos) continue;
      if (h.sensor != "us_front_left") {
        ++o.other_reports;
      } else if (!o.first_report_s) {
        o.first_report_s = step.estimate->time_s;
        o.report = h.state + ": " + h.reason;
      }
    }
  }
  return o;
}

TEST(LocalizationSessionMountCheck, ReportsA5cmMountErrorWithin30sOfTheFirstEcho) {
  const mapio::VehicleConfig truth = test::SimulatedOneLaneDrive().scenario.vehicle;
  const Outcome o = Drive(test::WithRangerMoved(truth, "us_front_left", 0.0, 0.05), true);
  ASSERT_TRUE(o.first_echo_used_s.has_value());
  ASSERT_TRUE(o.first_report_s.has_value());
  EXPECT_LT(*o.first_report_s - *o.first_echo_used_s, 30.0);
  EXPECT_THAT(o.report, HasSubstr("suspect: its echoes over the last 20 s fit the map with the ranger"));
  EXPECT_THAT(o.report, HasSubstr("further from the rows it hears"));
  EXPECT_THAT(o.notice, HasSubstr("us_front_left suspect"));
  EXPECT_EQ(o.other_reports, 0u);
}

TEST(LocalizationSessionMountCheck, RightMountsAreNotReported) {
  const Outcome o = Drive(test::SimulatedOneLaneDrive().scenario.vehicle, true);
  EXPECT_TRUE(o.monitor);
  EXPECT_FALSE(o.first_report_s.has_value());
  EXPECT_EQ(o.other_reports, 0u);
}

TEST(LocalizationSessionMountCheck, CanBeTurnedOff) {
  const mapio::VehicleConfig truth = test::SimulatedOneLaneDrive().scenario.vehicle;
  const Outcome o = Drive(test::WithRangerMoved(truth, "us_front_left", 0.0, 0.05), false);
  EXPECT_FALSE(o.monitor);
  EXPECT_FALSE(o.first_report_s.has_value());
}

}  // namespace
}  // namespace rowloc::localization
