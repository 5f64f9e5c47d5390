// Parsing, validation and the in-code shipped values of vehicle configurations (format in
// vehicle_config.hpp; values and their sources in docs/simulation-vehicles.md).
#include "rowloc/mapio/vehicle_config.hpp"

#include "rowloc/mapio/detail/json_object_reader.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <set>
#include <utility>

namespace rowloc::mapio {
namespace {

using Reader = detail::JsonObjectReader<VehicleConfigError>;
using Limits = VehicleConfigLimits;
using nlohmann::json;

constexpr std::array<std::pair<VehicleKind, std::string_view>, 4> kKindNames = {{
    {VehicleKind::kSwerveDrive, "swerve_drive"},
    {VehicleKind::kFourWheelSteer, "four_wheel_steer"},
    {VehicleKind::kDifferentialDrive, "differential_drive"},
    {VehicleKind::kSkidSteer, "skid_steer"},
}};

/// Tolerance (metres) for "same axle" / "symmetric tracks" geometry checks.
constexpr double kGeometryToleranceM = 1e-9;

bool IsPositive(double value) { return std::isfinite(value) && value > 0.0; }

/// A number for messages, "%g" (6 significant digits): never hundreds of digits.
std::string FormatShort(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

std::optional<std::string> MountProblem(const SensorMount& mount, const std::string& what) {
  if (mount.name.empty()) return what + ".name must not be empty";
  if (!mount.position_m.allFinite()) return what + ".position_m must be finite";
  if (!std::isfinite(mount.yaw_rad)) return what + ".yaw_rad must be finite";
  return std::nullopt;
}

std::optional<std::string> WheelListProblem(const std::vector<WheelGeometry>& wheels) {
  std::set<std::string> names;
  for (std::size_t i = 0; i < wheels.size(); ++i) {
    const WheelGeometry& wheel = wheels[i];
    const std::string where = "wheels[" + std::to_string(i) + "]";
    if (wheel.name.empty()) return where + ".name must not be empty";
    if (!names.insert(wheel.name).second) return where + ".name \"" + wheel.name + "\" is used twice";
    if (!wheel.position_m.allFinite()) return where + ".position_m must be finite";
    if (!IsPositive(wheel.nominal_radius_m)) return where + ".nominal_radius_m must be finite and > 0";
  }
  return std::nullopt;
}

std::optional<std::string> SteeredKindProblem(const VehicleConfig& config) {
  const bool swerve = config.kind == VehicleKind::kSwerveDrive;
  if (swerve && config.wheels.size() < 3) return std::string("swerve_drive needs at least 3 wheels");
  if (!swerve && config.wheels.size() != 4) return std::string("four_wheel_steer needs exactly 4 wheels");
  for (std::size_t i = 0; i < config.wheels.size(); ++i) {
    if (!config.wheels[i].steerable) {
      return "wheels[" + std::to_string(i) + "].steerable must be true for " +
             std::string(VehicleKindName(config.kind));
    }
  }
  if (!(config.max_steering_angle_rad > 0.0 && config.max_steering_angle_rad <= std::numbers::pi)) {
    return std::string("max_steering_angle_rad must be in (0, pi]");
  }
  if (config.tracks) return std::string("tracks must be null for ") + std::string(VehicleKindName(config.kind));
  return std::nullopt;
}

std::optional<std::string> FixedPairProblem(const VehicleConfig& config) {
  const std::string kind(VehicleKindName(config.kind));
  if (config.wheels.size() != 2) return kind + " needs exactly 2 " + (config.tracks ? "tracks" : "wheels");
  for (std::size_t i = 0; i < 2; ++i) {
    if (config.wheels[i].steerable) return "wheels[" + std::to_string(i) + "].steerable must be false for " + kind;
  }
  const Eigen::Vector2d& a = config.wheels[0].position_m;
  const Eigen::Vector2d& b = config.wheels[1].position_m;
  if (std::abs(a.x() - b.x()) > kGeometryToleranceM) return kind + ": both wheels must have the same x (one axle)";
  if (std::abs(a.y() - b.y()) <= kGeometryToleranceM) return kind + ": the two wheels must have different y";
  if (config.kind == VehicleKind::kDifferentialDrive) {
    if (config.tracks) return std::string("tracks must be null for differential_drive");
    return std::nullopt;
  }
  if (std::abs(a.y() + b.y()) > kGeometryToleranceM) {
    return std::string("skid_steer: the tracks must lie at y = +B/2 and -B/2 (reference point midway)");
  }
  if (!config.tracks) return std::string("skid_steer needs \"tracks\"");
  if (!IsPositive(config.tracks->contact_length_m)) {
    return std::string("tracks.contact_length_m must be finite and > 0");
  }
  const double mu_t = config.tracks->turning_resistance_coefficient;
  if (!(std::isfinite(mu_t) && mu_t >= 0.0)) {
    return std::string("tracks.turning_resistance_coefficient must be finite and >= 0");
  }
  return std::nullopt;
}

/// A number in [low, high] (its physical domain); the message prints numbers with "%g".
double NumberIn(Reader& reader, const std::string& key, double low, double high) {
  const double number = reader.Number(key);
  if (number < low || number > high) {
    reader.Fail(reader.Key(key), "must be in [" + FormatShort(low) + ", " + FormatShort(high) + "], got " +
                                     FormatShort(number));
  }
  return number;
}

/// A name of at most Limits::kMaxNameBytes bytes (emptiness is checked by VehicleConfigProblem).
std::string ReadName(Reader& reader, const std::string& key) {
  std::string name = reader.String(key);
  if (name.size() > Limits::kMaxNameBytes) {
    reader.Fail(reader.Key(key), "longer than " + std::to_string(Limits::kMaxNameBytes) + " bytes");
  }
  return name;
}

/// A body-frame position, every coordinate in [-kMaxAbsPositionM, kMaxAbsPositionM].
template <int N>
Eigen::Matrix<double, N, 1> ReadPosition(Reader& reader, const std::string& key) {
  const Eigen::Matrix<double, N, 1> position = reader.Vector<N>(key);
  for (int i = 0; i < N; ++i) {
    if (std::abs(position[i]) > Limits::kMaxAbsPositionM) {
      reader.Fail(reader.Key(key) + "[" + std::to_string(i) + "]",
                  "must be in [-" + FormatShort(Limits::kMaxAbsPositionM) + ", " + FormatShort(Limits::kMaxAbsPositionM) +
                      "], got " + FormatShort(position[i]));
    }
  }
  return position;
}

SensorMount ReadMount(Reader reader) {
  SensorMount mount;
  mount.name = ReadName(reader, "name");
  mount.position_m = ReadPosition<3>(reader, "position_m");
  mount.yaw_rad = NumberIn(reader, "yaw_rad", -std::numbers::pi, std::numbers::pi);
  reader.RejectUnknownKeys();
  return mount;
}

WheelGeometry ReadWheel(Reader reader) {
  WheelGeometry wheel;
  wheel.name = ReadName(reader, "name");
  wheel.position_m = ReadPosition<2>(reader, "position_m");
  wheel.nominal_radius_m = NumberIn(reader, "nominal_radius_m", Limits::kMinWheelRadiusM, Limits::kMaxWheelRadiusM);
  wheel.steerable = reader.Bool("steerable");
  reader.RejectUnknownKeys();
  return wheel;
}

TrackParameters ReadTracks(Reader reader) {
  TrackParameters tracks;
  tracks.contact_length_m =
      NumberIn(reader, "contact_length_m", Limits::kMinTrackContactLengthM, Limits::kMaxTrackContactLengthM);
  tracks.turning_resistance_coefficient =
      NumberIn(reader, "turning_resistance_coefficient", 0.0, Limits::kMaxTurningResistanceCoefficient);
  reader.RejectUnknownKeys();
  return tracks;
}

VehicleConfig ReadConfig(Reader& root) {
  VehicleConfig config;
  config.name = ReadName(root, "name");
  const std::string kind = root.String("kind");
  const auto parsed_kind = VehicleKindFromName(kind);
  if (!parsed_kind) {
    root.Fail("kind", "must be one of \"swerve_drive\", \"four_wheel_steer\", \"differential_drive\", "
                      "\"skid_steer\", got \"" + kind + "\"");
  }
  config.kind = *parsed_kind;
  config.mass_kg = NumberIn(root, "mass_kg", Limits::kMinMassKg, Limits::kMaxMassKg);
  config.max_steering_angle_rad = NumberIn(root, "max_steering_angle_rad", 0.0, Limits::kMaxSteeringAngleRad);
  config.wheels = root.ObjectArray("wheels", ReadWheel, 1, Limits::kMaxWheels);
  if (!root.IsNull("tracks")) config.tracks = ReadTracks(root.Object("tracks"));
  config.gnss_antenna = ReadMount(root.Object("gnss_antenna"));
  config.imu = ReadMount(root.Object("imu"));
  config.ultrasonic = root.ObjectArray("ultrasonic", ReadMount, 0, Limits::kMaxUltrasonicSensors);
  return config;
}

/// The optional "recommended_filter": a non-empty string (a path, resolved by the caller).
std::optional<std::string> ReadRecommendedFilter(Reader& root) {
  if (!root.Has("recommended_filter")) return std::nullopt;
  std::string value = root.String("recommended_filter");
  if (value.empty()) {
    root.Fail(root.Key("recommended_filter"), "must name a filter file (a path relative to the vehicle file)");
  }
  return value;
}

/// The vehicle and the text of its recommended filter: every key read, unknown ones refused, the
/// configuration checked.
std::pair<VehicleConfig, std::optional<std::string>> ParseDocument(std::string_view json_text, const std::string& source) {
  const json document = detail::ParseJsonText<VehicleConfigError>(json_text, source);
  Reader root(document, source, "");
  VehicleConfig config = ReadConfig(root);
  std::optional<std::string> recommended = ReadRecommendedFilter(root);
  root.RejectUnknownKeys();
  if (const auto problem = VehicleConfigProblem(config)) throw VehicleConfigError(source + ": " + *problem);
  return {std::move(config), std::move(recommended)};
}

}  // namespace

std::string_view VehicleKindName(VehicleKind kind) {
  for (const auto& [k, name] : kKindNames) {
    if (k == kind) return name;
  }
  return "unknown";
}

std::optional<VehicleKind> VehicleKindFromName(std::string_view name) {
  for (const auto& [kind, text] : kKindNames) {
    if (text == name) return kind;
  }
  return std::nullopt;
}

std::optional<std::string> VehicleConfigProblem(const VehicleConfig& config) {
  if (config.name.empty()) return std::string("name must not be empty");
  if (!IsPositive(config.mass_kg)) return std::string("mass_kg must be finite and > 0");
  if (!std::isfinite(config.max_steering_angle_rad)) return std::string("max_steering_angle_rad must be finite");
  if (auto problem = WheelListProblem(config.wheels)) return problem;
  const bool steered = config.kind == VehicleKind::kSwerveDrive || config.kind == VehicleKind::kFourWheelSteer;
  if (auto problem = steered ? SteeredKindProblem(config) : FixedPairProblem(config)) return problem;
  if (auto problem = MountProblem(config.gnss_antenna, "gnss_antenna")) return problem;
  if (auto problem = MountProblem(config.imu, "imu")) return problem;
  std::set<std::string> names;
  for (std::size_t i = 0; i < config.ultrasonic.size(); ++i) {
    const std::string where = "ultrasonic[" + std::to_string(i) + "]";
    if (auto problem = MountProblem(config.ultrasonic[i], where)) return problem;
    if (!names.insert(config.ultrasonic[i].name).second) return where + ".name is used twice";
  }
  return std::nullopt;
}

VehicleConfig ParseVehicleConfig(std::string_view json_text, std::string_view source_name) {
  return ParseDocument(json_text, std::string(source_name)).first;
}

VehicleConfig LoadVehicleConfig(const std::filesystem::path& path) {
  return ParseVehicleConfig(detail::ReadTextFile<VehicleConfigError>(path, "vehicle file"), path.string());
}

VehicleFile ParseVehicleFile(std::string_view json_text, const std::filesystem::path& path) {
  auto [vehicle, recommended] = ParseDocument(json_text, path.string());
  VehicleFile file{std::move(vehicle), std::nullopt};
  if (recommended) {
    const std::filesystem::path named(*recommended);
    file.recommended_filter = named.is_absolute() ? named : path.parent_path() / named;
  }
  return file;
}

VehicleFile LoadVehicleFile(const std::filesystem::path& path) {
  return ParseVehicleFile(detail::ReadTextFile<VehicleConfigError>(path, "vehicle file"), path);
}

// ---- shipped configurations (equal to config/vehicles/*.json; sources in docs/simulation-vehicles.md)

VehicleConfig AgrimaroSwerveConfig() {
  VehicleConfig c;
  c.name = "agrimaro-swerve";
  c.kind = VehicleKind::kSwerveDrive;
  c.mass_kg = 80.0;
  c.max_steering_angle_rad = std::numbers::pi;  // slip ring: unlimited steering (Danzi 2026 §2.2.2)
  c.wheels = {{"left_front", {0.5, 0.0}, 0.165, true},
              {"left_rear", {-0.5, 0.0}, 0.165, true},
              {"right", {0.0, -0.8}, 0.165, true}};
  c.gnss_antenna = {"gnss", {0.0, -0.4, 1.2}, 0.0};
  c.imu = {"imu", {0.0, 0.0, 0.0}, 0.0};
  return c;
}

VehicleConfig VineyardUgv4wsConfig() {
  constexpr double kHalfPi = std::numbers::pi / 2.0;
  VehicleConfig c;
  c.name = "vineyard-ugv-4ws";
  c.kind = VehicleKind::kFourWheelSteer;
  c.mass_kg = 120.0;
  c.max_steering_angle_rad = 1.0;
  c.wheels = {{"front_left", {0.5, 0.4}, 0.254, true},
              {"front_right", {0.5, -0.4}, 0.254, true},
              {"rear_left", {-0.5, 0.4}, 0.254, true},
              {"rear_right", {-0.5, -0.4}, 0.254, true}};
  c.gnss_antenna = {"gnss", {0.0, 0.0, 1.2}, 0.0};
  c.imu = {"imu", {0.0, 0.0, 0.25}, 0.0};
  c.ultrasonic = {{"us_front_left", {0.75, 0.5, 0.5}, kHalfPi},
                  {"us_rear_left", {-0.75, 0.5, 0.5}, kHalfPi},
                  {"us_front_right", {0.75, -0.5, 0.5}, -kHalfPi},
                  {"us_rear_right", {-0.75, -0.5, 0.5}, -kHalfPi}};
  return c;
}

VehicleConfig DifferentialDriveConfig() {
  VehicleConfig c;
  c.name = "differential";
  c.kind = VehicleKind::kDifferentialDrive;
  c.mass_kg = 50.0;
  c.max_steering_angle_rad = 0.0;
  c.wheels = {{"left", {0.0, 0.28}, 0.165, false}, {"right", {0.0, -0.28}, 0.165, false}};
  c.gnss_antenna = {"gnss", {-0.1, 0.0, 0.6}, 0.0};
  c.imu = {"imu", {0.0, 0.0, 0.2}, 0.0};
  return c;
}

VehicleConfig TrackedVehicleConfig() {
  VehicleConfig c;
  c.name = "tracked";
  c.kind = VehicleKind::kSkidSteer;
  c.mass_kg = 600.0;
  c.max_steering_angle_rad = 0.0;
  c.wheels = {{"left_track", {0.0, 0.55}, 0.15, false}, {"right_track", {0.0, -0.55}, 0.15, false}};
  c.tracks = TrackParameters{1.0, 0.3};
  c.gnss_antenna = {"gnss", {0.0, 0.0, 1.5}, 0.0};
  c.imu = {"imu", {0.0, 0.0, 0.4}, 0.0};
  return c;
}

}  // namespace rowloc::mapio
