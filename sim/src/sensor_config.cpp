// JSON loading of the sensor error-model profiles (format in sensor_config.hpp).
#include "rowloc/sim/sensor_config.hpp"

#include "rowloc/mapio/detail/json_object_reader.hpp"

namespace rowloc::sim {
namespace {

using Reader = mapio::detail::JsonObjectReader<SensorConfigError>;

formats::GnssFixQuality ParseFixQuality(Reader& reader, const std::string& key) {
  const std::string text = reader.String(key);
  if (text == "sbas") return formats::GnssFixQuality::kSbas;
  if (text == "rtk_float") return formats::GnssFixQuality::kRtkFloat;
  if (text == "rtk_fixed") return formats::GnssFixQuality::kRtkFixed;
  reader.Fail(reader.Key(key), "must be one of \"sbas\", \"rtk_float\", \"rtk_fixed\", got \"" + text + "\"");
}

GnssMarkovFaultConfig ParseFault(Reader reader) {
  GnssMarkovFaultConfig fault;
  fault.onset_rate_open_per_s = reader.Number("onset_rate_open_per_s");
  fault.onset_rate_canopy_per_s = reader.Number("onset_rate_canopy_per_s");
  fault.mean_duration_s = reader.Number("mean_duration_s");
  reader.RejectUnknownKeys();
  return fault;
}

GnssConfig ParseGnss(Reader& reader) {
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

ImuAxisConfig ParseImuAxis(Reader reader) {
  ImuAxisConfig axis;
  axis.noise_density = reader.Number("noise_density");
  axis.bias_random_walk = reader.Number("bias_random_walk");
  axis.initial_bias = reader.Number("initial_bias");
  reader.RejectUnknownKeys();
  return axis;
}

ImuConfig ParseImu(Reader& reader) {
  ImuConfig c;
  c.rate_hz = reader.Number("rate_hz");
  c.accel_x = ParseImuAxis(reader.Object("accel_x"));
  c.accel_y = ParseImuAxis(reader.Object("accel_y"));
  c.gyro_z = ParseImuAxis(reader.Object("gyro_z"));
  return c;
}

WheelEncoderConfig ParseWheelEncoder(Reader& reader) {
  WheelEncoderConfig c;
  c.rate_hz = reader.Number("rate_hz");
  c.ticks_per_revolution = reader.Number("ticks_per_revolution");
  c.low_pass_time_constant_s = reader.Number("low_pass_time_constant_s");
  c.speed_noise_sigma_radps = reader.Number("speed_noise_sigma_radps");
  return c;
}

SteeringEncoderConfig ParseSteeringEncoder(Reader& reader) {
  SteeringEncoderConfig c;
  c.rate_hz = reader.Number("rate_hz");
  c.quantization_step_rad = reader.Number("quantization_step_rad");
  c.noise_sigma_rad = reader.Number("noise_sigma_rad");
  return c;
}

/// Parses and validates every profile of one sensor kind (root.<kind>.<name>) with parse(reader).
template <typename Config, typename Parse>
std::map<std::string, Config> ParseProfiles(Reader& root, const std::string& kind, Parse parse) {
  Reader kind_reader = root.Object(kind);
  std::map<std::string, Config> profiles;
  for (const std::string& name : kind_reader.Keys()) {
    Reader reader = kind_reader.Object(name);
    Config config = parse(reader);
    reader.RejectUnknownKeys();
    try {
      config.Validate();
    } catch (const std::invalid_argument& e) {
      reader.Fail(reader.path(), e.what());
    }
    profiles.emplace(name, config);
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
  const nlohmann::json document = mapio::detail::ParseJsonText<SensorConfigError>(json_text, source);
  Reader root(document, source, "");
  SensorProfiles profiles;
  profiles.gnss = ParseProfiles<GnssConfig>(root, "gnss", ParseGnss);
  profiles.imu = ParseProfiles<ImuConfig>(root, "imu", ParseImu);
  profiles.wheel_encoder = ParseProfiles<WheelEncoderConfig>(root, "wheel_encoder", ParseWheelEncoder);
  profiles.steering_encoder = ParseProfiles<SteeringEncoderConfig>(root, "steering_encoder", ParseSteeringEncoder);
  root.RejectUnknownKeys();
  return profiles;
}

SensorProfiles LoadSensorProfiles(const std::filesystem::path& path) {
  return ParseSensorProfiles(mapio::detail::ReadTextFile<SensorConfigError>(path, "sensor profile file"), path.string());
}

GnssConfig DefaultGnssRtkConfig() {
  GnssConfig c;
  c.rate_hz = 10.0;
  c.sigma_horizontal_m = 0.01;
  c.sigma_vertical_m = 0.02;
  c.canopy_sigma_gain = 4.0;
  c.nominal_fix = formats::GnssFixQuality::kRtkFixed;
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
  c.nominal_fix = formats::GnssFixQuality::kSbas;
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

WheelEncoderConfig WhiteWheelEncoderConfig() { return {50.0, 16777216.0, 0.0, 0.1}; }

SteeringEncoderConfig DefaultSteeringEncoderConfig() { return {50.0, 0.0015, 0.0005}; }

SensorProfiles DefaultSensorProfiles() {
  SensorProfiles p;
  p.gnss = {{"gnss_rtk", DefaultGnssRtkConfig()}, {"gnss_sbas", DefaultGnssSbasConfig()}};
  p.imu = {{"imu_mems", DefaultImuConfig()}};
  p.wheel_encoder = {{"wheel_encoder_1024", DefaultWheelEncoderConfig()},
                     {"wheel_encoder_white", WhiteWheelEncoderConfig()}};
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
