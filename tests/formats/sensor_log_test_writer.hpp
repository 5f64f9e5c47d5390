// Test helper: writes sensor messages back as log lines in the simulator's layout
// (sim/src/log_writers.cpp: keys in the order of docs/protocol.md §1), and compares two lines as
// JSON text: the same bytes outside numbers, and numbers that are the same doubles. Numbers are
// compared by value because the simulator's writer (nlohmann-json's dump, Grisu2) does not always
// print the shortest digits: it writes -0.045505880608945067 where -0.04550588060894507 is the
// shortest text of the same double. Names are written without escaping (the fixtures need none).
#pragma once

#include "rowloc/formats/sensor_messages.hpp"

#include <charconv>
#include <cstdlib>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace rowloc::formats::log_text {

/// Shortest text that reads back as the same double.
inline std::string JsonNumber(double value) {
  char buffer[64];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, value).ptr;
  return std::string(buffer, end);
}

/// A JSON line with every number replaced by '#', and the numbers in order.
struct NumbersApart {
  std::string skeleton;
  std::vector<double> numbers;
};

inline NumbersApart SplitNumbers(std::string_view line) {
  NumbersApart out;
  bool in_string = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    const bool starts_number = !in_string && (c == '-' || (c >= '0' && c <= '9'));
    if (!starts_number) {
      if (c == '"' && (i == 0 || line[i - 1] != '\\')) in_string = !in_string;
      out.skeleton += c;
      continue;
    }
    const std::size_t end = line.find_first_not_of("0123456789+-.eE", i);
    const std::string token(line.substr(i, end - i));
    out.numbers.push_back(std::strtod(token.c_str(), nullptr));
    out.skeleton += '#';
    i = (end == std::string_view::npos ? line.size() : end) - 1;
  }
  return out;
}

inline std::string Quote(const std::string& text) { return "\"" + text + "\""; }

inline std::string Key(const char* key) { return std::string(",\"") + key + "\":"; }

inline std::string Start(const char* type, double time_s) {
  return std::string("{\"type\":\"") + type + "\",\"t\":" + JsonNumber(time_s);
}

inline std::string NameArray(const std::vector<std::string>& names) {
  std::string out = "[";
  for (const std::string& name : names) {
    if (out.size() > 1) out += ',';
    out += Quote(name);
  }
  return out + "]";
}

/// {"name":value,...} over the header's wheels that have a value.
inline std::string PerWheel(const LogHeader& header, const std::vector<std::optional<double>>& values) {
  std::string out = "{";
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!values[i]) continue;
    if (out.size() > 1) out += ',';
    out += Quote(header.wheels[i]) + ":" + JsonNumber(*values[i]);
  }
  return out + "}";
}

inline std::string PerWheel(const LogHeader& header, const std::vector<double>& values) {
  return PerWheel(header, std::vector<std::optional<double>>(values.begin(), values.end()));
}

inline std::string WriteLine(const LogHeader& h) {
  return "{\"type\":\"log_header\"" + Key("protocol") + Quote(h.protocol) + Key("source") + Quote(h.source) +
         Key("scenario") + Quote(h.scenario) + Key("vehicle") + Quote(h.vehicle) + Key("origin") +
         "{\"latitude_deg\":" + JsonNumber(h.origin.latitude_deg) + Key("longitude_deg") +
         JsonNumber(h.origin.longitude_deg) + Key("altitude_m") + JsonNumber(h.origin.altitude_m) + "}" +
         Key("wheels") + NameArray(h.wheels) + Key("ultrasonic") + NameArray(h.ultrasonic) + "}";
}

inline std::string Write(const LogHeader&, const GpsMessage& m) {
  std::string out = Start("gps", m.time_s) + Key("sensor") + Quote(m.sensor) + Key("fix") +
                    Quote(std::string(GnssFixQualityName(m.fix)));
  if (const auto& p = m.position) {
    out += Key("latitude_deg") + JsonNumber(p->latitude_deg) + Key("longitude_deg") + JsonNumber(p->longitude_deg) +
           Key("altitude_m") + JsonNumber(p->altitude_m) + Key("sigma_horizontal_m") +
           JsonNumber(p->sigma_horizontal_m) + Key("sigma_vertical_m") + JsonNumber(p->sigma_vertical_m);
  }
  return out + "}";
}

inline std::string Write(const LogHeader&, const ImuMessage& m) {
  return Start("imu", m.time_s) + Key("sensor") + Quote(m.sensor) + Key("accel_x_mps2") + JsonNumber(m.accel_x_mps2) +
         Key("accel_y_mps2") + JsonNumber(m.accel_y_mps2) + Key("gyro_z_radps") + JsonNumber(m.gyro_z_radps) + "}";
}

inline std::string Write(const LogHeader& h, const WheelsMessage& m) {
  std::string out = Start("wheels", m.time_s) + Key("speed_radps") + PerWheel(h, m.speed_radps);
  if (m.torque_nm) out += Key("torque_nm") + PerWheel(h, *m.torque_nm);
  return out + "}";
}

inline std::string Write(const LogHeader& h, const SteeringMessage& m) {
  return Start("steering", m.time_s) + Key("angle_rad") + PerWheel(h, m.angle_rad) + "}";
}

inline std::string Write(const LogHeader&, const UltrasonicMessage& m) {
  return Start("ultrasonic", m.time_s) + Key("sensor") + Quote(m.sensor) + Key("range_m") +
         (m.range_m ? JsonNumber(*m.range_m) : "null") + "}";
}

inline std::string Write(const LogHeader&, const VioMessage& m) {
  return Start("vio", m.time_s) + Key("sensor") + Quote(m.sensor) + Key("velocity_x_mps") +
         JsonNumber(m.velocity_x_mps) + Key("velocity_y_mps") + JsonNumber(m.velocity_y_mps) + Key("sigma_mps") +
         JsonNumber(m.sigma_mps) + "}";
}

inline std::string WriteLine(const LogHeader& header, const SensorMessage& message) {
  return std::visit([&header](const auto& m) { return Write(header, m); }, message);
}

}  // namespace rowloc::formats::log_text
