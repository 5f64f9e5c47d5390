// The online mount check (ranger_mount_monitor.hpp) on a synthetic drive along a straight lane:
// a ranger written 5 cm off is reported after the window fills and the confirmations agree, named
// and with its offset; right mounts are never reported; a restart empties the window; bad
// settings are refused.
#include "rowloc/localization/ranger_mount_monitor.hpp"
#include "synthetic_row_drive.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace rowloc::localization {
namespace {

using ::testing::HasSubstr;
using test::Rangers;
using test::StraightRows;

/// Feeds the drive in time order (a pose, then its echoes) and runs Check after each pose.
/// Returns the time of the first change of the suspects, if any.
std::optional<double> Feed(RangerMountMonitor& monitor, const test::SyntheticDrive& drive) {
  std::optional<double> first_change;
  std::size_t e = 0;
  for (const ReferenceKnot& knot : drive.reference) {
    monitor.ObservePose(knot.time_s, knot.pose, *knot.body_rates);
    for (; e < drive.echoes.size() && drive.echoes[e].time_s <= knot.time_s; ++e) {
      monitor.ObserveEcho(drive.echoes[e].time_s, drive.echoes[e].ranger, drive.echoes[e].range_m);
    }
    if (monitor.Check(knot.time_s) && !first_change) first_change = knot.time_s;
  }
  return first_change;
}

std::shared_ptr<const RowMapRanging> Ranging(const geometry::RowMap& map) {
  return std::make_shared<const RowMapRanging>(map, map.origin, 2.0);
}

test::SyntheticDrive DriveOnStraightRows() {
  const geometry::RowMap map = StraightRows();
  const RowMapRanging ranging(map, map.origin, 2.0);
  return test::Drive(ranging, Rangers());
}

TEST(RangerMountMonitor, ReportsTheRangerThatIsOffOnceTheWindowAndTheConfirmationsAgree) {
  std::vector<mapio::SensorMount> configured = Rangers();
  configured[2].position_m.y() = -0.45;  // us_front_right written 5 cm inward: it sits 5 cm further along its beam
  const geometry::RowMap map = StraightRows();
  RangerMountMonitor monitor(Ranging(map), configured, MapAidedConfig{});
  const std::optional<double> reported = Feed(monitor, DriveOnStraightRows());
  ASSERT_TRUE(reported.has_value());
  // Window of 10 s before the first fit, then two fits 5 s apart.
  EXPECT_NEAR(*reported, 15.0, 0.5);
  ASSERT_EQ(monitor.suspects().size(), 1u);
  const RangerMountFinding& f = monitor.suspects().front();
  EXPECT_EQ(f.ranger, "us_front_right");
  // A 20 s window pins the front pair's split less well than a whole drive (ranger_mount_fit_test.cpp).
  EXPECT_NEAR(f.along_beam_m, 0.05, 0.008);
  EXPECT_GT(f.sigma_m, 0.0);
  EXPECT_THAT(RangerMountMonitor::Reason(f, 20.0), HasSubstr("cm nearer to the rows it hears than configured"));
  EXPECT_THAT(RangerMountMonitor::Reason(f, 20.0), HasSubstr("rowloc calibrate"));
  EXPECT_GT(monitor.checks(), 10u);
}

TEST(RangerMountMonitor, NeverReportsRightMounts) {
  const geometry::RowMap map = StraightRows();
  RangerMountMonitor monitor(Ranging(map), Rangers(), MapAidedConfig{});
  EXPECT_FALSE(Feed(monitor, DriveOnStraightRows()).has_value());
  EXPECT_TRUE(monitor.suspects().empty());
  EXPECT_GT(monitor.checks(), 10u);
}

TEST(RangerMountMonitor, ARestartEmptiesTheWindowAndAJumpRestartsIt) {
  const geometry::RowMap map = StraightRows();
  RangerMountMonitor monitor(Ranging(map), Rangers(), MapAidedConfig{});
  const test::SyntheticDrive drive = DriveOnStraightRows();
  for (std::size_t k = 0; k < 60; ++k) monitor.ObservePose(drive.reference[k].time_s, drive.reference[k].pose, {0.5, 0, 0});
  EXPECT_TRUE(monitor.Check(drive.reference[59].time_s) || monitor.checks() == 1u);
  monitor.Restart();
  EXPECT_FALSE(monitor.Check(100.0));  // nothing in the window: no fit
  EXPECT_EQ(monitor.checks(), 1u);
  // Poses 5 m apart (a re-initialisation): each jump restarts the window, which never spans 10 s.
  for (int k = 0; k < 100; ++k) monitor.ObservePose(200.0 + 0.2 * k, Eigen::Vector3d(5.0 * (k % 2), 1.25, 0.0), {0.5, 0, 0});
  EXPECT_FALSE(monitor.Check(300.0));
  EXPECT_EQ(monitor.checks(), 1u);
}

TEST(RangerMountMonitor, RefusesBadSettingsAndUnknownRangers) {
  const geometry::RowMap map = StraightRows();
  RangerMountMonitorConfig config;
  config.window_s = 5.0;  // below min_span_s
  EXPECT_THROW(RangerMountMonitor(Ranging(map), Rangers(), MapAidedConfig{}, config), std::invalid_argument);
  config = {};
  config.check_every_s = -1.0;
  EXPECT_THROW(RangerMountMonitor(Ranging(map), Rangers(), MapAidedConfig{}, config), std::invalid_argument);
  config = {};
  config.confirmations = 0;
  EXPECT_THROW(RangerMountMonitor(Ranging(map), Rangers(), MapAidedConfig{}, config), std::invalid_argument);
  config = {};
  config.fit.range_sigma_m = 0.0;
  EXPECT_THROW(RangerMountMonitor(Ranging(map), Rangers(), MapAidedConfig{}, config), std::invalid_argument);
  EXPECT_THROW(RangerMountMonitor(nullptr, Rangers(), MapAidedConfig{}), std::invalid_argument);
  RangerMountMonitor monitor(Ranging(map), Rangers(), MapAidedConfig{});
  EXPECT_THROW(monitor.ObserveEcho(1.0, 4, 1.0), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::localization
