// Strict reading of JSON configuration objects (simulator scenarios, vehicle and filter files).
// Internal to rowloc (a detail header of mapio, shared by mapio, sim and localization sources).
//
// Every configuration file of the simulator follows the same rules (docs/simulation-scenarios.md):
// every key is required, unknown keys are rejected (so that a typo never falls back silently to a
// default), numbers must be finite, and every error names the source (file), the full key path
// (e.g. "sensors.ultrasonic.rate_hz") and the reason. JsonObjectReader implements those rules once;
// `Error` is the exception type thrown (constructible from a std::string message).
//
// Reading order decides which of several defects is reported: a key is "missing" when it is read,
// and unknown keys are reported by RejectUnknownKeys after the reads, or first by ExpectKeys (which
// also reports a misspelt key as unknown rather than the correct spelling as missing).
#pragma once

#include "rowloc/mapio/input_file.hpp"

#include <nlohmann/json.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>  // kept: includers may rely on it
#include <initializer_list>
#include <iterator>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace rowloc::mapio::detail {

/// Parses JSON text; throws Error("<source>: <what>: ...") on a syntax error or a number too large
/// for a double (`what` is "invalid JSON" unless a file format words it otherwise).
template <typename Error>
nlohmann::json ParseJsonText(std::string_view text, const std::string& source,
                             std::string_view what = "invalid JSON") {
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {  // parse_error, and out_of_range for number overflow
    throw Error(source + ": " + std::string(what) + ": " + e.what());
  }
}

/// Reads a whole configuration file through mapio::ReadInputFile (regular files only, at most
/// max_bytes, 16 MiB by default); throws Error("<path>: cannot open <what>: <OS reason>"),
/// Error("<path>: is a directory, not a regular file"), ... (input_file.hpp) if it cannot be read.
template <typename Error>
std::string ReadTextFile(const std::filesystem::path& path, const std::string& what,
                         std::uintmax_t max_bytes = kMaxConfigFileBytes) {
  try {
    return ReadInputFile(path, max_bytes, what);
  } catch (const InputFileError& e) {
    throw Error(e.what());
  }
}

template <typename Error>
class JsonObjectReader {
 public:
  using json = nlohmann::json;

  JsonObjectReader(const json& object, std::string source, std::string path)
      : object_(object), source_(std::move(source)), path_(std::move(path)) {
    if (!object_.is_object()) Fail(path_, std::string("must be an object, got ") + object_.type_name());
  }

  const std::string& source() const { return source_; }
  const std::string& path() const { return path_; }
  std::string Key(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

  bool Has(const std::string& key) const { return object_.contains(key); }
  /// True if the (required) key holds null: "this part is absent/disabled".
  bool IsNull(const std::string& key) { return Get(key).is_null(); }

  double Number(const std::string& key) {
    const json& value = Get(key);
    if (!value.is_number()) Fail(Key(key), std::string("must be a number, got ") + value.type_name());
    const double number = value.get<double>();
    if (!std::isfinite(number)) Fail(Key(key), "must be finite");
    return number;
  }

  /// A number that must lie in [low, high].
  double NumberIn(const std::string& key, double low, double high) {
    const double number = Number(key);
    if (number < low || number > high) {
      Fail(Key(key), "must be in [" + Format(low) + ", " + Format(high) + "], got " + Format(number));
    }
    return number;
  }

  std::int64_t Integer(const std::string& key, std::int64_t low, std::int64_t high) {
    const json& value = Get(key);
    if (!value.is_number_integer()) Fail(Key(key), std::string("must be an integer, got ") + value.type_name());
    const std::int64_t number = value.get<std::int64_t>();
    if (number < low || number > high) {
      Fail(Key(key), "must be in [" + std::to_string(low) + ", " + std::to_string(high) + "], got " +
                         std::to_string(number));
    }
    return number;
  }

  /// A non-negative integer that fits in 64 bits (seeds).
  std::uint64_t Unsigned(const std::string& key) {
    const json& value = Get(key);
    if (!value.is_number_unsigned()) Fail(Key(key), "must be a non-negative integer");
    return value.get<std::uint64_t>();
  }

  bool Bool(const std::string& key) {
    const json& value = Get(key);
    if (!value.is_boolean()) Fail(Key(key), std::string("must be true or false, got ") + value.type_name());
    return value.get<bool>();
  }

  std::string String(const std::string& key) {
    const json& value = Get(key);
    if (!value.is_string()) Fail(Key(key), std::string("must be a string, got ") + value.type_name());
    return value.get<std::string>();
  }

  /// A fixed-size array of finite numbers, e.g. [x, y] or [x, y, z].
  template <int N>
  Eigen::Matrix<double, N, 1> Vector(const std::string& key) {
    const json& value = Get(key);
    if (!value.is_array() || value.size() != static_cast<std::size_t>(N)) {
      Fail(Key(key), "must be an array of " + std::to_string(N) + " numbers");
    }
    Eigen::Matrix<double, N, 1> vector;
    for (int i = 0; i < N; ++i) {
      const json& item = value[static_cast<std::size_t>(i)];
      if (!item.is_number() || !std::isfinite(item.get<double>())) {
        Fail(Key(key) + "[" + std::to_string(i) + "]", "must be a finite number");
      }
      vector[i] = item.get<double>();
    }
    return vector;
  }

  /// A nested object, read with key paths "<this path>.<key>.<...>".
  JsonObjectReader Object(const std::string& key) { return JsonObjectReader(Get(key), source_, Key(key)); }

  /// The raw value of a required key (marked as used).
  const json& Value(const std::string& key) { return Get(key); }

  /// An array of min_size to max_size elements (the raw value, marked as used).
  const json& Array(const std::string& key, std::size_t min_size = 0,
                    std::size_t max_size = std::numeric_limits<std::size_t>::max()) {
    const json& value = Get(key);
    if (!value.is_array()) Fail(Key(key), std::string("must be an array, got ") + value.type_name());
    if (value.size() < min_size || value.size() > max_size) {
      Fail(Key(key), "must have " + SizeRange(min_size, max_size) + " elements, got " + std::to_string(value.size()));
    }
    return value;
  }

  /// An array of objects: read(reader) for each element, with key paths "<key>[i].<...>"; returns
  /// the results in order. `read` takes a JsonObjectReader (by value or reference).
  template <typename Read>
  auto ObjectArray(const std::string& key, Read read, std::size_t min_size = 0,
                   std::size_t max_size = std::numeric_limits<std::size_t>::max()) {
    using Item = std::decay_t<std::invoke_result_t<Read&, JsonObjectReader&>>;
    const json& value = Array(key, min_size, max_size);
    std::vector<Item> items;
    items.reserve(value.size());
    for (std::size_t i = 0; i < value.size(); ++i) {
      JsonObjectReader item(value[i], source_, Key(key) + "[" + std::to_string(i) + "]");
      items.push_back(read(item));
    }
    return items;
  }

  /// The keys of this object in order, all marked as used: for objects whose keys are names chosen
  /// by the file (profiles, classes); read each with Object(name).
  std::vector<std::string> Keys() {
    std::vector<std::string> keys;
    for (const auto& item : object_.items()) {
      used_.insert(item.key());
      keys.push_back(item.key());
    }
    return keys;
  }

  /// Checks the keys before any is read: the first key not in `keys` is an unknown key, then the
  /// first of `keys` (in their order) that is absent is a missing key. `keys`: any range of strings.
  template <typename Names>
  void ExpectKeys(const Names& keys) const {
    for (const auto& item : object_.items()) {
      const auto is_item = [&item](const auto& key) { return item.key() == key; };
      if (std::none_of(std::begin(keys), std::end(keys), is_item)) Fail(Key(item.key()), "unknown key");
    }
    for (const auto& key : keys) {
      const std::string name(key);
      if (!object_.contains(name)) Fail(Key(name), "missing key");
    }
  }
  void ExpectKeys(std::initializer_list<std::string_view> keys) const {
    ExpectKeys<std::initializer_list<std::string_view>>(keys);
  }

  /// Call after reading every field.
  void RejectUnknownKeys() const {
    for (const auto& item : object_.items()) {
      if (!used_.contains(item.key())) Fail(Key(item.key()), "unknown key");
    }
  }

  [[noreturn]] void Fail(const std::string& key_path, const std::string& reason) const {
    throw Error(source_ + ": " + (key_path.empty() ? "<root>" : key_path) + ": " + reason);
  }

 private:
  /// 15 significant digits when they read back as the same double (1e-06, 0.1), else 17.
  static std::string Format(double value) {
    for (const int digits : {std::numeric_limits<double>::digits10, std::numeric_limits<double>::max_digits10}) {
      std::ostringstream out;
      out.precision(digits);
      out << value;
      if (digits == std::numeric_limits<double>::max_digits10 || std::strtod(out.str().c_str(), nullptr) == value) {
        return out.str();
      }
    }
    return {};  // not reached
  }

  static std::string SizeRange(std::size_t min_size, std::size_t max_size) {
    if (max_size == std::numeric_limits<std::size_t>::max()) return "at least " + std::to_string(min_size);
    if (min_size == 0) return "at most " + std::to_string(max_size);
    return std::to_string(min_size) + " to " + std::to_string(max_size);
  }

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

}  // namespace rowloc::mapio::detail
