// Sensor log reader (see sensor_log_reader.hpp for the rules, docs/protocol.md §1 for the format).
#include "rowloc/formats/sensor_log_reader.hpp"

#include "log_json_fields.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <numbers>
#include <set>
#include <string_view>
#include <utility>
#include <vector>

namespace rowloc::formats {
namespace {

using detail::FormatNumber;
using detail::JsonFields;
using detail::LineLocation;
using json = nlohmann::json;

constexpr std::string_view kProtocolMajor = "rowloc/1";

// Physical domains of message values (docs/protocol.md §1, "Value domains"): far beyond any sensor
// of a field robot, but finite enough that the filter's arithmetic cannot overflow (a torque of
// 1e308 aborted a replay with no line or key, issue 26). A value outside is refused with its key.
constexpr double kMaxAbsAltitudeM = 1e5;
constexpr double kMaxSigmaM = 1e6;            // GNSS sigmas
constexpr double kMaxAbsAccelerationMps2 = 1e3;
constexpr double kMaxAbsRateRadps = 1e3;      // gyro, wheel speeds
constexpr double kMaxAbsTorqueNm = 1e6;
constexpr double kMaxAbsWheelAngleRad = 1e12; // cumulative encoder angle
constexpr double kMaxRangeM = 1e3;            // ultrasonic
constexpr double kMaxAbsVelocityMps = 1e3;    // VIO
constexpr double kMaxVelocitySigmaMps = 1e3;

/// nlohmann's message without its "[json.exception.parse_error.101] " prefix, and without the
/// "line 1, " of a position (the text parsed is one line).
std::string JsonErrorText(const json::exception& error) {
  std::string text = error.what();
  if (const std::size_t end = text.find("] "); !text.empty() && text.front() == '[' && end != std::string::npos) {
    text.erase(0, end + 2);
  }
  if (const std::size_t at = text.find("at line 1, column "); at != std::string::npos) text.erase(at + 3, 8);
  return text;
}

/// Key path ("speed_radps.front_left") of the number on which parsing `line` overflows a double:
/// the line is parsed again with a callback that records the keys as they are read. path[d - 1]
/// is the current key at nesting depth d ("" for an array level, left out of the result).
std::string KeyPathOfOverflow(std::string_view line) {
  std::vector<std::string> path;
  const auto record_keys = [&path](int depth, json::parse_event_t event, json& parsed) {
    const auto level = static_cast<std::size_t>(std::max(depth, 0));
    if (event == json::parse_event_t::key && level >= 1) {
      path.resize(level - 1);
      path.push_back(parsed.get<std::string>());
    } else if (event == json::parse_event_t::object_end && level < path.size()) {
      path.resize(level);  // the keys inside the object that ended
    }
    return true;
  };
  try {
    [[maybe_unused]] const json value = json::parse(line, record_keys);
  } catch (const json::exception&) {
    // expected: the same overflow as the first parse
  }
  std::string joined;
  for (const std::string& key : path) {
    if (key.empty()) continue;
    if (!joined.empty()) joined += '.';
    joined += key;
  }
  return joined.empty() ? "line" : joined;
}

/// The line as a JSON object. JSON has no NaN or infinity; the only non-finite number a line can
/// hold is one beyond the range of a double, which nlohmann rejects while parsing (error 406).
json ParseObject(std::string_view line, const LineLocation& where) {
  json value;
  try {
    value = json::parse(line);
  } catch (const json::out_of_range& error) {
    where.Fail(KeyPathOfOverflow(line), "not a finite number (" + JsonErrorText(error) + ")");
  } catch (const json::exception& error) {
    where.Fail("line", "invalid JSON: " + JsonErrorText(error));
  }
  if (!value.is_object()) where.Fail("line", std::string("must be a JSON object, got ") + value.type_name());
  return value;
}

std::string Quoted(const std::string& text) { return json(text).dump(); }

std::string NameList(const std::vector<std::string>& names) {
  if (names.empty()) return "no names";
  std::string list;
  for (const std::string& name : names) {
    if (!list.empty()) list += ", ";
    list += name;
  }
  return list;
}

std::optional<std::size_t> IndexOf(const std::vector<std::string>& names, const std::string& name) {
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) return std::nullopt;
  return static_cast<std::size_t>(it - names.begin());
}

/// "rowloc/1" or a minor revision "rowloc/1.N" (N: digits); anything else is another protocol.
bool IsProtocolMajor1(const std::string& protocol) {
  if (!protocol.starts_with(kProtocolMajor)) return false;
  const std::string_view rest = std::string_view(protocol).substr(kProtocolMajor.size());
  if (rest.empty()) return true;
  return rest.size() >= 2 && rest.front() == '.' &&
         std::all_of(rest.begin() + 1, rest.end(), [](char c) { return c >= '0' && c <= '9'; });
}

/// A header list of at most max_count names: an array of non-empty, distinct strings (distinctness
/// checked with a set: linear in the names, not quadratic).
std::vector<std::string> ReadNames(const JsonFields& fields, const std::string& key, std::size_t max_count) {
  const json& value = fields.Required(key);
  if (!value.is_array()) fields.Fail(key, std::string("must be an array of names, got ") + value.type_name());
  if (value.size() > max_count) {
    fields.Fail(key, std::to_string(value.size()) + " names, more than the limit of " + std::to_string(max_count));
  }
  std::vector<std::string> names;
  std::set<std::string_view> seen;
  names.reserve(value.size());
  for (std::size_t i = 0; i < value.size(); ++i) {
    const std::string item_key = key + "[" + std::to_string(i) + "]";
    if (!value[i].is_string()) fields.Fail(item_key, std::string("must be a string, got ") + value[i].type_name());
    const std::string& name = value[i].get_ref<const std::string&>();
    if (name.empty()) fields.Fail(item_key, "empty name");
    if (!seen.insert(name).second) fields.Fail(item_key, "duplicate name " + Quoted(name));
    names.push_back(name);
  }
  return names;
}

/// The `type` of a line's object (a required string).
std::string MessageType(const json& object, const LineLocation& where) {
  return JsonFields(object, where, "every message").String("type");
}

LogHeader HeaderFromFields(const JsonFields& fields) {
  LogHeader header;
  header.protocol = fields.String("protocol");
  if (!IsProtocolMajor1(header.protocol)) {
    fields.Fail("protocol", Quoted(header.protocol) + " is not supported (this reader reads rowloc/1)");
  }
  header.source = fields.String("source");
  header.scenario = fields.String("scenario");
  header.vehicle = fields.String("vehicle");
  const JsonFields origin = fields.Object("origin");
  header.origin.latitude_deg = origin.NumberIn("latitude_deg", -90.0, 90.0);
  header.origin.longitude_deg = origin.NumberIn("longitude_deg", -180.0, 180.0);
  header.origin.altitude_m = origin.NumberIn("altitude_m", -kMaxAbsAltitudeM, kMaxAbsAltitudeM);
  header.wheels = ReadNames(fields, "wheels", kMaxLogWheels);
  header.ultrasonic = ReadNames(fields, "ultrasonic", kMaxLogUltrasonicSensors);
  if (fields.object().contains("reorder_window_s")) {
    header.reorder_window_s = fields.NumberIn("reorder_window_s", 0.0, 3600.0);
  }
  return header;
}

// --- messages (docs/protocol.md §1); `t` is read by the caller -------------------------------------

SensorMessage ReadGps(const JsonFields& fields, const LogHeader&, double time_s) {
  GpsMessage m{time_s, fields.String("sensor"), GnssFixQuality::kNone, std::nullopt};
  const std::string fix = fields.String("fix");
  constexpr std::array kFixes{GnssFixQuality::kNone, GnssFixQuality::kSbas, GnssFixQuality::kRtkFloat,
                              GnssFixQuality::kRtkFixed};
  const auto known = std::find_if(kFixes.begin(), kFixes.end(),
                                  [&fix](GnssFixQuality q) { return GnssFixQualityName(q) == fix; });
  if (known == kFixes.end()) {
    fields.Fail("fix", "unknown fix quality " + Quoted(fix) + " (none, sbas, rtk_float or rtk_fixed)");
  }
  m.fix = *known;
  if (m.fix == GnssFixQuality::kNone) return m;  // no solution: position keys are absent (not read)
  m.position = GpsPosition{fields.NumberIn("latitude_deg", -90.0, 90.0),
                           fields.NumberIn("longitude_deg", -180.0, 180.0),
                           fields.NumberIn("altitude_m", -kMaxAbsAltitudeM, kMaxAbsAltitudeM),
                           fields.PositiveUpTo("sigma_horizontal_m", kMaxSigmaM),
                           fields.PositiveUpTo("sigma_vertical_m", kMaxSigmaM)};
  return m;
}

SensorMessage ReadImu(const JsonFields& fields, const LogHeader&, double time_s) {
  constexpr double kA = kMaxAbsAccelerationMps2;
  return ImuMessage{time_s, fields.String("sensor"), fields.NumberIn("accel_x_mps2", -kA, kA),
                    fields.NumberIn("accel_y_mps2", -kA, kA),
                    fields.NumberIn("gyro_z_radps", -kMaxAbsRateRadps, kMaxAbsRateRadps)};
}

/// Values of an object keyed by wheel name, in the header's wheel order (nullopt: not in the
/// object). Every name must be a wheel of the header; every value a number in [low, high].
std::vector<std::optional<double>> ReadPerWheel(const JsonFields& fields, const std::string& key,
                                                const LogHeader& header, double low, double high) {
  const JsonFields values = fields.Object(key);
  std::vector<std::optional<double>> result(header.wheels.size());
  for (const auto& item : values.object().items()) {
    const std::optional<std::size_t> index = IndexOf(header.wheels, item.key());
    if (!index) values.Fail(item.key(), "unknown wheel (the log header lists " + NameList(header.wheels) + ")");
    result[*index] = values.NumberIn(item.key(), low, high);
  }
  return result;
}

/// ReadPerWheel for an object that must carry every wheel of the header, values in [-max_abs, max_abs].
std::vector<double> ReadEveryWheel(const JsonFields& fields, const std::string& key, const LogHeader& header,
                                   double max_abs) {
  const std::vector<std::optional<double>> values = ReadPerWheel(fields, key, header, -max_abs, max_abs);
  std::vector<double> result;
  result.reserve(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!values[i]) {
      fields.Fail(key + "." + header.wheels[i], "missing (every wheel of the log header must appear in " + key + ")");
    }
    result.push_back(*values[i]);
  }
  return result;
}

SensorMessage ReadWheels(const JsonFields& fields, const LogHeader& header, double time_s) {
  WheelsMessage m{time_s, ReadEveryWheel(fields, "speed_radps", header, kMaxAbsRateRadps), std::nullopt,
                  std::nullopt};
  if (fields.object().contains("torque_nm")) m.torque_nm = ReadEveryWheel(fields, "torque_nm", header, kMaxAbsTorqueNm);
  if (fields.object().contains("angle_rad")) {
    m.angle_rad = ReadEveryWheel(fields, "angle_rad", header, kMaxAbsWheelAngleRad);
  }
  return m;
}

SensorMessage ReadSteering(const JsonFields& fields, const LogHeader& header, double time_s) {
  constexpr double kPi = std::numbers::pi;
  return SteeringMessage{time_s, ReadPerWheel(fields, "angle_rad", header, -kPi, kPi)};
}

SensorMessage ReadUltrasonic(const JsonFields& fields, const LogHeader& header, double time_s) {
  UltrasonicMessage m{time_s, fields.String("sensor"), 0, std::nullopt};
  const std::optional<std::size_t> index = IndexOf(header.ultrasonic, m.sensor);
  if (!index) {
    fields.Fail("sensor", "unknown ultrasonic sensor " + Quoted(m.sensor) + " (the log header lists " +
                              NameList(header.ultrasonic) + ")");
  }
  m.sensor_index = *index;
  if (!fields.Required("range_m").is_null()) m.range_m = fields.PositiveUpTo("range_m", kMaxRangeM);  // null: no echo
  return m;
}

SensorMessage ReadVio(const JsonFields& fields, const LogHeader&, double time_s) {
  constexpr double kV = kMaxAbsVelocityMps;
  return VioMessage{time_s, fields.String("sensor"), fields.NumberIn("velocity_x_mps", -kV, kV),
                    fields.NumberIn("velocity_y_mps", -kV, kV), fields.PositiveUpTo("sigma_mps", kMaxVelocitySigmaMps)};
}

using MessageParser = SensorMessage (*)(const JsonFields&, const LogHeader&, double);

constexpr std::array<std::pair<std::string_view, MessageParser>, 6> kMessageParsers{{
    {"gps", &ReadGps},
    {"imu", &ReadImu},
    {"wheels", &ReadWheels},
    {"steering", &ReadSteering},
    {"ultrasonic", &ReadUltrasonic},
    {"vio", &ReadVio},
}};

}  // namespace

SensorLogError::SensorLogError(std::string source, std::size_t line, std::string subject, std::string reason)
    : std::runtime_error(source + ":" + std::to_string(line) + ": " + subject + ": " + reason),
      source_(std::move(source)),
      line_(line),
      subject_(std::move(subject)),
      reason_(std::move(reason)) {}

LogHeader ParseLogHeader(std::string_view line, const std::string& source, std::size_t line_number) {
  const LineLocation where{source, line_number};
  const json object = ParseObject(line, where);
  const std::string type = MessageType(object, where);
  if (type != "log_header") {
    where.Fail("type", "expected \"log_header\", got " + Quoted(type) + " (a sensor log starts with its header)");
  }
  return HeaderFromFields(JsonFields(object, where, "the log_header"));
}

SensorMessage ParseSensorMessage(std::string_view line, const LogHeader& header, const std::string& source,
                                 std::size_t line_number) {
  const LineLocation where{source, line_number};
  return ParseSensorMessageObject(ParseObject(line, where), header, source, line_number);
}

SensorMessage ParseSensorMessageObject(const nlohmann::json& object, const LogHeader& header,
                                       const std::string& source, std::size_t line_number) {
  const LineLocation where{source, line_number};
  if (!object.is_object()) where.Fail("line", std::string("must be a JSON object, got ") + object.type_name());
  const std::string type = MessageType(object, where);
  const auto parser = std::find_if(kMessageParsers.begin(), kMessageParsers.end(),
                                   [&type](const auto& entry) { return entry.first == type; });
  if (parser == kMessageParsers.end()) {
    if (type == "log_header") where.Fail("type", "a second log_header (only the first line of a log is a header)");
    where.Fail("type", "unknown message type " + Quoted(type) +
                           " (rowloc/1 sensor messages: gps, imu, wheels, steering, ultrasonic, vio)");
  }
  const bool vowel = std::string_view("aeiou").find(type.front()) != std::string_view::npos;
  const JsonFields fields(object, where, (vowel ? "an " : "a ") + type + " message");
  return parser->second(fields, header, fields.Number("t"));
}

SensorLogReader::SensorLogReader(std::istream& in, std::string source)
    : in_(in), source_(std::move(source)), lines_(in, kMaxLogLineBytes), header_(ReadHeader()) {}

LogHeader SensorLogReader::ReadHeader() {
  std::string line;
  if (!ReadLine(line)) throw SensorLogError(source_, 1, "log_header", "missing (the log is empty)");
  return ParseLogHeader(line, source_, lines_.line_number());
}

std::optional<SensorMessage> SensorLogReader::Next() {
  std::string line;
  if (!ReadLine(line)) return std::nullopt;
  SensorMessage message = ParseSensorMessage(line, header_, source_, lines_.line_number());
  const double time_s = TimeOf(message);
  // A journal with a reorder window holds messages in arrival order; its reader orders them.
  if (time_s < last_time_s_ && header_.reorder_window_s == 0.0) {
    throw SensorLogError(source_, lines_.line_number(), "t",
                         FormatNumber(time_s) + " s is before the previous message's " + FormatNumber(last_time_s_) +
                             " s (time never decreases inside a log)");
  }
  last_time_s_ = time_s;
  ++messages_read_;
  return message;
}

bool SensorLogReader::ReadLine(std::string& line) {
  for (;;) {
    switch (lines_.Read(line)) {
      case BoundedLineReader::Result::kEnd:
        return false;
      case BoundedLineReader::Result::kReadError:
        throw SensorLogError(source_, lines_.line_number() + 1, "line", "read error");
      case BoundedLineReader::Result::kTooLong:
        throw SensorLogError(source_, lines_.line_number(), "line",
                             "longer than 1 MiB (" + std::to_string(kMaxLogLineBytes) + " bytes, the protocol's limit)");
      case BoundedLineReader::Result::kUnterminated:
        throw SensorLogError(source_, lines_.line_number(), "line", "not terminated by a newline (a truncated log?)");
      case BoundedLineReader::Result::kLine:
        if (!line.empty()) return true;
        break;
    }
  }
}

}  // namespace rowloc::formats
