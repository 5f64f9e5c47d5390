// Layout of the vehicle EKF state for the shipped vehicles (state_layout.hpp).
#include "rowloc/localization/state_layout.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>
#include <vector>

namespace rowloc::localization {
namespace {

using L = StateLayout;

struct Expected {
  mapio::VehicleConfig vehicle;
  int size;       // without slip-aware odometry
  int steerable;  // steering states
};

std::vector<Expected> ShippedVehicles() {
  return {{mapio::AgrimaroSwerveConfig(), 12, 3},
          {mapio::VineyardUgv4wsConfig(), 13, 4},
          {mapio::DifferentialDriveConfig(), 9, 0},
          {mapio::TrackedVehicleConfig(), 9, 0}};
}

// Every index in [0, size) used exactly once by the base states and the per-wheel states.
void ExpectUniqueAndContiguous(const StateLayout& layout) {
  std::vector<int> used;
  for (int i = 0; i < L::kBaseSize; ++i) used.push_back(i);
  for (const auto* indices : {&layout.steering, &layout.rolling_radius, &layout.slip_compliance, &layout.wheel_angle,
                              &layout.traction}) {
    ASSERT_EQ(indices->size(), layout.wheel_count());
    for (int index : *indices) {
      if (index >= 0) used.push_back(index);
    }
  }
  if (layout.accel_bias >= 0) used.insert(used.end(), {layout.accel_bias, layout.accel_bias + 1});
  if (layout.gnss_bias >= 0) used.insert(used.end(), {layout.gnss_bias, layout.gnss_bias + 1});
  std::sort(used.begin(), used.end());
  ASSERT_EQ(used.size(), static_cast<std::size_t>(layout.size));
  for (std::size_t i = 0; i < used.size(); ++i) EXPECT_EQ(used[i], static_cast<int>(i));
}

TEST(StateLayout, BaseIndicesAreTheDocumentedOnes) {
  EXPECT_EQ(L::kX, 0);
  EXPECT_EQ(L::kY, 1);
  EXPECT_EQ(L::kPhi, 2);
  EXPECT_EQ(L::kVx, 3);
  EXPECT_EQ(L::kVy, 4);
  EXPECT_EQ(L::kYawRate, 5);
  EXPECT_EQ(L::kAx, 6);
  EXPECT_EQ(L::kAy, 7);
  EXPECT_EQ(L::kGyroBias, 8);
  EXPECT_EQ(L::kBaseSize, 9);
}

TEST(StateLayout, SizesOfTheShippedVehicles) {
  for (const Expected& e : ShippedVehicles()) {
    SCOPED_TRACE(e.vehicle.name);
    const StateLayout plain = StateLayout::For(e.vehicle, false);
    EXPECT_EQ(plain.size, e.size);
    EXPECT_EQ(plain.wheel_count(), e.vehicle.wheels.size());
    EXPECT_FALSE(plain.slip_aware());
    EXPECT_EQ(std::count_if(plain.steering.begin(), plain.steering.end(), [](int i) { return i >= 0; }),
              e.steerable);
    const StateLayout slip = StateLayout::For(e.vehicle, true);
    EXPECT_EQ(slip.size, e.size + 2 * static_cast<int>(e.vehicle.wheels.size()));
    EXPECT_TRUE(slip.slip_aware());
    EXPECT_EQ(slip.steering, plain.steering);  // augmented states come after the steering angles
  }
  for (const Expected& e : ShippedVehicles()) {  // the accelerometer bias comes last, after everything
    for (bool slip : {false, true}) {
      const StateLayout without = StateLayout::For(e.vehicle, slip);
      const StateLayout with = StateLayout::For(e.vehicle, {.slip_aware_odometry = slip, .accel_bias = true});
      EXPECT_EQ(without.accel_bias, -1);
      EXPECT_EQ(with.accel_bias, without.size);
      EXPECT_EQ(with.size, without.size + 2);
      EXPECT_EQ(with.steering, without.steering);
      EXPECT_EQ(with.rolling_radius, without.rolling_radius);
      ExpectUniqueAndContiguous(with);
      const auto names = with.Names(e.vehicle);
      EXPECT_EQ(names[static_cast<std::size_t>(with.accel_bias)], "bax_mps2");
      EXPECT_EQ(names.back(), "bay_mps2");
    }
  }
  // The AgriMaRo design (Danzi 2026) has 12 states.
  EXPECT_EQ(StateLayout::For(mapio::AgrimaroSwerveConfig(), false).size, 12);
  EXPECT_EQ(StateLayout::For(mapio::AgrimaroSwerveConfig(), true).size, 18);
  EXPECT_EQ(StateLayout::For(mapio::VineyardUgv4wsConfig(), true).size, 21);
  EXPECT_EQ(StateLayout::For(mapio::DifferentialDriveConfig(), true).size, 13);
  EXPECT_EQ(StateLayout::For(mapio::TrackedVehicleConfig(), true).size, 13);
}

TEST(StateLayout, IndicesAreUniqueAndContiguous) {
  for (const Expected& e : ShippedVehicles()) {
    for (bool slip : {false, true}) {
      SCOPED_TRACE(e.vehicle.name + (slip ? " slip-aware" : ""));
      const StateLayout layout = StateLayout::For(e.vehicle, slip);
      ExpectUniqueAndContiguous(layout);
      for (std::size_t i = 0; i < layout.wheel_count(); ++i) {
        EXPECT_EQ(layout.steering[i] >= 0, e.vehicle.wheels[i].steerable) << i;
        EXPECT_EQ(layout.rolling_radius[i] >= 0, slip) << i;
        EXPECT_EQ(layout.slip_compliance[i] >= 0, slip) << i;
        if (slip) {
          EXPECT_EQ(layout.slip_compliance[i], layout.rolling_radius[i] + 1) << i;
        }
      }
    }
  }
}

TEST(StateLayout, EveryCombinationOfOptionsIsContiguousAndTheGnssBiasComesLast) {
  for (const Expected& e : ShippedVehicles()) {
    for (int options = 0; options < 32; ++options) {
      const bool slip = options & 1, accel = options & 2, angles = options & 4, traction = options & 8,
                 gnss = options & 16;
      SCOPED_TRACE(e.vehicle.name + " options " + std::to_string(options));
      StateLayout::Options chosen{.slip_aware_odometry = slip, .accel_bias = accel, .wheel_angles = angles,
                                  .traction = traction, .gnss_bias = gnss};
      const StateLayout layout = StateLayout::For(e.vehicle, chosen);
      ExpectUniqueAndContiguous(layout);
      chosen.gnss_bias = false;
      const StateLayout without = StateLayout::For(e.vehicle, chosen);
      EXPECT_EQ(layout.gnss_bias, gnss ? without.size : -1);
      EXPECT_EQ(layout.size, without.size + (gnss ? 2 : 0));
      const std::vector<std::string> names = layout.Names(e.vehicle);
      if (gnss) {
        EXPECT_EQ(names[static_cast<std::size_t>(layout.gnss_bias)], "gnss_bias_east_m");
        EXPECT_EQ(names.back(), "gnss_bias_north_m");
      }
    }
  }
}

TEST(StateLayout, SteeringStatesFollowTheBaseInWheelOrder) {
  const StateLayout layout = StateLayout::For(mapio::VineyardUgv4wsConfig(), true);
  EXPECT_EQ(layout.steering, (std::vector<int>{9, 10, 11, 12}));
  EXPECT_EQ(layout.rolling_radius, (std::vector<int>{13, 15, 17, 19}));
  EXPECT_EQ(layout.slip_compliance, (std::vector<int>{14, 16, 18, 20}));
  const StateLayout tracked = StateLayout::For(mapio::TrackedVehicleConfig(), true);
  EXPECT_EQ(tracked.steering, (std::vector<int>{-1, -1}));
  EXPECT_EQ(tracked.rolling_radius, (std::vector<int>{9, 11}));
  EXPECT_EQ(tracked.slip_compliance, (std::vector<int>{10, 12}));
}

TEST(StateLayout, NamesOfTheSwerveRobot) {
  const mapio::VehicleConfig swerve = mapio::AgrimaroSwerveConfig();
  const std::vector<std::string> base = {"x_m",     "y_m",     "phi_rad", "vx_mps", "vy_mps",
                                         "r_radps", "ax_mps2", "ay_mps2", "bg_radps"};
  std::vector<std::string> expected = base;
  for (const char* wheel : {"left_front", "left_rear", "right"}) expected.push_back(std::string("delta_") + wheel);
  EXPECT_EQ(StateLayout::For(swerve, false).Names(swerve), expected);
  for (const char* wheel : {"left_front", "left_rear", "right"}) {
    expected.push_back(std::string("R_") + wheel);
    expected.push_back(std::string("kappa_") + wheel);
  }
  EXPECT_EQ(StateLayout::For(swerve, true).Names(swerve), expected);
}

TEST(StateLayout, NamesOfEveryVehicleAreUniqueAndNonEmpty) {
  for (const Expected& e : ShippedVehicles()) {
    for (bool slip : {false, true}) {
      SCOPED_TRACE(e.vehicle.name + (slip ? " slip-aware" : ""));
      const StateLayout layout = StateLayout::For(e.vehicle, slip);
      const std::vector<std::string> names = layout.Names(e.vehicle);
      ASSERT_EQ(names.size(), static_cast<std::size_t>(layout.size));
      EXPECT_EQ(std::set<std::string>(names.begin(), names.end()).size(), names.size());
      for (const std::string& name : names) EXPECT_FALSE(name.empty());
      for (std::size_t i = 0; i < layout.wheel_count(); ++i) {
        const std::string& wheel = e.vehicle.wheels[i].name;
        if (layout.steering[i] >= 0) {
          EXPECT_EQ(names[static_cast<std::size_t>(layout.steering[i])], "delta_" + wheel);
        }
        if (slip) {
          EXPECT_EQ(names[static_cast<std::size_t>(layout.rolling_radius[i])], "R_" + wheel);
          EXPECT_EQ(names[static_cast<std::size_t>(layout.slip_compliance[i])], "kappa_" + wheel);
        }
      }
    }
  }
  const mapio::VehicleConfig tracked = mapio::TrackedVehicleConfig();
  const auto names = StateLayout::For(tracked, true).Names(tracked);
  EXPECT_EQ(names[9], "R_left_track");
  EXPECT_EQ(names[12], "kappa_right_track");
}

}  // namespace
}  // namespace rowloc::localization
