// Simulation scenarios as data (issue 3, "Logs, scenarios, command line"): one JSON file
// under config/scenarios/ names the world (or an open field), the vehicle, the terrain under it,
// the route it drives and its sensors with their error profiles. Format and the shipped scenarios:
// docs/simulation-scenarios.md.
//
// Rules (as every simulator data file): every key is required (null where a part is absent),
// unknown keys are rejected, numbers are finite, and every error names the scenario file, the key
// path and the reason (errors of a referenced file are prefixed with the scenario's key that
// references it). Paths inside a scenario are relative to the scenario file.
//
// A scenario may be a variant of another: "extends": "base.json" (a path relative to the file)
// reads the base and merges the file onto it key by key (mapio/config_overlay.hpp: objects merge,
// any other value, arrays and null included, replaces). The file then states only what differs
// (the `*-white-encoder` whiteness controls: name, description, the wheel encoder's profile and
// their filter file). Paths a base states keep naming the files the base meant, also when the
// base lies in another directory. The rules of the merged document are the rules above; its errors
// name the file that was asked for.
#pragma once

#include "rowloc/geometry/row_map.hpp"
#include "rowloc/sim/encoder_model.hpp"
#include "rowloc/sim/gnss_model.hpp"
#include "rowloc/sim/imu_model.hpp"
#include "rowloc/sim/route.hpp"
#include "rowloc/sim/sensor_faults.hpp"
#include "rowloc/sim/row_world.hpp"
#include "rowloc/sim/terrain.hpp"
#include "rowloc/sim/terrain_map.hpp"
#include "rowloc/sim/ultrasonic_model.hpp"
#include "rowloc/sim/vehicle_config.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace rowloc::sim {

class ScenarioError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct GnssScenario {
  std::string profile;               ///< name in the sensor profiles
  GnssConfig config;                 ///< the profile's parameters
  std::optional<double> off_after_s; ///< no GNSS message after this time (Lindgren et al. 2002: fixes stop at 50 s)
};

struct UltrasonicScenario {
  double rate_hz = 10.0;             ///< pings per second of each sensor, in (0, 1000]
  std::vector<SensorMount> mounts;   ///< body frame; position z = height above the terrain
  UltrasonicParams params;
};

struct TorqueScenario {
  double noise_sigma_nm = 0.0;       ///< white noise on each wheel torque reading, >= 0
};

struct VioScenario {
  double rate_hz = 10.0;             ///< in (0, 1000]
  double sigma_mps = 0.02;           ///< per-axis white noise of the camera velocity, > 0
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  ///< camera lever arm, body frame
};

struct Scenario {
  std::string name;
  std::string description;
  std::uint64_t seed = 0;
  std::optional<RowWorldParams> world;  ///< absent: an open field
  geometry::GeoOrigin origin;           ///< the world's origin, or the scenario's for an open field
  VehicleConfig vehicle;
  TerrainSlipTable terrains;
  TerrainMap terrain_map;
  RouteSpec route;
  double truth_rate_hz = 50.0;          ///< in (0, 10000]
  double row_map_height_m = 1.0;        ///< slice height of the written true row map (world only)
  std::optional<GnssScenario> gnss;
  ImuConfig imu;
  WheelEncoderConfig wheel_encoder;
  std::optional<SteeringEncoderConfig> steering_encoder;  ///< must be absent for non-steering kinds
  std::optional<TorqueScenario> torque;
  std::optional<UltrasonicScenario> ultrasonic;           ///< requires a world
  std::optional<VioScenario> vio;
  /// "filters" (optional): filter files the scenario is meant to be measured with besides
  /// config/filters/default.json, resolved against the scenario's directory; each must be a file.
  /// scripts/validate-sim replays each (docs/simulation-scenarios.md). Their content is the
  /// localization's to check (`rowloc replay` parses them); the simulator only references them.
  std::vector<std::filesystem::path> filter_files;
  /// "faults" (optional): sensor faults to inject (sensor_faults.hpp); none by default.
  SensorFaults faults;
};

/// Parses scenario text; relative file references resolve against base_directory, and source_name
/// prefixes every error. Throws ScenarioError.
Scenario ParseScenario(std::string_view json_text, std::string_view source_name,
                       const std::filesystem::path& base_directory);
/// Reads and parses a scenario file. Throws ScenarioError (including for a missing file).
Scenario LoadScenario(const std::filesystem::path& path);

/// The document LoadScenario reads for `path`: the file merged onto the files it extends, as
/// JSON (two-space indent, keys sorted, a final newline). `rowloc config show --scenario` prints
/// it. Throws ScenarioError.
std::string ExpandedScenarioJson(const std::filesystem::path& path);

}  // namespace rowloc::sim
