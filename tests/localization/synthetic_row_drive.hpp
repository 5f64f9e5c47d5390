// A synthetic drive along a straight lane for the ranger mount tests (ranger_mount_fit_test.cpp,
// ranger_mount_monitor_test.cpp): two straight canopies, four side rangers, exact echoes from the
// true mounts, and a reference trajectory with a slowly varying error as GNSS leaves it.
#pragma once

#include "rowloc/localization/map_aided_ranging.hpp"
#include "rowloc/localization/ranger_mount_fit.hpp"

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

namespace rowloc::localization::test {

/// Two straight closed rows along x (canopies 0.4 m wide at y = 0 and 2.5 m, 50 m long): the
/// range model of the map-aided update is exact on them (no smoothing of a curved outline).
inline geometry::RowMap StraightRows() {
  geometry::RowMap map;
  map.origin = {45.0, 7.0, 200.0};
  for (const double y : {0.0, 2.5}) {
    geometry::Row row;
    row.id = "row-" + std::to_string(map.rows.size() + 1);
    row.closed = true;
    row.points_m = {{0.0, y - 0.2}, {50.0, y - 0.2}, {50.0, y + 0.2}, {0.0, y + 0.2}};
    map.rows.push_back(row);
  }
  return map;
}

constexpr double kCone = 0.1309;  // rad, the shipped rangers' half aperture

/// Four side-looking rangers 0.75 m ahead of and behind the reference point, 0.5 m out.
inline std::vector<mapio::SensorMount> Rangers() {
  const double left = std::numbers::pi / 2;
  return {{"us_front_left", {0.75, 0.5, 0.5}, left},
          {"us_rear_left", {-0.75, 0.5, 0.5}, left},
          {"us_front_right", {0.75, -0.5, 0.5}, -left},
          {"us_rear_right", {-0.75, -0.5, 0.5}, -left}};
}

struct SyntheticDrive {
  std::vector<ReferenceKnot> reference;  ///< truth + ReferenceError, with the body rates
  std::vector<ReferenceKnot> truth;
  std::vector<EchoRecord> echoes;
};

/// The reference's error at time t: 4-6 cm across, 8 mrad in heading, drifting over tens of seconds.
inline Eigen::Vector3d ReferenceError(double t) {
  return {0.3 * std::sin(0.02 * t), 0.05 + 0.01 * std::sin(0.05 * t), 0.008 * std::cos(0.03 * t)};
}

/// 0.5 m/s along the lane's centre (y = 1.25) from x = 2 to 48 m, weaving +-5 cm; the reference is
/// the truth plus an error of 4-6 cm across and 8 mrad in heading that drifts over tens of seconds.
/// Every ranger echoes at every knot (0.2 s), from its true mount, exactly.
inline SyntheticDrive Drive(const RowMapRanging& ranging, const std::vector<mapio::SensorMount>& truth) {
  SyntheticDrive d;
  for (double t = 0.0; 2.0 + 0.5 * t <= 48.0; t += 0.2) {
    const double weave = 0.05 * std::sin(0.1 * t);
    const Eigen::Vector3d pose(2.0 + 0.5 * t, 1.25 + weave, std::atan2(0.05 * 0.1 * std::cos(0.1 * t), 0.5));
    const double yaw_rate = -0.05 * 0.1 * 0.1 * std::sin(0.1 * t) / 0.5;  // d/dt of the weave's course, small
    d.reference.push_back({t, pose + ReferenceError(t), Eigen::Vector3d(0.5, 0.0, yaw_rate)});
    d.truth.push_back({t, pose, Eigen::Vector3d(0.5, 0.0, yaw_rate)});
    for (std::size_t i = 0; i < truth.size(); ++i) {
      const RangeSensorMount mount{truth[i].position_m.head<2>(), truth[i].yaw_rad, kCone};
      const auto candidates = ranging.Candidates(pose, mount, 4.0, 0.01);
      if (!candidates.empty()) d.echoes.push_back({t, i, candidates.front().predicted_range_m});
    }
  }
  return d;
}

}  // namespace rowloc::localization::test
