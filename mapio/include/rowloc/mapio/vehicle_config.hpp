// Shared by the simulator (sim) and the filter (localization): lives in mapio, the file-format
// library both may depend on.
// Vehicle configurations as data (issue 3, "Vehicles and motion"; the design's "Vehicle models
// (configured by a file, not recompiled)"; body frame: x forward, y left, z up, origin at the
// vehicle reference point).
//
// Four kinds (docs/simulation-vehicles.md gives the geometry of each shipped file and its source):
//   swerve_drive        >= 3 independently steered and driven wheels (AgriMaRo, Danzi 2026 §2.3, eq. 2.3)
//   four_wheel_steer    4 steered and driven wheels (vineyard UGV, Donati 2021 Tables 5.1 and 5.5)
//   differential_drive  2 fixed driven wheels on a common axle (Tazzari et al. n.d. eq. (2), the "DWR")
//   skid_steer          2 tracks (Tazzari et al. n.d. eqs. (3)-(7)); WheelGeometry describes a track: its centre
//                       line position and its sprocket radius; `tracks` holds contact length and
//                       Wong's turning-resistance coefficient.
//
// File format (config/vehicles/*.json): every key required, unknown keys rejected, errors name the
// source, the key path (e.g. "wheels[1].nominal_radius_m") and the reason:
//   { "name": str, "kind": "swerve_drive" | "four_wheel_steer" | "differential_drive" | "skid_steer",
//     "mass_kg": num, "max_steering_angle_rad": num,
//     "wheels": [ {"name": str, "position_m": [x, y], "nominal_radius_m": num, "steerable": bool}, ... ],
//     "tracks": null | {"contact_length_m": num, "turning_resistance_coefficient": num},
//     "gnss_antenna": mount, "imu": mount, "ultrasonic": [mount, ...],
//     "recommended_filter": str (optional) }
//   mount = {"name": str, "position_m": [x, y, z], "yaw_rad": num}
// recommended_filter names the filter file (config/filters/*.json, a path relative to the vehicle
// file) with the best known settings for the vehicle: `rowloc replay` without --filter and a
// service session opened without a filter use it (docs/localization-filter.md §3). It is not part
// of VehicleConfig (the vehicle's physics): LoadVehicleFile returns it, resolved.
// The in-code configurations (AgrimaroSwerveConfig() ...) equal the shipped files (tested).
#pragma once

#include <Eigen/Core>

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace rowloc::mapio {

enum class VehicleKind { kSwerveDrive, kFourWheelSteer, kDifferentialDrive, kSkidSteer };

/// "swerve_drive", "four_wheel_steer", "differential_drive", "skid_steer" (the JSON values).
std::string_view VehicleKindName(VehicleKind kind);
/// Inverse of VehicleKindName; nullopt for an unknown name.
std::optional<VehicleKind> VehicleKindFromName(std::string_view name);

/// One wheel (or one track for kSkidSteer).
struct WheelGeometry {
  std::string name;             ///< e.g. "front", "rear_left", "left_track"
  Eigen::Vector2d position_m;   ///< body frame: x forward, y left, origin = vehicle reference point
  double nominal_radius_m;      ///< wheel radius (sprocket radius for a track), > 0
  bool steerable;               ///< swerve / 4WS wheels
  bool operator==(const WheelGeometry&) const = default;
};

/// Lever arm of a sensor.
struct SensorMount {
  std::string name;             ///< e.g. "us_front_left"
  Eigen::Vector3d position_m;   ///< body frame, metres (z up from the reference point)
  double yaw_rad = 0.0;         ///< sensor axis direction in the body frame (from +x, ccw); 0 for GNSS/IMU
  bool operator==(const SensorMount&) const = default;
};

/// Track data of a skid-steer vehicle (Tazzari et al. n.d. eq. (7): l; Wong, Theory of Ground Vehicles §7.2:
/// turning-resistance moment M_r = mu_t m g l / 4 for a uniform track pressure).
struct TrackParameters {
  double contact_length_m = 0.0;                ///< l > 0: track-ground contact length
  double turning_resistance_coefficient = 0.0;  ///< mu_t >= 0: lateral resistance coefficient
  bool operator==(const TrackParameters&) const = default;
};

struct VehicleConfig {
  std::string name;
  VehicleKind kind = VehicleKind::kSwerveDrive;
  double mass_kg = 0.0;                  ///< whole vehicle; carried equally by the wheels (see vehicle_model.hpp)
  double max_steering_angle_rad = 0.0;   ///< |delta| limit in (0, pi]; ignored by non-steering kinds
  std::vector<WheelGeometry> wheels;
  std::optional<TrackParameters> tracks; ///< required for kSkidSteer, absent otherwise
  SensorMount gnss_antenna;
  SensorMount imu;
  std::vector<SensorMount> ultrasonic;   ///< may be empty
  bool operator==(const VehicleConfig&) const = default;
};

/// Physical domains of the values of a vehicle file, refused at load with the key path and the
/// range (docs/simulation-vehicles.md, "Value domains"): wide enough for any field robot or
/// tractor, narrow enough that no product of them overflows or stalls the models (a wheel radius of
/// 1e300 made a replay abort without naming a key, issue 26).
struct VehicleConfigLimits {
  static constexpr double kMinMassKg = 0.1;
  static constexpr double kMaxMassKg = 1e5;                  ///< 100 t
  static constexpr double kMaxSteeringAngleRad = 3.141592653589793;  ///< pi
  static constexpr double kMaxAbsPositionM = 50.0;           ///< every body-frame coordinate
  static constexpr double kMinWheelRadiusM = 0.005;
  static constexpr double kMaxWheelRadiusM = 5.0;
  static constexpr double kMinTrackContactLengthM = 0.01;
  static constexpr double kMaxTrackContactLengthM = 20.0;
  static constexpr double kMaxTurningResistanceCoefficient = 10.0;
  static constexpr std::size_t kMaxWheels = 16;              ///< wheels (or tracks) per vehicle
  static constexpr std::size_t kMaxUltrasonicSensors = 64;
  static constexpr std::size_t kMaxNameBytes = 256;          ///< vehicle, wheel and sensor names
};

/// A vehicle file that cannot be read, parsed or validated: what() names the source, the key path
/// and the reason.
class VehicleConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Why the configuration is unusable (naming the field), or nullopt. Checks: finite positive mass;
/// steering limit in (0, pi] for steering kinds; per kind the wheel count and `steerable` flags
/// (swerve >= 3 steerable, 4WS exactly 4 steerable, differential 2 fixed wheels on one axle
/// (same x, distinct y), skid steer 2 fixed tracks at y = +-B/2 with the same x and `tracks` given);
/// unique non-empty wheel and ultrasonic names; finite positions; radii > 0.
std::optional<std::string> VehicleConfigProblem(const VehicleConfig& config);

/// Parses a vehicle file's text; source_name appears in the messages. Throws VehicleConfigError.
VehicleConfig ParseVehicleConfig(std::string_view json_text, std::string_view source_name);
/// Reads and parses a vehicle file. Throws VehicleConfigError (including for a missing file).
VehicleConfig LoadVehicleConfig(const std::filesystem::path& path);

/// What a vehicle file holds: the vehicle, and the filter file recommended for it.
struct VehicleFile {
  VehicleConfig vehicle;
  /// "recommended_filter", resolved against the vehicle file's directory (unless absolute); nullopt
  /// when the file names none. Not opened here: its reader is the filter's (LoadFilterConfig).
  std::optional<std::filesystem::path> recommended_filter;
};

/// Parses the text of the vehicle file at `path` (already read by the caller). Throws
/// VehicleConfigError.
VehicleFile ParseVehicleFile(std::string_view json_text, const std::filesystem::path& path);
/// Reads and parses a vehicle file with its recommended filter. Throws VehicleConfigError.
VehicleFile LoadVehicleFile(const std::filesystem::path& path);

/// The shipped configurations, in code (equal to config/vehicles/<name>.json, tested).
VehicleConfig AgrimaroSwerveConfig();    ///< "agrimaro-swerve"
VehicleConfig VineyardUgv4wsConfig();    ///< "vineyard-ugv-4ws"
VehicleConfig DifferentialDriveConfig(); ///< "differential"
VehicleConfig TrackedVehicleConfig();    ///< "tracked"

}  // namespace rowloc::mapio
