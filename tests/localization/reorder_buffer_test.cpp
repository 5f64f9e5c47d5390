// The reorder window: late messages inside it come out in time order, older ones are refused, and
// the order of releases depends only on the order of arrivals.
#include "rowloc/localization/reorder_buffer.hpp"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace rowloc::localization {
namespace {

formats::SensorMessage Imu(double t, double marker = 0.0) {
  return formats::ImuMessage{t, "imu", marker, 0.0, 0.0};
}

std::vector<double> Drain(ReorderBuffer& buffer, bool all) {
  std::vector<double> times;
  while (auto m = all ? buffer.PopAny() : buffer.PopReady()) times.push_back(formats::TimeOf(*m));
  return times;
}

TEST(ReorderBuffer, HoldsForTheWindowThenReleasesInTimeOrder) {
  ReorderBuffer buffer(0.2);
  EXPECT_EQ(buffer.Add(Imu(1.0)), ReorderBuffer::Admission::kHeld);
  EXPECT_EQ(buffer.Add(Imu(1.1)), ReorderBuffer::Admission::kHeld);
  EXPECT_TRUE(Drain(buffer, false).empty());  // nothing 0.2 s newer yet
  EXPECT_EQ(buffer.Add(Imu(1.25)), ReorderBuffer::Admission::kHeld);
  EXPECT_EQ(buffer.Add(Imu(1.05)), ReorderBuffer::Admission::kHeld);  // late, inside the window
  EXPECT_EQ(Drain(buffer, false), (std::vector<double>{1.0, 1.05}));
  EXPECT_EQ(buffer.held(), 2u);
  EXPECT_EQ(buffer.Add(Imu(1.04)), ReorderBuffer::Admission::kTooOld);  // before the last released
  EXPECT_EQ(buffer.Add(Imu(1.05)), ReorderBuffer::Admission::kHeld);    // equal times are fine
  EXPECT_EQ(Drain(buffer, true), (std::vector<double>{1.05, 1.1, 1.25}));
}

TEST(ReorderBuffer, EqualTimesKeepTheirArrivalOrder) {
  ReorderBuffer buffer(0.0);
  buffer.Add(Imu(2.0, 1.0));
  buffer.Add(Imu(2.0, 2.0));
  std::vector<double> markers;
  while (auto m = buffer.PopReady()) markers.push_back(std::get<formats::ImuMessage>(*m).accel_x_mps2);
  EXPECT_EQ(markers, (std::vector<double>{1.0, 2.0}));
}

TEST(ReorderBuffer, ZeroWindowIsTheRuleOfALog) {
  ReorderBuffer buffer(0.0);
  buffer.Add(Imu(1.0));
  EXPECT_EQ(Drain(buffer, false), std::vector<double>{1.0});
  EXPECT_EQ(buffer.Add(Imu(0.999)), ReorderBuffer::Admission::kTooOld);
}

TEST(ReorderBuffer, AnyArrivalOrderWithinTheWindowGivesSortedOutput) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> jitter(0.0, 0.15);
  ReorderBuffer buffer(0.2);
  std::vector<double> released;
  for (int i = 0; i < 2000; ++i) {
    const double t = 0.01 * i + jitter(rng);  // arrives up to 0.15 s late
    ASSERT_EQ(buffer.Add(Imu(t)), ReorderBuffer::Admission::kHeld) << i;
    for (double r : Drain(buffer, false)) released.push_back(r);
  }
  for (double r : Drain(buffer, true)) released.push_back(r);
  EXPECT_EQ(released.size(), 2000u);
  EXPECT_TRUE(std::is_sorted(released.begin(), released.end()));
}

TEST(ReorderBuffer, RefusesBadWindowsAndTimes) {
  EXPECT_THROW(ReorderBuffer(-0.1), std::invalid_argument);
  EXPECT_THROW(ReorderBuffer(std::nan("")), std::invalid_argument);
  ReorderBuffer buffer(0.1);
  EXPECT_THROW(buffer.Add(Imu(std::nan(""))), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::localization
