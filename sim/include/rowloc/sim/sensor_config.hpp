// Named sensor error-model profiles as data (issue 3, Sensors): config/sensors.json
// holds one object per sensor kind, each mapping a profile name to its parameters:
//   { "gnss": { "gnss_rtk": {...}, "gnss_sbas": {...} }, "imu": { ... },
//     "wheel_encoder": { ... }, "steering_encoder": { ... } }
// Every key of a profile is required and unknown keys are rejected, so that a typo cannot
// silently fall back to a default. The in-code defaults below equal the shipped file (tested).
// Field meanings and units: gnss_model.hpp, imu_model.hpp, encoder_model.hpp and
// docs/simulation-sensors.md.
#pragma once

#include "rowloc/sim/encoder_model.hpp"
#include "rowloc/sim/gnss_model.hpp"
#include "rowloc/sim/imu_model.hpp"

#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>

namespace rowloc::sim {

struct SensorProfiles {
  std::map<std::string, GnssConfig> gnss;
  std::map<std::string, ImuConfig> imu;
  std::map<std::string, WheelEncoderConfig> wheel_encoder;
  std::map<std::string, SteeringEncoderConfig> steering_encoder;
  bool operator==(const SensorProfiles&) const = default;
};

/// A sensor file that cannot be read, parsed or validated. what() names the source, the key path
/// (e.g. "gnss.gnss_rtk.sigma_horizontal_m") and the reason.
class SensorConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Parses profiles from JSON text; source_name appears in error messages. Throws SensorConfigError.
SensorProfiles ParseSensorProfiles(std::string_view json_text, std::string_view source_name);

/// Reads and parses a profile file. Throws SensorConfigError (including for a missing file).
SensorProfiles LoadSensorProfiles(const std::filesystem::path& path);

/// The shipped profiles, in code (equal to config/sensors.json).
GnssConfig DefaultGnssRtkConfig();   ///< "gnss_rtk": RTK fixed, 0.01 m per axis
GnssConfig DefaultGnssSbasConfig();  ///< "gnss_sbas": SBAS, 0.6 m per axis
ImuConfig DefaultImuConfig();        ///< "imu_mems": consumer-grade MEMS IMU
WheelEncoderConfig DefaultWheelEncoderConfig();        ///< "wheel_encoder_1024"
/// "wheel_encoder_white": 2^24 ticks per revolution (speed step at 50 Hz 1.9e-5 rad/s, against
/// 0.31 rad/s at 1024 ticks), no low-pass, white Gaussian speed noise of 0.1 rad/s (the default
/// filter's wheel sigma). A control sensor: its speed error is what the filter's wheel model
/// assumes, so the innovations' whiteness shows the filter's own model error, apart from the
/// 1024-tick encoder's correlated quantization (docs/notes/2026-12-02-localization-filter.md §5.11).
WheelEncoderConfig WhiteWheelEncoderConfig();
SteeringEncoderConfig DefaultSteeringEncoderConfig();  ///< "steering_encoder_12bit"
SensorProfiles DefaultSensorProfiles();

/// Looks up a profile by name; throws SensorConfigError listing the known names if absent.
const GnssConfig& FindGnssProfile(const SensorProfiles& profiles, const std::string& name);
const ImuConfig& FindImuProfile(const SensorProfiles& profiles, const std::string& name);
const WheelEncoderConfig& FindWheelEncoderProfile(const SensorProfiles& profiles, const std::string& name);
const SteeringEncoderConfig& FindSteeringEncoderProfile(const SensorProfiles& profiles, const std::string& name);

}  // namespace rowloc::sim
