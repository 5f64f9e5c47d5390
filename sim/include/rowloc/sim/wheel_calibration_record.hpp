// The slip-aware odometry's calibration states of one wheel, as the estimate stream carries them
// (docs/protocol.md §3 `wheel_calibration`; the model is docs/localization-filter.md §4):
// rolling radius R_w and slip compliance kappa (slip per unit traction coefficient) with their
// standard deviations. Written by log_writers.hpp, read by trajectory_streams.hpp.
#pragma once

#include <string>

namespace rowloc::sim {

struct WheelCalibrationRecord {
  std::string wheel;
  double rolling_radius_m = 0.0;        ///< > 0
  double rolling_radius_sigma_m = 0.0;  ///< >= 0
  double slip_compliance = 0.0;         ///< kappa, slip per unit traction coefficient, >= 0
  double slip_compliance_sigma = 0.0;   ///< >= 0
};

}  // namespace rowloc::sim
