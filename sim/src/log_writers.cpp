// The simulator's sensor-log and truth writers of docs/protocol.md (see log_writers.hpp).
#include "rowloc/sim/log_writers.hpp"

#include "rowloc/formats/ndjson_writing.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <set>
#include <stdexcept>

namespace rowloc::sim {
namespace {

using formats::ndjson::CheckTimeOrder;
using formats::ndjson::Finite;
using formats::ndjson::MessageStart;
using formats::ndjson::OriginJson;
using formats::ndjson::Refuse;
using ordered_json = nlohmann::ordered_json;

void CheckUnique(const std::vector<std::string>& names, const char* what) {
  std::set<std::string> seen;
  for (const std::string& name : names) {
    if (name.empty()) throw std::invalid_argument(std::string("log header: empty ") + what + " name");
    if (!seen.insert(name).second) {
      throw std::invalid_argument(std::string("log header: duplicate ") + what + " name \"" + name + "\"");
    }
  }
}

ordered_json HeaderJson(const char* type, const char* protocol, const formats::LogHeader& header) {
  CheckUnique(header.wheels, "wheel");
  CheckUnique(header.ultrasonic, "ultrasonic");
  ordered_json j;
  j["type"] = type;
  j["protocol"] = protocol;
  j["source"] = header.source;
  j["scenario"] = header.scenario;
  j["vehicle"] = header.vehicle;
  j["origin"] = OriginJson(header.origin);
  j["wheels"] = header.wheels;
  j["ultrasonic"] = header.ultrasonic;
  return j;
}

ordered_json NamedJson(const char* type, const NamedValues& values) {
  ordered_json o = ordered_json::object();
  for (const auto& [name, value] : values) o[name] = Finite(type, name.c_str(), value);
  return o;
}

}  // namespace

SensorLogWriter::SensorLogWriter(std::ostream& out, formats::LogHeader header)
    : out_(out), header_(std::move(header)) {
  Emit(HeaderJson("log_header", "rowloc/1", header_).dump());
}

void SensorLogWriter::CheckTime(const char* type, double time_s) { CheckTimeOrder(type, time_s, last_time_s_); }

void SensorLogWriter::CheckWheels(const char* type, const NamedValues& values, bool all_required) const {
  for (auto it = values.begin(); it != values.end(); ++it) {
    const std::string& name = it->first;
    if (std::find(header_.wheels.begin(), header_.wheels.end(), name) == header_.wheels.end()) {
      Refuse(type, "wheel \"" + name + "\" is not in the log header");
    }
    if (std::any_of(values.begin(), it, [&](const auto& earlier) { return earlier.first == name; })) {
      Refuse(type, "wheel \"" + name + "\" appears twice");
    }
  }
  if (all_required && values.size() != header_.wheels.size()) {
    Refuse(type, "expected " + std::to_string(header_.wheels.size()) + " wheels, got " + std::to_string(values.size()));
  }
}

void SensorLogWriter::Emit(const std::string& line) {
  out_ << line << '\n';
  if (!out_) throw std::runtime_error("sensor log: write failed");
}

void SensorLogWriter::EmitMessage(const std::string& line, double time_s) {
  Emit(line);
  last_time_s_ = time_s;
  ++messages_;
}

void SensorLogWriter::Write(const GpsMessage& m) {
  CheckTime("gps", m.time_s);
  ordered_json j = MessageStart("gps", m.time_s);
  j["sensor"] = m.sensor;
  j["fix"] = formats::GnssFixQualityName(m.fix);
  if (m.fix != formats::GnssFixQuality::kNone) {
    j["latitude_deg"] = Finite("gps", "latitude_deg", m.latitude_deg);
    j["longitude_deg"] = Finite("gps", "longitude_deg", m.longitude_deg);
    j["altitude_m"] = Finite("gps", "altitude_m", m.altitude_m);
    j["sigma_horizontal_m"] = Finite("gps", "sigma_horizontal_m", m.sigma_horizontal_m);
    j["sigma_vertical_m"] = Finite("gps", "sigma_vertical_m", m.sigma_vertical_m);
  }
  EmitMessage(j.dump(), m.time_s);
}

void SensorLogWriter::Write(const ImuMessage& m) {
  CheckTime("imu", m.time_s);
  ordered_json j = MessageStart("imu", m.time_s);
  j["sensor"] = m.sensor;
  j["accel_x_mps2"] = Finite("imu", "accel_x_mps2", m.accel_x_mps2);
  j["accel_y_mps2"] = Finite("imu", "accel_y_mps2", m.accel_y_mps2);
  j["gyro_z_radps"] = Finite("imu", "gyro_z_radps", m.gyro_z_radps);
  EmitMessage(j.dump(), m.time_s);
}

void SensorLogWriter::Write(const WheelsMessage& m) {
  CheckTime("wheels", m.time_s);
  CheckWheels("wheels", m.speed_radps, true);
  if (!m.torque_nm.empty()) CheckWheels("wheels", m.torque_nm, true);  // all wheels or none
  if (!m.angle_rad.empty()) CheckWheels("wheels", m.angle_rad, true);
  ordered_json j = MessageStart("wheels", m.time_s);
  j["speed_radps"] = NamedJson("wheels", m.speed_radps);
  if (!m.torque_nm.empty()) j["torque_nm"] = NamedJson("wheels", m.torque_nm);
  if (!m.angle_rad.empty()) j["angle_rad"] = NamedJson("wheels", m.angle_rad);
  EmitMessage(j.dump(), m.time_s);
}

void SensorLogWriter::Write(const SteeringMessage& m) {
  CheckTime("steering", m.time_s);
  CheckWheels("steering", m.angle_rad, false);
  ordered_json j = MessageStart("steering", m.time_s);
  j["angle_rad"] = NamedJson("steering", m.angle_rad);
  EmitMessage(j.dump(), m.time_s);
}

void SensorLogWriter::Write(const UltrasonicMessage& m) {
  CheckTime("ultrasonic", m.time_s);
  if (std::find(header_.ultrasonic.begin(), header_.ultrasonic.end(), m.sensor) == header_.ultrasonic.end()) {
    Refuse("ultrasonic", "sensor \"" + m.sensor + "\" is not in the log header");
  }
  ordered_json j = MessageStart("ultrasonic", m.time_s);
  j["sensor"] = m.sensor;
  if (m.range_m) {
    j["range_m"] = Finite("ultrasonic", "range_m", *m.range_m);
  } else {
    j["range_m"] = nullptr;
  }
  EmitMessage(j.dump(), m.time_s);
}

void SensorLogWriter::Write(const VioMessage& m) {
  CheckTime("vio", m.time_s);
  ordered_json j = MessageStart("vio", m.time_s);
  j["sensor"] = m.sensor;
  j["velocity_x_mps"] = Finite("vio", "velocity_x_mps", m.velocity_x_mps);
  j["velocity_y_mps"] = Finite("vio", "velocity_y_mps", m.velocity_y_mps);
  j["sigma_mps"] = Finite("vio", "sigma_mps", m.sigma_mps);
  EmitMessage(j.dump(), m.time_s);
}

TruthLogWriter::TruthLogWriter(std::ostream& out, const formats::LogHeader& header)
    : out_(out), wheels_(header.wheels) {
  out_ << HeaderJson("truth_header", "rowloc-truth/1", header).dump() << '\n';
  if (!out_) throw std::runtime_error("truth log: write failed");
}

void TruthLogWriter::Write(const TruthRecord& r) {
  const char* type = "truth";
  CheckTimeOrder(type, r.time_s, last_time_s_);
  if (r.wheels.size() != wheels_.size()) Refuse(type, "wrong number of wheels");
  ordered_json j = MessageStart(type, r.time_s);
  j["x_m"] = Finite(type, "x_m", r.position_m.x());
  j["y_m"] = Finite(type, "y_m", r.position_m.y());
  j["z_m"] = Finite(type, "z_m", r.position_m.z());
  j["phi_rad"] = Finite(type, "phi_rad", r.heading_rad);
  j["velocity_x_mps"] = Finite(type, "velocity_x_mps", r.velocity_x_mps);
  j["velocity_y_mps"] = Finite(type, "velocity_y_mps", r.velocity_y_mps);
  j["yaw_rate_radps"] = Finite(type, "yaw_rate_radps", r.yaw_rate_radps);
  j["accel_x_mps2"] = Finite(type, "accel_x_mps2", r.accel_x_mps2);
  j["accel_y_mps2"] = Finite(type, "accel_y_mps2", r.accel_y_mps2);
  j["gnss_available"] = r.gnss_available;
  j["gnss_multipath"] = r.gnss_multipath;
  j["canopy_cover"] = Finite(type, "canopy_cover", r.canopy_cover);
  ordered_json bias;
  bias["accel_x_mps2"] = Finite(type, "imu_bias", r.imu_bias_accel_x_mps2);
  bias["accel_y_mps2"] = Finite(type, "imu_bias", r.imu_bias_accel_y_mps2);
  bias["gyro_z_radps"] = Finite(type, "imu_bias", r.imu_bias_gyro_z_radps);
  j["imu_bias"] = bias;
  ordered_json wheels = ordered_json::object();
  for (std::size_t i = 0; i < r.wheels.size(); ++i) {
    const WheelTruthRecord& w = r.wheels[i];
    if (w.name != wheels_[i]) Refuse(type, "wheel \"" + w.name + "\" out of the header's order");
    ordered_json o;
    o["steering_rad"] = Finite(type, "steering_rad", w.steering_rad);
    o["speed_radps"] = Finite(type, "speed_radps", w.speed_radps);
    o["slip"] = Finite(type, "slip", w.slip);
    o["rolling_radius_m"] = Finite(type, "rolling_radius_m", w.rolling_radius_m);
    o["torque_nm"] = Finite(type, "torque_nm", w.torque_nm);
    o["terrain"] = w.terrain;
    wheels[w.name] = o;
  }
  j["wheels"] = wheels;
  out_ << j.dump() << '\n';
  if (!out_) throw std::runtime_error("truth log: write failed");
  last_time_s_ = r.time_s;
  ++records_;
}

}  // namespace rowloc::sim
