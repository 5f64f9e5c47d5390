// Tests of the per-sensor health monitor (sensor_health.hpp): stuck readings only while moving,
// persistent gating, exclusion of the stuck sensor that disagrees with the others, latching and
// recovery, refusals, and the notices of state changes.
#include "rowloc/localization/sensor_health.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <stdexcept>

namespace rowloc::localization {
namespace {

using ::testing::HasSubstr;

SensorHealth Of(const SensorHealthMonitor& m, const std::string& sensor) {
  for (const SensorHealth& h : m.Report()) {
    if (h.sensor == sensor) return h;
  }
  ADD_FAILURE() << "no sensor " << sensor;
  return {};
}

void Feed(SensorHealthMonitor& m, const std::string& sensor, std::size_t count, bool moving, double value = 0.0) {
  for (std::size_t i = 0; i < count; ++i) {
    const std::array<double, 3> readings{value, value, value};
    m.ObserveReadings(sensor, readings, moving);
  }
}

TEST(SensorHealth, IdenticalReadingsAtRestSayNothing) {
  SensorHealthMonitor m;
  Feed(m, "imu", 500, false);
  EXPECT_EQ(Of(m, "imu").state, SensorHealthState::kOk);
  EXPECT_FALSE(m.TakeChanges().has_value());
}

TEST(SensorHealth, StuckWhileMovingIsSuspectAndExcludedWhenAnotherDisagrees) {
  SensorHealthMonitor m;
  Feed(m, "imu", 48, true);
  EXPECT_EQ(Of(m, "imu").state, SensorHealthState::kOk);
  Feed(m, "imu", 2, true);  // 50 identical readings while moving
  EXPECT_EQ(Of(m, "imu").state, SensorHealthState::kSuspect);
  EXPECT_THAT(m.TakeChanges().value_or(""), HasSubstr("imu suspect: readings identical for 50 messages"));
  for (int i = 0; i < 20; ++i) m.ObserveUpdate("gnss", i % 2 == 0);  // 10 of 20 gated: inconsistent
  EXPECT_EQ(Of(m, "gnss").state, SensorHealthState::kSuspect);
  EXPECT_EQ(Of(m, "imu").state, SensorHealthState::kExcluded);
  EXPECT_TRUE(m.Excluded("imu"));
  EXPECT_EQ(m.exclusions(), 1u);
  EXPECT_EQ(m.last_excluded(), "imu");
  EXPECT_THAT(m.TakeChanges().value_or(""), HasSubstr("while gnss disagrees (10 of the last 20 updates gated out)"));
  // Latched: the GNSS agreeing again does not bring the stuck IMU back.
  for (int i = 0; i < 20; ++i) m.ObserveUpdate("gnss", true);
  EXPECT_EQ(Of(m, "gnss").state, SensorHealthState::kOk);
  EXPECT_EQ(Of(m, "imu").state, SensorHealthState::kExcluded);
  m.ObserveSkipped("imu");
  EXPECT_EQ(Of(m, "imu").skipped, 1u);
  // Readings that change again for 50 messages: ok.
  for (int i = 1; i <= 50; ++i) Feed(m, "imu", 1, true, 0.001 * i);
  EXPECT_EQ(Of(m, "imu").state, SensorHealthState::kOk);
  EXPECT_FALSE(m.Excluded("imu"));
}

TEST(SensorHealth, StuckAndOwnUpdatesInconsistentIsExcluded) {
  SensorHealthMonitor m;
  Feed(m, "ranger", 60, true, 1.5);
  for (int i = 0; i < 20; ++i) m.ObserveUpdate("ranger", false);
  EXPECT_EQ(Of(m, "ranger").state, SensorHealthState::kExcluded);
  EXPECT_EQ(Of(m, "ranger").gated, 20u);
}

TEST(SensorHealth, PersistentGatingAloneIsSuspectNotExcluded) {
  SensorHealthMonitor m;
  for (int i = 0; i < 19; ++i) m.ObserveUpdate("wheels", false);
  EXPECT_EQ(Of(m, "wheels").state, SensorHealthState::kOk);  // the window is not full yet
  m.ObserveUpdate("wheels", false);
  EXPECT_EQ(Of(m, "wheels").state, SensorHealthState::kSuspect);
  EXPECT_THAT(Of(m, "wheels").reason, HasSubstr("20 of the last 20 updates gated out"));
  EXPECT_FALSE(m.Excluded("wheels"));
  for (int i = 0; i < 11; ++i) m.ObserveUpdate("wheels", true);  // 9 of 20 gated
  EXPECT_EQ(Of(m, "wheels").state, SensorHealthState::kOk);
  EXPECT_EQ(Of(m, "wheels").accepted, 11u);
}

TEST(SensorHealth, RefusalIsSuspectUntilTheNextAcceptedMessage) {
  SensorHealthMonitor m;
  m.ObserveRefusal("gnss", "time stamp jump");
  EXPECT_EQ(Of(m, "gnss").state, SensorHealthState::kSuspect);
  EXPECT_THAT(Of(m, "gnss").reason, HasSubstr("message refused: time stamp jump"));
  EXPECT_EQ(Of(m, "gnss").refused, 1u);
  m.ObserveAccepted("gnss");
  EXPECT_EQ(Of(m, "gnss").state, SensorHealthState::kOk);
  EXPECT_EQ(Of(m, "gnss").refused, 1u);  // counts stay
  const std::string changes = m.TakeChanges().value_or("");
  EXPECT_THAT(changes, HasSubstr("gnss suspect"));
  EXPECT_THAT(changes, HasSubstr("gnss ok"));
}

TEST(SensorHealth, ADisagreementIsSuspectWhileItLasts) {
  SensorHealthMonitor m;
  m.ObserveDisagreement("map", std::nullopt);  // nothing to report: no entry
  EXPECT_TRUE(m.Report().empty());
  m.ObserveDisagreement("map", std::string("70 of the last 100 echoes found no row"));
  EXPECT_EQ(Of(m, "map").state, SensorHealthState::kSuspect);
  EXPECT_EQ(Of(m, "map").reason, "70 of the last 100 echoes found no row");
  m.ObserveDisagreement("map", std::string("80 of the last 100 echoes found no row"));  // still suspect
  EXPECT_EQ(m.TakeChanges().value_or(""), "sensor health: map suspect: 70 of the last 100 echoes found no row");
  EXPECT_FALSE(m.Excluded("map"));
  m.ObserveDisagreement("map", std::nullopt);
  EXPECT_EQ(Of(m, "map").state, SensorHealthState::kOk);
  EXPECT_EQ(m.TakeChanges().value_or(""), "sensor health: map ok");
}

TEST(SensorHealth, NamesAndConfigurationChecks) {
  EXPECT_EQ(SensorHealthStateName(SensorHealthState::kOk), "ok");
  EXPECT_EQ(SensorHealthStateName(SensorHealthState::kSuspect), "suspect");
  EXPECT_EQ(SensorHealthStateName(SensorHealthState::kExcluded), "excluded");
  EXPECT_THROW(SensorHealthMonitor({.window = 0}), std::invalid_argument);
  EXPECT_THROW(SensorHealthMonitor({.window = 20, .suspect_gated_fraction = 1.5}), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::localization
