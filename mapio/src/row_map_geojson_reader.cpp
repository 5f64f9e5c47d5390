// Reader of row map GeoJSON files (docs/map-format.md). Three stages, each with its own errors:
// bytes (ReadRowMapGeoJson), JSON syntax (ParseJsonText: line:column from the parser's byte
// offset, duplicate object keys, numeric overflow) and content (RowMapReader: structure, values,
// geometry), all reported as MapFormatError.
#include "rowloc/mapio/input_file.hpp"
#include "rowloc/mapio/local_frame.hpp"
#include "rowloc/mapio/row_map_geojson.hpp"

#include "rowloc/geometry/row_outline_validity.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <set>
#include <utility>
#include <vector>

namespace rowloc::mapio {
namespace {

using Json = nlohmann::json;

/// 'text' (built with append: GCC 12 warns falsely (-Wrestrict) on "'" + std::string).
std::string Quoted(std::string_view text) {
  std::string quoted;
  quoted.reserve(text.size() + 2);
  quoted.append(1, '\'').append(text).append(1, '\'');
  return quoted;
}

// --- JSON text ----------------------------------------------------------------------------

/// "line:column" (both 1-based) of a 0-based byte offset into text.
std::string LineColumn(std::string_view text, std::size_t offset) {
  offset = std::min(offset, text.size());
  const std::string_view before = text.substr(0, offset);
  const std::size_t line = 1 + static_cast<std::size_t>(std::count(before.begin(), before.end(), '\n'));
  const std::size_t line_start = before.rfind('\n') == std::string_view::npos ? 0 : before.rfind('\n') + 1;
  return std::to_string(line) + ":" + std::to_string(offset - line_start + 1);
}

/// A hint when the parser stopped on NaN or Infinity, which JSON (RFC 8259 §6) does not have.
std::string NonFiniteHint(std::string_view text, std::size_t offset) {
  const auto is_word = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '+' || c == '.'; };
  if (offset >= text.size()) return "";
  std::size_t begin = offset, end = offset;
  while (begin > 0 && is_word(text[begin - 1])) --begin;
  while (end < text.size() && is_word(text[end])) ++end;
  std::string word(text.substr(begin, end - begin));
  if (!word.empty() && (word[0] == '-' || word[0] == '+')) word.erase(0, 1);
  std::transform(word.begin(), word.end(), word.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (word.rfind("nan", 0) == 0 || word.rfind("inf", 0) == 0) {
    return " (JSON has no NaN or Infinity: every coordinate must be a finite number)";
  }
  return "";
}

/// text with bytes outside printable ASCII written as \xNN: parser messages quote the input,
/// which may be invalid UTF-8, and the message must stay valid text (e.g. in a JSON reply).
std::string PrintableAscii(std::string_view text) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  std::string out;
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte < 0x7F) {
      out += c;
    } else {
      out += "\\x";
      out += kHex[byte >> 4];
      out += kHex[byte & 0xF];
    }
  }
  return out;
}

/// Tracks the JSON Pointer (RFC 6901) of the value being parsed, and rejects duplicate keys,
/// which nlohmann::json would silently resolve by keeping the last one.
class PathTracker {
 public:
  struct DuplicateKey {
    std::string path;
    std::string key;
  };

  bool OnEvent(Json::parse_event_t event, const Json& parsed) {
    switch (event) {
      case Json::parse_event_t::object_start: frames_.push_back(Frame{false, 0, "", {}}); break;
      case Json::parse_event_t::array_start: frames_.push_back(Frame{true, 0, "", {}}); break;
      case Json::parse_event_t::key: OnKey(parsed.get<std::string>()); break;
      case Json::parse_event_t::object_end:
      case Json::parse_event_t::array_end:
        if (!frames_.empty()) frames_.pop_back();
        CountElement();
        break;
      case Json::parse_event_t::value: CountElement(); break;
    }
    return true;
  }

  /// Pointer of the value being parsed ("" for the root).
  std::string Path() const {
    std::string path;
    for (const Frame& f : frames_) {
      path += '/';
      path += f.is_array ? std::to_string(f.next_index) : EscapeToken(f.key);
    }
    return path;
  }

 private:
  struct Frame {
    bool is_array;
    std::size_t next_index;
    std::string key;
    std::set<std::string> keys;
  };

  /// RFC 6901 §3: '~' -> "~0", '/' -> "~1".
  static std::string EscapeToken(const std::string& key) {
    std::string token;
    for (const char c : key) {
      if (c == '~') {
        token += "~0";
      } else if (c == '/') {
        token += "~1";
      } else {
        token += c;
      }
    }
    return token;
  }

  void OnKey(const std::string& key) {
    if (frames_.empty()) return;
    if (!frames_.back().keys.insert(key).second) {
      frames_.back().key = key;
      throw DuplicateKey{Path(), key};
    }
    frames_.back().key = key;
  }
  void CountElement() {
    if (!frames_.empty() && frames_.back().is_array) ++frames_.back().next_index;
  }

  std::vector<Frame> frames_;
};

Json ParseJsonText(std::string_view text, const std::string& source) {
  PathTracker tracker;
  try {
    return Json::parse(text.begin(), text.end(),
                       [&tracker](int /*depth*/, Json::parse_event_t event, Json& parsed) {
                         return tracker.OnEvent(event, parsed);
                       });
  } catch (const Json::parse_error& e) {
    const std::size_t offset = e.byte > 0 ? e.byte - 1 : 0;
    std::string what = e.what();
    const std::size_t syntax = what.find("syntax error");
    if (syntax != std::string::npos) what.erase(0, syntax);
    throw MapFormatError(source, LineColumn(text, offset),
                         "JSON " + PrintableAscii(what) + NonFiniteHint(text, offset));
  } catch (const PathTracker::DuplicateKey& e) {
    throw MapFormatError(source, "JSON value " + e.path,
                         "duplicate key " + Quoted(e.key) + " in an object (JSON objects need unique keys)");
  } catch (const Json::exception& e) {  // e.g. out_of_range 406: a number too large for a double
    throw MapFormatError(source, "JSON value " + tracker.Path(), "invalid JSON: " + PrintableAscii(e.what()));
  }
}

// --- content ------------------------------------------------------------------------------

struct Position {
  double longitude_deg;
  double latitude_deg;
  double altitude_m;
  bool operator==(const Position&) const = default;
};

/// Reads the content of a parsed document; every Fail names the source and the location.
class RowMapReader {
 public:
  explicit RowMapReader(std::string source) : source_(std::move(source)) {}

  geometry::RowMap Read(const Json& root) {
    location_ = "top level";
    if (!root.is_object()) Fail("expected a GeoJSON FeatureCollection object, got " + TypeOf(root));
    const std::string type = RequireString(root, "type", "\"type\"");
    if (type != "FeatureCollection") {
      Fail("expected a GeoJSON \"FeatureCollection\", got \"type\": " + Quoted(type) +
           " (a row map is a FeatureCollection with one Feature per row)");
    }
    geometry::RowMap map;
    map.origin = ReadOrigin(root);
    const LocalFrame frame(map.origin);
    const Json* features = Find(root, "features");
    if (features == nullptr || !features->is_array()) {
      Fail("\"features\" must be an array, got " + TypeOf(features));
    }
    if (features->empty()) Fail("the FeatureCollection has no features; a row map needs at least one row");
    std::map<std::string, std::size_t> first_use;
    for (std::size_t i = 0; i < features->size(); ++i) {
      geometry::Row row = ReadFeature((*features)[i], i, frame);
      const auto [it, inserted] = first_use.emplace(row.id, i);
      if (!inserted) Fail("duplicate id " + Quoted(row.id) + " (also used by feature " + std::to_string(it->second) + ")");
      map.rows.push_back(std::move(row));
    }
    location_ = "top level";
    if (const auto problem = geometry::ValidateRowMap(map)) Fail("invalid row map: " + *problem);  // safety net
    return map;
  }

 private:
  [[noreturn]] void Fail(const std::string& reason) const { throw MapFormatError(source_, location_, reason); }

  static std::string TypeOf(const Json* value) {
    return value == nullptr ? "nothing (missing)" : std::string(value->type_name());
  }
  static std::string TypeOf(const Json& value) { return TypeOf(&value); }

  static const Json* Find(const Json& object, const char* key) {
    const auto it = object.find(key);
    return it == object.end() ? nullptr : &*it;
  }

  std::string RequireString(const Json& object, const char* key, const std::string& name) const {
    const Json* value = Find(object, key);
    if (value == nullptr) Fail(name + " is missing");
    if (!value->is_string()) Fail(name + " must be a string, got " + TypeOf(value));
    return value->get<std::string>();
  }

  double RequireNumber(const Json* value, const std::string& name) const {
    if (value == nullptr) Fail(name + " is missing");
    if (!value->is_number()) Fail(name + " must be a number, got " + TypeOf(value));
    const double number = value->get<double>();
    if (!std::isfinite(number)) Fail(name + " is not finite");
    return number;
  }

  geometry::GeoOrigin ReadOrigin(const Json& root) const {
    const Json* rowloc = Find(root, "rowloc");
    if (rowloc == nullptr) {
      Fail("missing the \"rowloc\" member with the local origin: \"rowloc\": {\"format_version\": 1, "
           "\"origin\": {\"latitude_deg\": .., \"longitude_deg\": .., \"altitude_m\": ..}}");
    }
    if (!rowloc->is_object()) Fail("\"rowloc\" must be an object, got " + TypeOf(rowloc));
    const Json* version = Find(*rowloc, "format_version");
    if (version == nullptr) Fail("\"rowloc\".\"format_version\" is missing");
    if (!version->is_number_integer()) Fail("\"rowloc\".\"format_version\" must be an integer, got " + version->dump());
    if (version->get<long long>() != kRowMapFormatVersion) {
      Fail("unsupported \"rowloc\".\"format_version\" " + version->dump() + " (this reader understands " +
           std::to_string(kRowMapFormatVersion) + ")");
    }
    const Json* origin = Find(*rowloc, "origin");
    if (origin == nullptr) Fail("missing the local origin \"rowloc\".\"origin\"");
    if (!origin->is_object()) Fail("\"rowloc\".\"origin\" must be an object, got " + TypeOf(origin));
    geometry::GeoOrigin o;
    o.latitude_deg = RequireNumber(Find(*origin, "latitude_deg"), "\"rowloc\".\"origin\".\"latitude_deg\"");
    o.longitude_deg = RequireNumber(Find(*origin, "longitude_deg"), "\"rowloc\".\"origin\".\"longitude_deg\"");
    o.altitude_m = RequireNumber(Find(*origin, "altitude_m"), "\"rowloc\".\"origin\".\"altitude_m\"");
    const std::string problem = GeodeticPositionProblem(o.latitude_deg, o.longitude_deg, o.altitude_m);
    if (!problem.empty()) Fail("\"rowloc\".\"origin\": " + problem);
    return o;
  }

  geometry::Row ReadFeature(const Json& feature, std::size_t index, const LocalFrame& frame) {
    location_ = "feature " + std::to_string(index);
    if (!feature.is_object()) Fail("a feature must be an object, got " + TypeOf(feature));
    const std::string type = RequireString(feature, "type", "\"type\"");
    if (type != "Feature") Fail("expected \"type\": \"Feature\", got " + Quoted(type));
    geometry::Row row;
    row.id = ReadId(feature);
    location_ += " (id " + Quoted(row.id) + ")";
    row.outline_sigma_m = ReadOutlineSigma(*Find(feature, "properties"));
    const Json* geometry = Find(feature, "geometry");
    if (geometry == nullptr || geometry->is_null()) Fail("the feature has no geometry");
    if (!geometry->is_object()) Fail("\"geometry\" must be an object, got " + TypeOf(geometry));
    const std::string geometry_type = RequireString(*geometry, "type", "\"geometry\".\"type\"");
    if (geometry_type != "LineString" && geometry_type != "Polygon") {
      Fail("geometry type " + Quoted(geometry_type) +
           " is not supported: a row is a LineString (open row) or a Polygon (closed outline)");
    }
    const Json* coordinates = Find(*geometry, "coordinates");
    if (coordinates == nullptr || coordinates->is_null()) Fail("the " + geometry_type + " has no \"coordinates\"");
    if (!coordinates->is_array()) Fail("\"coordinates\" must be an array, got " + TypeOf(coordinates));
    row.closed = geometry_type == "Polygon";
    row.points_m = row.closed ? ReadPolygon(*coordinates, frame) : ReadLineString(*coordinates, frame);
    if (const auto defect = geometry::RowOutlineDefect(row)) Fail(*defect);
    return row;
  }

  std::string ReadId(const Json& feature) const {
    const Json* properties = Find(feature, "properties");
    if (properties == nullptr || properties->is_null()) Fail("the feature has no \"properties\" with the row \"id\"");
    if (!properties->is_object()) Fail("\"properties\" must be an object, got " + TypeOf(properties));
    const Json* id = Find(*properties, "id");
    if (id == nullptr) Fail("\"properties\".\"id\" is missing (every row needs a unique id)");
    if (!id->is_string()) Fail("\"properties\".\"id\" must be a string, got " + TypeOf(id) + " " + id->dump());
    if (id->get_ref<const std::string&>().empty()) Fail("\"properties\".\"id\" is empty");
    return id->get<std::string>();
  }

  /// The optional "outline_sigma_m" property: a finite number >= 0 (0 when absent).
  double ReadOutlineSigma(const Json& properties) const {
    const Json* sigma = Find(properties, "outline_sigma_m");
    if (sigma == nullptr) return 0.0;
    const double value = RequireNumber(sigma, "\"properties\".\"outline_sigma_m\"");
    if (value < 0.0) Fail("\"properties\".\"outline_sigma_m\" must be >= 0, got " + sigma->dump());
    return value;
  }

  std::vector<Eigen::Vector2d> ReadLineString(const Json& coordinates, const LocalFrame& frame) {
    if (coordinates.size() < 2) {
      Fail("a LineString row needs at least 2 positions, has " + std::to_string(coordinates.size()));
    }
    CountVertices(coordinates.size());
    return ToLocal(ReadPositions(coordinates, "coordinates", frame), "coordinates", frame);
  }

  std::vector<Eigen::Vector2d> ReadPolygon(const Json& rings, const LocalFrame& frame) {
    if (rings.empty()) Fail("the Polygon has no ring");
    if (!rings[0].is_array() || (!rings[0].empty() && !rings[0][0].is_array())) {
      // Not a ring inside: a flat list of positions (a common slip), or of something else.
      const bool flat = rings[0].is_array() && rings[0][0].is_number();
      Fail("\"coordinates\" of a Polygon must be an array of rings (arrays of [longitude, latitude] positions), got " +
           (flat ? std::string("an array of positions (write \"coordinates\": [[[lon, lat], ...]], one ring)")
                 : "coordinates[0] = " + TypeOf(rings[0]) + (rings[0].is_array() ? " of " + TypeOf(rings[0][0]) : "")));
    }
    if (rings.size() > 1) {
      Fail("the Polygon has " + std::to_string(rings.size() - 1) +
           " hole(s) (interior rings); a row outline must be a single ring without holes");
    }
    const Json& ring = rings[0];
    if (!ring.is_array()) Fail("coordinates[0] (the ring) must be an array, got " + TypeOf(ring));
    if (ring.size() < 4) {
      Fail("a Polygon ring needs at least 4 positions (3 vertices and the closing copy of the first), has " +
           std::to_string(ring.size()));
    }
    CountVertices(ring.size() - 1);
    const std::vector<Position> positions = ReadPositions(ring, "coordinates[0]", frame);
    if (!(positions.front() == positions.back())) {
      Fail("the Polygon ring is not closed: its last position coordinates[0][" + std::to_string(ring.size() - 1) +
           "] differs from the first (RFC 7946 §3.1.6 requires identical values)");
    }
    std::vector<Eigen::Vector2d> points = ToLocal(positions, "coordinates[0]", frame);
    points.pop_back();  // geometry::Row stores a closed ring without the repeated vertex
    return points;
  }

  std::vector<Position> ReadPositions(const Json& array, const std::string& name, const LocalFrame& frame) const {
    std::vector<Position> positions;
    positions.reserve(array.size());
    for (std::size_t i = 0; i < array.size(); ++i) {
      positions.push_back(ReadPosition(array[i], name + "[" + std::to_string(i) + "]", frame));
    }
    return positions;
  }

  Position ReadPosition(const Json& position, const std::string& name, const LocalFrame& frame) const {
    if (!position.is_array()) Fail(name + " must be a position [longitude, latitude(, altitude)], got " + TypeOf(position));
    if (position.size() != 2 && position.size() != 3) {
      Fail(name + " has " + std::to_string(position.size()) +
           " elements; a position is [longitude, latitude] or [longitude, latitude, altitude]");
    }
    static constexpr const char* kAxes[] = {"longitude", "latitude", "altitude"};
    double values[3] = {0.0, 0.0, frame.origin().altitude_m};
    for (std::size_t k = 0; k < position.size(); ++k) {
      values[k] = RequireNumber(&position[k], name + "[" + std::to_string(k) + "] (" + kAxes[k] + ")");
    }
    const std::string problem = GeodeticPositionProblem(values[1], values[0], values[2]);
    if (!problem.empty()) Fail(name + ": " + problem);
    return Position{values[0], values[1], values[2]};
  }

  /// Positions -> ENU metres, dropping z; rejects consecutive positions at the same point.
  std::vector<Eigen::Vector2d> ToLocal(const std::vector<Position>& positions, const std::string& name,
                                       const LocalFrame& frame) const {
    std::vector<Eigen::Vector2d> points;
    points.reserve(positions.size());
    for (const Position& p : positions) {
      points.push_back(frame.ToEnu(p.latitude_deg, p.longitude_deg, p.altitude_m).head<2>());
      const std::size_t i = points.size() - 1;
      if (i > 0 && points[i] == points[i - 1]) {
        Fail(name + "[" + std::to_string(i - 1) + "] and " + name + "[" + std::to_string(i) +
             "] are the same point (zero-length segment)");
      }
    }
    return points;
  }

  /// Counts a row's vertices against kMaxRowVertices and the map's against kMaxMapVertices, before
  /// they are read (no memory is spent on a row that is refused).
  void CountVertices(std::size_t count) {
    if (count > kMaxRowVertices) {
      Fail("the row has " + std::to_string(count) + " vertices, more than the limit of " +
           std::to_string(kMaxRowVertices) + " per row (docs/map-format.md, \"Limits\")");
    }
    map_vertices_ += count;
    if (map_vertices_ > kMaxMapVertices) {
      Fail("the map has more than the limit of " + std::to_string(kMaxMapVertices) +
           " vertices in all (docs/map-format.md, \"Limits\")");
    }
  }

  std::string source_;
  std::string location_;
  std::size_t map_vertices_ = 0;
};

/// The whole content of a regular file of at most kMaxRowMapFileBytes, or MapFormatError with
/// the reason (the system's, or the file's kind or size: input_file.hpp).
std::string ReadFileBytes(const std::filesystem::path& path) {
  try {
    return ReadInputFile(path, kMaxRowMapFileBytes, "row map file");
  } catch (const InputFileError& e) {
    throw MapFormatError(path.string(), "", e.reason());
  }
}

}  // namespace

geometry::RowMap ParseRowMapGeoJson(std::string_view text, std::string_view source_name) {
  const std::string source(source_name);
  return RowMapReader(source).Read(ParseJsonText(text, source));
}

geometry::RowMap ReadRowMapGeoJson(const std::filesystem::path& path) {
  return ParseRowMapGeoJson(ReadFileBytes(path), path.string());
}

}  // namespace rowloc::mapio
