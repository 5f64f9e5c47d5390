#include "rowloc/sim/scenario.hpp"

#include "rowloc/mapio/config_overlay.hpp"
#include "rowloc/mapio/detail/json_object_reader.hpp"
#include "rowloc/sim/route_builders.hpp"
#include "rowloc/sim/sensor_config.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <set>
#include <string>
#include <system_error>

namespace rowloc::sim {
namespace {

using Reader = mapio::detail::JsonObjectReader<ScenarioError>;
using json = nlohmann::json;

constexpr double kDegToRad = std::numbers::pi / 180.0;

/// Runs a loader of a referenced file; its errors become ScenarioErrors that name the scenario and
/// the key that references the file (the inner message names the file, its key and the reason).
template <typename Loader>
auto Referenced(const Reader& reader, const std::string& key, Loader&& load) {
  try {
    return load();
  } catch (const ScenarioError&) {
    throw;
  } catch (const std::exception& e) {
    reader.Fail(reader.Key(key), e.what());
  }
}

/// Runs a parser of a part of the scenario's own text whose errors already name the scenario and
/// the full key path ("<scenario>: route.length_m: missing key"): rethrown unchanged.
template <typename Parser>
auto Inline(Parser&& parse) {
  try {
    return parse();
  } catch (const ScenarioError&) {
    throw;
  } catch (const std::exception& e) {
    throw ScenarioError(e.what());
  }
}

std::filesystem::path FilePath(Reader& reader, const std::string& key, const std::filesystem::path& base) {
  const std::string text = reader.String(key);
  if (text.empty()) reader.Fail(reader.Key(key), "must name a file");
  const std::filesystem::path path(text);
  return path.is_absolute() ? path : base / path;
}

geometry::GeoOrigin ReadOrigin(Reader reader) {
  geometry::GeoOrigin origin;
  origin.latitude_deg = reader.NumberIn("latitude_deg", -90.0, 90.0);
  origin.longitude_deg = reader.NumberIn("longitude_deg", -180.0, 180.0);
  origin.altitude_m = reader.NumberIn("altitude_m", -1e4, 1e5);
  reader.RejectUnknownKeys();
  return origin;
}

SensorMount ReadMountObject(Reader reader) {
  SensorMount mount;
  mount.name = reader.String("name");
  if (mount.name.empty()) reader.Fail(reader.Key("name"), "must not be empty");
  mount.position_m = reader.Vector<3>("position_m");
  mount.yaw_rad = reader.NumberIn("yaw_deg", -360.0, 360.0) * kDegToRad;
  reader.RejectUnknownKeys();
  return mount;
}

/// `mounts`: null (all of the vehicle's), or names of the vehicle's sensors and/or mount objects.
std::vector<SensorMount> ReadMounts(Reader& reader, const VehicleConfig& vehicle) {
  const json& value = reader.Value("mounts");
  const std::string key = reader.Key("mounts");
  if (value.is_null()) {
    if (vehicle.ultrasonic.empty()) reader.Fail(key, "null (all of the vehicle's) but the vehicle has none");
    return vehicle.ultrasonic;
  }
  if (!value.is_array() || value.empty()) reader.Fail(key, "must be null or a non-empty array");
  std::vector<SensorMount> mounts;
  std::set<std::string> names;
  for (std::size_t i = 0; i < value.size(); ++i) {
    const std::string item_key = key + "[" + std::to_string(i) + "]";
    const json& item = value[i];
    if (item.is_string()) {
      const auto it = std::find_if(vehicle.ultrasonic.begin(), vehicle.ultrasonic.end(),
                                   [&](const SensorMount& m) { return m.name == item.get<std::string>(); });
      if (it == vehicle.ultrasonic.end()) {
        reader.Fail(item_key, "the vehicle has no ultrasonic sensor \"" + item.get<std::string>() + "\"");
      }
      mounts.push_back(*it);
    } else if (item.is_object()) {
      mounts.push_back(ReadMountObject(Reader(item, reader.source(), item_key)));
    } else {
      reader.Fail(item_key, "must be a sensor name or a mount object");
    }
    if (!names.insert(mounts.back().name).second) reader.Fail(item_key, "duplicate sensor name");
    if (mounts.back().position_m.z() <= 0.0) reader.Fail(item_key, "position_m[2] (height) must be > 0");
  }
  return mounts;
}

UltrasonicScenario ReadUltrasonic(Reader reader, const VehicleConfig& vehicle) {
  UltrasonicScenario scenario;
  scenario.rate_hz = reader.NumberIn("rate_hz", 1e-3, 1000.0);
  scenario.mounts = ReadMounts(reader, vehicle);
  scenario.params.min_range_m = reader.Number("min_range_m");
  scenario.params.max_range_m = reader.Number("max_range_m");
  scenario.params.half_aperture_rad = reader.NumberIn("half_aperture_deg", 0.0, 89.0) * kDegToRad;
  scenario.params.range_sigma_m = reader.Number("range_sigma_m");
  scenario.params.miss_probability = reader.Number("miss_probability");
  reader.RejectUnknownKeys();
  if (const auto problem = UltrasonicParamsProblem(scenario.params)) reader.Fail(reader.path(), *problem);
  return scenario;
}

VioScenario ReadVio(Reader reader) {
  VioScenario vio;
  vio.rate_hz = reader.NumberIn("rate_hz", 1e-3, 1000.0);
  vio.sigma_mps = reader.NumberIn("sigma_mps", 1e-9, 100.0);
  vio.position_m = reader.Vector<3>("position_m");
  reader.RejectUnknownKeys();
  return vio;
}

/// The profile name of a sensor object {"profile": name} (with extra keys read by the caller).
std::string ProfileName(Reader& reader) {
  const std::string name = reader.String("profile");
  if (name.empty()) reader.Fail(reader.Key("profile"), "must not be empty");
  return name;
}

void ReadSensors(Reader reader, const SensorProfiles& profiles, Scenario& scenario) {
  const auto profile = [&](const std::string& key, auto find) {
    Reader sensor = reader.Object(key);
    const std::string name = ProfileName(sensor);
    sensor.RejectUnknownKeys();
    return Referenced(sensor, "profile", [&] { return find(profiles, name); });
  };
  if (!reader.IsNull("gnss")) {
    Reader gnss = reader.Object("gnss");
    GnssScenario g;
    g.profile = ProfileName(gnss);
    if (!gnss.IsNull("off_after_s")) g.off_after_s = gnss.NumberIn("off_after_s", 0.0, 1e7);
    gnss.RejectUnknownKeys();
    g.config = Referenced(gnss, "profile", [&] { return FindGnssProfile(profiles, g.profile); });
    scenario.gnss = g;
  }
  scenario.imu = profile("imu", FindImuProfile);
  scenario.wheel_encoder = profile("wheel_encoder", FindWheelEncoderProfile);
  if (!reader.IsNull("steering_encoder")) {
    const bool steers = std::any_of(scenario.vehicle.wheels.begin(), scenario.vehicle.wheels.end(),
                                    [](const WheelGeometry& w) { return w.steerable; });
    if (!steers) reader.Fail(reader.Key("steering_encoder"), "the vehicle has no steerable wheel: must be null");
    scenario.steering_encoder = profile("steering_encoder", FindSteeringEncoderProfile);
  }
  if (!reader.IsNull("torque")) {
    Reader torque = reader.Object("torque");
    scenario.torque = TorqueScenario{torque.NumberIn("noise_sigma_nm", 0.0, 1e6)};
    torque.RejectUnknownKeys();
  }
  if (!reader.IsNull("ultrasonic")) {
    if (!scenario.world) reader.Fail(reader.Key("ultrasonic"), "needs a world (world is null)");
    scenario.ultrasonic = ReadUltrasonic(reader.Object("ultrasonic"), scenario.vehicle);
  }
  if (!reader.IsNull("vio")) scenario.vio = ReadVio(reader.Object("vio"));
  reader.RejectUnknownKeys();
}

void ReadWorldAndOrigin(Reader& reader, const std::filesystem::path& base, Scenario& scenario) {
  if (!reader.IsNull("world")) {
    const auto path = FilePath(reader, "world", base);
    scenario.world = Referenced(reader, "world", [&] { return LoadRowWorldParams(path); });
    if (!reader.IsNull("origin")) reader.Fail(reader.Key("origin"), "must be null with a world (the world's origin is used)");
    scenario.origin = scenario.world->origin;
  } else {
    if (reader.IsNull("origin")) reader.Fail(reader.Key("origin"), "required for an open field (world is null)");
    scenario.origin = ReadOrigin(reader.Object("origin"));
  }
}

void ReadRouteAndTerrain(Reader& reader, Scenario& scenario) {
  const std::string terrain_text = reader.Value("terrain_map").dump();
  scenario.terrain_map = Inline([&] {
    return ParseTerrainMap(terrain_text, reader.source(), "terrain_map");
  });
  const std::string route_text = reader.Value("route").dump();
  std::optional<RowWorld> world;
  if (scenario.world) world.emplace(*scenario.world);
  scenario.route = Inline([&] {
    return ParseRouteSpec(route_text, reader.source(), world ? &*world : nullptr, "route");
  });
  if (const auto problem = RouteSpecProblem(scenario.route)) reader.Fail(reader.Key("route"), *problem);
}

/// The optional "filters" array: each element a non-empty path of an existing file.
std::vector<std::filesystem::path> ReadFilterFiles(Reader& reader, const std::filesystem::path& base) {
  std::vector<std::filesystem::path> files;
  if (!reader.Has("filters")) return files;
  const json& array = reader.Array("filters");
  for (std::size_t i = 0; i < array.size(); ++i) {
    const std::string key = reader.Key("filters") + "[" + std::to_string(i) + "]";
    if (!array[i].is_string() || array[i].get<std::string>().empty()) {
      reader.Fail(key, std::string("must name a filter file, got ") + array[i].dump());
    }
    const std::filesystem::path path(array[i].get<std::string>());
    files.push_back(path.is_absolute() ? path : base / path);
    std::error_code error;  // an unreadable path is "no such file" too, not an exception
    if (!std::filesystem::is_regular_file(files.back(), error)) {
      reader.Fail(key, "no such file: " + files.back().string());
    }
  }
  return files;
}

Scenario ParseScenarioObject(Reader reader, const std::filesystem::path& base) {
  Scenario scenario;
  scenario.name = reader.String("name");
  if (scenario.name.empty()) reader.Fail(reader.Key("name"), "must not be empty");
  scenario.description = reader.String("description");
  scenario.seed = reader.Unsigned("seed");
  ReadWorldAndOrigin(reader, base, scenario);
  const auto vehicle_path = FilePath(reader, "vehicle", base);
  scenario.vehicle = Referenced(reader, "vehicle", [&] { return LoadVehicleConfig(vehicle_path); });
  const auto profiles_path = FilePath(reader, "sensor_profiles", base);
  const SensorProfiles profiles =
      Referenced(reader, "sensor_profiles", [&] { return LoadSensorProfiles(profiles_path); });
  const auto terrains_path = FilePath(reader, "terrains", base);
  scenario.terrains = Referenced(reader, "terrains", [&] { return LoadTerrainSlipTable(terrains_path); });
  ReadRouteAndTerrain(reader, scenario);
  scenario.truth_rate_hz = reader.NumberIn("truth_rate_hz", 1e-3, 1e4);
  scenario.row_map_height_m = reader.NumberIn("row_map_height_m", 0.0, 100.0);
  ReadSensors(reader.Object("sensors"), profiles, scenario);
  scenario.filter_files = ReadFilterFiles(reader, base);
  if (reader.Has("faults")) {
    const std::string faults_text = reader.Value("faults").dump();
    std::vector<std::string> wheels;
    for (const auto& w : scenario.vehicle.wheels) wheels.push_back(w.name);
    scenario.faults = Inline([&] { return ParseSensorFaults(faults_text, reader.source(), "faults", wheels); });
  }
  reader.RejectUnknownKeys();
  return scenario;
}

/// The keys of a scenario that hold file paths (relative to the file that states them).
constexpr std::array<const char*, 5> kPathKeys = {"world", "vehicle", "sensor_profiles", "terrains", "filters"};

bool SameDirectory(const std::filesystem::path& a, const std::filesystem::path& b) {
  std::error_code error;
  const auto canonical = [&error](const std::filesystem::path& p) {
    return std::filesystem::weakly_canonical(p.empty() ? std::filesystem::path(".") : p, error);
  };
  return canonical(a) == canonical(b) && !error;
}

/// A relative path of a base in another directory, made absolute (normalized) so that it still
/// names the file the base meant once the base is merged into the extending file.
void RebasePath(json& value, const std::filesystem::path& directory) {
  if (!value.is_string() || value.get<std::string>().empty()) return;  // the reader refuses it later
  const std::filesystem::path path(value.get<std::string>());
  if (path.is_absolute()) return;
  std::error_code error;
  value = std::filesystem::absolute(directory / path, error).lexically_normal().string();
}

void RebasePaths(json& document, const std::filesystem::path& directory) {
  for (const char* key : kPathKeys) {
    const auto it = document.find(key);
    if (it == document.end()) continue;
    if (it->is_array()) {
      for (json& item : *it) RebasePath(item, directory);
    } else {
      RebasePath(*it, directory);
    }
  }
}

/// The chain of a scenario merged, base first; the paths of bases in other directories rebased.
json MergeScenarioLayers(const std::vector<mapio::ConfigLayer>& layers, const std::filesystem::path& directory) {
  json merged = json::object();
  for (const mapio::ConfigLayer& layer : layers) {
    if (&layer == &layers.back() || SameDirectory(layer.file.parent_path(), directory)) {
      mapio::MergeOverlay(merged, layer.document);
    } else {
      json document = layer.document;
      RebasePaths(document, layer.file.parent_path());
      mapio::MergeOverlay(merged, document);
    }
  }
  return merged;
}

/// Runs a reader of scenario layers; its errors become ScenarioErrors (same message).
template <typename Read>
json ExpandedDocument(Read&& read, const std::filesystem::path& directory) {
  try {
    return MergeScenarioLayers(read(), directory);
  } catch (const mapio::ConfigOverlayError& e) {
    throw ScenarioError(e.what());
  }
}

json ExpandFile(const std::filesystem::path& path) {
  return ExpandedDocument([&] { return mapio::ReadConfigLayers(path, "scenario file"); }, path.parent_path());
}

}  // namespace

Scenario ParseScenario(std::string_view json_text, std::string_view source_name,
                       const std::filesystem::path& base_directory) {
  const std::string source(source_name);
  const json document = ExpandedDocument(
      [&] { return mapio::ParseConfigLayers(json_text, source, base_directory, "scenario file"); }, base_directory);
  return ParseScenarioObject(Reader(document, source, ""), base_directory);
}

Scenario LoadScenario(const std::filesystem::path& path) {
  const json document = ExpandFile(path);
  return ParseScenarioObject(Reader(document, path.string(), ""), path.parent_path());
}

std::string ExpandedScenarioJson(const std::filesystem::path& path) { return ExpandFile(path).dump(2) + "\n"; }

}  // namespace rowloc::sim
