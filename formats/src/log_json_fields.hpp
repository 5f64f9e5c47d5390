// Checked access to the keys of one JSON object of a sensor log line (private to formats/src;
// used by sensor_log_reader.cpp). Every failure throws SensorLogError located at the line, with the
// key path ("origin.latitude_deg") as subject: docs/protocol.md requires that missing keys, wrong
// types and non-finite numbers "name the line and the key". Unknown keys are never looked at.
#pragma once

#include "rowloc/formats/sensor_log_reader.hpp"

#include <nlohmann/json.hpp>

#include <charconv>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

namespace rowloc::formats::detail {

/// Where a line came from: the input's name and the 1-based line number.
struct LineLocation {
  const std::string& source;
  std::size_t line;

  [[noreturn]] void Fail(std::string subject, std::string reason) const {
    throw SensorLogError(source, line, std::move(subject), std::move(reason));
  }
};

/// Shortest text that reads back as the same double (as the writers print numbers).
inline std::string FormatNumber(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

class JsonFields {
 public:
  using json = nlohmann::json;

  /// `owner` completes "missing (required in <owner>)", e.g. "a gps message"; `prefix` is the key
  /// path of this object inside the line ("" for the line's object).
  JsonFields(const json& object, const LineLocation& where, std::string owner, std::string prefix = "")
      : object_(object), where_(where), owner_(std::move(owner)), prefix_(std::move(prefix)) {
    if (!object_.is_object()) Fail("", std::string("must be a JSON object, got ") + object_.type_name());
  }

  const json& object() const { return object_; }
  const LineLocation& where() const { return where_; }
  std::string Path(const std::string& key) const {
    if (key.empty()) return prefix_.empty() ? "line" : prefix_;
    return prefix_.empty() ? key : prefix_ + "." + key;
  }

  [[noreturn]] void Fail(const std::string& key, std::string reason) const {
    where_.Fail(Path(key), std::move(reason));
  }

  const json& Required(const std::string& key) const {
    const auto it = object_.find(key);
    if (it == object_.end()) Fail(key, "missing (required in " + owner_ + ")");
    return *it;
  }

  double Number(const std::string& key) const {
    const json& value = Required(key);
    if (!value.is_number()) Fail(key, std::string("must be a number, got ") + value.type_name());
    const double number = value.get<double>();
    if (!std::isfinite(number)) Fail(key, "must be a finite number");
    return number;
  }

  /// A number in [low, high].
  double NumberIn(const std::string& key, double low, double high) const {
    const double number = Number(key);
    if (number < low || number > high) {
      Fail(key, FormatNumber(number) + " is not in [" + FormatNumber(low) + ", " + FormatNumber(high) + "]");
    }
    return number;
  }

  double Positive(const std::string& key) const {
    const double number = Number(key);
    if (!(number > 0.0)) Fail(key, "must be positive, got " + FormatNumber(number));
    return number;
  }

  /// A number in (0, high].
  double PositiveUpTo(const std::string& key, double high) const {
    const double number = Positive(key);
    if (number > high) Fail(key, FormatNumber(number) + " is not in (0, " + FormatNumber(high) + "]");
    return number;
  }

  std::string String(const std::string& key) const {
    const json& value = Required(key);
    if (!value.is_string()) Fail(key, std::string("must be a string, got ") + value.type_name());
    return value.get<std::string>();
  }

  /// A nested object, whose keys are reported as "<this path>.<key>".
  JsonFields Object(const std::string& key) const {
    const json& value = Required(key);
    if (!value.is_object()) Fail(key, std::string("must be an object, got ") + value.type_name());
    return JsonFields(value, where_, owner_, Path(key));
  }

 private:
  const json& object_;
  LineLocation where_;
  std::string owner_;
  std::string prefix_;
};

}  // namespace rowloc::formats::detail
