// The slip-aware odometry's calibration states of one wheel, as the estimate stream carries them
// (docs/protocol.md §3 `wheel_calibration`; the model is docs/localization-filter.md §4):
// rolling radius R_w and slip compliance kappa (slip per unit traction coefficient) with their
// standard deviations. Written by estimate_stream_writer.hpp, read by trajectory_streams.hpp, both
// with the keys and domains of kWheelCalibrationFields.
#pragma once

#include <array>
#include <string>

namespace rowloc::formats {

struct WheelCalibrationRecord {
  std::string wheel;
  double rolling_radius_m = 0.0;        ///< > 0
  double rolling_radius_sigma_m = 0.0;  ///< >= 0
  double slip_compliance = 0.0;         ///< kappa, slip per unit traction coefficient, >= 0
  double slip_compliance_sigma = 0.0;   ///< >= 0
};

/// One number of the record: its key in the stream and its domain (finite, and > 0 if `positive`,
/// else >= 0).
struct WheelCalibrationField {
  const char* key;
  double WheelCalibrationRecord::*member;
  bool positive;

  bool InDomain(double value) const { return positive ? value > 0.0 : value >= 0.0; }
  const char* DomainText() const { return positive ? "must be > 0" : "must be >= 0"; }
};

/// The four numbers, in the stream's order.
inline constexpr std::array<WheelCalibrationField, 4> kWheelCalibrationFields{{
    {"rolling_radius_m", &WheelCalibrationRecord::rolling_radius_m, true},
    {"rolling_radius_sigma_m", &WheelCalibrationRecord::rolling_radius_sigma_m, false},
    {"slip_compliance", &WheelCalibrationRecord::slip_compliance, false},
    {"slip_compliance_sigma", &WheelCalibrationRecord::slip_compliance_sigma, false},
}};

}  // namespace rowloc::formats
