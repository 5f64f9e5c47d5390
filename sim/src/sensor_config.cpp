// JSON loading of the sensor error-model profiles (format in sensor_config.hpp).
#include "rowloc/sim/sensor_config.hpp"

#include <nlohmann/json.hpp>

#include <fstream>
#include <set>
#include <sstream>

namespace rowloc::sim {
namespace {

using nlohmann::json;

/// Reads the fields of one JSON object, remembering which were used so that unknown keys are
/// reported; every error names the source and the full key path.
class ObjectReader {
 public:
  ObjectReader(const json& object, std::string source, std::string path)
      : object_(object), source_(std::move(source)), path_(std::move(path)) {
    if (!object_.is_object()) Fail(path_, std::string("must be an object, got ") + object_.type_name());
  }

  double Number(const std::string& key) {
    const json& value = Get(key);
    if (!value.is_number()) Fail(Key(key), std::string("must be a number, got ") + value.type_name());
    return value.get<double>();
  }

  std::string String(const std::string& key) {
    const json& value = Get(key);
    if (!value.is_string()) Fail(Key(key), std::string("must be a string, got ") + value.type_name());
    return value.get<std::string>();
  }

  ObjectReader Object(const std::string& key) { return ObjectReader(Get(key), source_, Key(key)); }

  /// The raw value of a required key (marked as used).
  const json& Value(const std::string& key) { return Get(key); }

  /// Call after reading every field.
  void RejectUnknownKeys() const {
    for (const auto& item : object_.items()) {
      if (!used_.contains(item.key())) Fail(Key(item.key()), "unknown key");
    }
  }

  [[noreturn]] void Fail(const std::string& key_path, const std::string& reason) const {
    throw SensorConfigError(source_ + ": " + (key_path.empty() ? "<root>" : key_path) + ": " + reason);
  }
  const std::string& path() const { return path_; }

 private:
  std::string Key(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  const json& Get(const std::string& key) {
    const auto it = object_.find(key);
    if (it == object_.end()) Fail(Key(key), "missing key");
    used_.insert(key);
    return *it;
  }

  const json& object_;
  std::string source_;
  std::string path_;
  std::set<std::string> used_;
};

GnssFixQuality ParseFixQuality(ObjectReader& reader, const std::string& key) {
  const std::string text = reader.String(key);
  if (text == "sbas") return GnssFixQuality::kSbas;
  if (text == "rtk_float") return GnssFixQuality::kRtkFloat;
  if (text == "rtk_fixed") return GnssFixQuality::kRtkFixed;
  reader.Fail(reader.path() + "." + key, "must be one of \"sbas\", \"rtk_float\", \"rtk_fixed\", got \"" + text + "\"");
}

GnssMarkovFaultConfig ParseFault(ObjectReader reader) {
  GnssMarkovFaultConfig fault;
  fault.onset_rate_open_per_s = reader.Number("onset_rate_open_per_s");
  fault.onset_rate_canopy_per_s = reader.Number("onset_rate_canopy_per_s");
  fault.mean_duration_s = reader.Number("mean_duration_s");
  reader.RejectUnknownKeys();
  return fault;
}

GnssConfig ParseGnss(ObjectReader& reader) {
  GnssConfig c;
  c.rate_hz = reader.Number("rate_hz");
  c.sigma_horizontal_m = reader.Number("sigma_horizontal_m");
  c.sigma_vertical_m = reader.Number("sigma_vertical_m");
  c.canopy_sigma_gain = reader.Number("canopy_sigma_gain");
  c.nominal_fix = ParseFixQuality(reader, "nominal_fix");
  c.dropout = ParseFault(reader.Object("dropout"));
  c.multipath = ParseFault(reader.Object("multipath"));
  c.multipath_offset_min_m = reader.Number("multipath_offset_min_m");
  c.multipath_offset_max_m = reader.Number("multipath_offset_max_m");
  return c;
}

ImuAxisConfig ParseImuAxis(ObjectReader reader) {
  ImuAxisConfig axis;
  axis.noise_density = reader.Number("noise_density");
  axis.bias_random_walk = reader.Number("bias_random_walk");
  axis.initial_bias = reader.Number("initial_bias");
  reader.RejectUnknownKeys();
  return axis;
}

ImuConfig ParseImu(ObjectReader& reader) {
  ImuConfig c;
  c.rate_hz = reader.Number("rate_hz");
  c.accel_x = ParseImuAxis(reader.Object("accel_x"));
  c.accel_y = ParseImuAxis(reader.Object("accel_y"));
  c.gyro_z = ParseImuAxis(reader.Object("gyro_z"));
  return c;
}

WheelEncoderConfig ParseWheelEncoder(ObjectReader& reader) {
  WheelEncoderConfig c;
  c.rate_hz = reader.Number("rate_hz");
  c.ticks_per_revolution = reader.Number("ticks_per_revolution");
  c.low_pass_time_constant_s = reader.Number("low_pass_time_constant_s");
  c.speed_noise_sigma_radps = reader.Number("speed_noise_sigma_radps");
  return c;
}

SteeringEncoderConfig ParseSteeringEncoder(ObjectReader& reader) {
  SteeringEncoderConfig c;
  c.rate_hz = reader.Number("rate_hz");
  c.quantization_step_rad = reader.Number("quantization_step_rad");
  c.noise_sigma_rad = reader.Number("noise_sigma_rad");
  return c;
}

/// Parses and validates every profile of one sensor kind (root.<kind>.<name>) with parse(reader).
template <typename Config, typename Parse>
std::map<std::string, Config> ParseProfiles(ObjectReader& root, const std::string& source, const std::string& kind,
                                            Parse parse) {
  const json& kind_object = root.Value(kind);
  ObjectReader check_is_object(kind_object, source, kind);
  std::map<std::string, Config> profiles;
  for (const auto& item : kind_object.items()) {
    ObjectReader reader(item.value(), source, kind + "." + item.key());
    Config config = parse(reader);
    reader.RejectUnknownKeys();
    try {
      config.Validate();
    } catch (const std::invalid_argument& e) {
      reader.Fail(reader.path(), e.what());
    }
    profiles.emplace(item.key(), config);
  }
  return profiles;
}

template <typename Config>
const Config& FindProfile(const std::map<std::string, Config>& profiles, const std::string& kind,
                          const std::string& name) {
  const auto it = profiles.find(name);
  if (it != profiles.end()) return it->second;
  std::string known;
  for (const auto& entry : profiles) known += (known.empty() ? "" : ", ") + entry.first;
  throw SensorConfigError("no " + kind + " profile named \"" + name + "\" (known: " + known + ")");
}

}  // namespace

SensorProfiles ParseSensorProfiles(std::string_view json_text, std::string_view source_name) {
  const std::string source(source_name);
  json document;
  try {
    document = json::parse(json_text);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for number overflow
    throw SensorConfigError(source + ": invalid JSON: " + e.what());
  }
  ObjectReader root(document, source, "");
  SensorProfiles profiles;
  profiles.gnss = ParseProfiles<GnssConfig>(root, source, "gnss", ParseGnss);
  profiles.imu = ParseProfiles<ImuConfig>(root, source, "imu", ParseImu);
  profiles.wheel_encoder = ParseProfiles<WheelEncoderConfig>(root, source, "wheel_encoder", ParseWheelEncoder);
  profiles.steering_encoder =
      ParseProfiles<SteeringEncoderConfig>(root, source, "steering_encoder", ParseSteeringEncoder);
  root.RejectUnknownKeys();
  return profiles;
}

SensorProfiles LoadSensorProfiles(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SensorConfigError(path.string() + ": cannot open sensor profile file");
  std::ostringstream text;
  text << in.rdbuf();
  return ParseSensorProfiles(text.str(), path.string());
}

GnssConfig DefaultGnssRtkConfig() {
  GnssConfig c;
  c.rate_hz = 10.0;
  c.sigma_horizontal_m = 0.01;
  c.sigma_vertical_m = 0.02;
  c.canopy_sigma_gain = 4.0;
  c.nominal_fix = GnssFixQuality::kRtkFixed;
  c.dropout = {0.001, 0.05, 5.0};
  c.multipath = {0.002, 0.02, 3.0};
  c.multipath_offset_min_m = 0.05;
  c.multipath_offset_max_m = 0.5;
  return c;
}

GnssConfig DefaultGnssSbasConfig() {
  GnssConfig c;
  c.rate_hz = 5.0;
  c.sigma_horizontal_m = 0.6;
  c.sigma_vertical_m = 1.0;
  c.canopy_sigma_gain = 1.0;
  c.nominal_fix = GnssFixQuality::kSbas;
  c.dropout = {0.0005, 0.02, 3.0};
  c.multipath = {0.002, 0.02, 5.0};
  c.multipath_offset_min_m = 0.5;
  c.multipath_offset_max_m = 3.0;
  return c;
}

ImuConfig DefaultImuConfig() {
  ImuConfig c;
  c.rate_hz = 100.0;
  c.accel_x = {0.002, 0.0004, 0.02};
  c.accel_y = {0.002, 0.0004, -0.015};
  c.gyro_z = {0.0002, 0.00002, 0.001};
  return c;
}

WheelEncoderConfig DefaultWheelEncoderConfig() { return {50.0, 1024.0, 0.02, 0.0}; }

SteeringEncoderConfig DefaultSteeringEncoderConfig() { return {50.0, 0.0015, 0.0005}; }

SensorProfiles DefaultSensorProfiles() {
  SensorProfiles p;
  p.gnss = {{"gnss_rtk", DefaultGnssRtkConfig()}, {"gnss_sbas", DefaultGnssSbasConfig()}};
  p.imu = {{"imu_mems", DefaultImuConfig()}};
  p.wheel_encoder = {{"wheel_encoder_1024", DefaultWheelEncoderConfig()}};
  p.steering_encoder = {{"steering_encoder_12bit", DefaultSteeringEncoderConfig()}};
  return p;
}

const GnssConfig& FindGnssProfile(const SensorProfiles& profiles, const std::string& name) {
  return FindProfile(profiles.gnss, "gnss", name);
}
const ImuConfig& FindImuProfile(const SensorProfiles& profiles, const std::string& name) {
  return FindProfile(profiles.imu, "imu", name);
}
const WheelEncoderConfig& FindWheelEncoderProfile(const SensorProfiles& profiles, const std::string& name) {
  return FindProfile(profiles.wheel_encoder, "wheel_encoder", name);
}
const SteeringEncoderConfig& FindSteeringEncoderProfile(const SensorProfiles& profiles, const std::string& name) {
  return FindProfile(profiles.steering_encoder, "steering_encoder", name);
}

}  // namespace rowloc::sim
