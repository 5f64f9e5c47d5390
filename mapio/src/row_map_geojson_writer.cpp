// Writer of row map GeoJSON files (docs/map-format.md): validation, conversion of every vertex
// from the local ENU plane (z = 0) to WGS84 with mapio::LocalFrame, one Feature per line, and an
// atomic replace of the target file (mapio::OutputFile: a temporary file, fsync, rename(2); never over
// a device or directory).
#include "rowloc/mapio/local_frame.hpp"
#include "rowloc/mapio/output_file.hpp"
#include "rowloc/mapio/row_map_geojson.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <stdexcept>

namespace rowloc::mapio {
namespace {

using OrderedJson = nlohmann::ordered_json;  // keeps "type" first, as GeoJSON files usually do

OrderedJson RowlocMember(const geometry::GeoOrigin& origin) {
  return OrderedJson{{"format_version", kRowMapFormatVersion},
                     {"origin",
                      {{"latitude_deg", origin.latitude_deg},
                       {"longitude_deg", origin.longitude_deg},
                       {"altitude_m", origin.altitude_m}}}};
}

/// value rounded to a multiple of 10^-decimals; prints as the short decimal (the division of two
/// exact integers is correctly rounded, so the result is the double nearest to that decimal).
double RoundToDecimals(double value, int decimals) {
  const double scale = std::pow(10.0, decimals);
  return std::round(value * scale) / scale;
}

/// Decimals written: 1e-12 deg is 0.11 um on the ground and 1e-6 m of altitude moves a point of
/// the tangent plane sideways by far less, so the rounding error stays under 1e-7 m (the format
/// promises 1e-6 m) while the file stays readable.
constexpr int kDegreeDecimals = 12;
constexpr int kAltitudeDecimals = 6;

/// [longitude, latitude, altitude] of the tangent-plane point (x, y, 0). Writing the altitude of
/// the plane (not the origin's) makes the reader's ToEnu return (x, y, ~0).
OrderedJson PositionJson(const Eigen::Vector2d& point_m, const LocalFrame& frame) {
  const geometry::GeoOrigin g = frame.ToGeodetic(Eigen::Vector3d(point_m.x(), point_m.y(), 0.0));
  return OrderedJson::array({RoundToDecimals(g.longitude_deg, kDegreeDecimals),
                             RoundToDecimals(g.latitude_deg, kDegreeDecimals),
                             RoundToDecimals(g.altitude_m, kAltitudeDecimals)});
}

OrderedJson FeatureJson(const geometry::Row& row, const LocalFrame& frame) {
  OrderedJson positions = OrderedJson::array();
  for (const Eigen::Vector2d& p : row.points_m) {
    positions.push_back(PositionJson(p, frame));
    const std::size_t n = positions.size();
    const bool closing = row.closed && n == row.points_m.size();
    if ((n > 1 && positions[n - 1] == positions[n - 2]) || (closing && positions[n - 1] == positions[0])) {
      // ValidateRowMap only rejects exactly zero-length segments; the reader would reject these.
      throw std::invalid_argument("FormatRowMapGeoJson: row '" + row.id + "': vertex " + std::to_string(n - 1) +
                                  " is too close to its neighbour to be told apart in the file (1e-12 deg)");
    }
  }
  OrderedJson geometry;
  if (row.closed) {
    positions.push_back(positions.front());  // RFC 7946 §3.1.6: the ring repeats its first position
    geometry = OrderedJson{{"type", "Polygon"}, {"coordinates", OrderedJson::array({positions})}};
  } else {
    geometry = OrderedJson{{"type", "LineString"}, {"coordinates", positions}};
  }
  OrderedJson properties = {{"id", row.id}};
  if (row.outline_sigma_m > 0.0) properties["outline_sigma_m"] = row.outline_sigma_m;
  return OrderedJson{{"type", "Feature"}, {"properties", properties}, {"geometry", geometry}};
}

}  // namespace

std::string FormatRowMapGeoJson(const geometry::RowMap& map) {
  if (const auto problem = geometry::ValidateRowMap(map)) {
    throw std::invalid_argument("FormatRowMapGeoJson: invalid row map: " + *problem);
  }
  const LocalFrame frame(map.origin);
  std::string text = "{\n\"type\": \"FeatureCollection\",\n\"rowloc\": " + RowlocMember(map.origin).dump() +
                     ",\n\"features\": [\n";
  for (std::size_t r = 0; r < map.rows.size(); ++r) {
    try {
      text += FeatureJson(map.rows[r], frame).dump();  // may throw std::invalid_argument
    } catch (const nlohmann::json::type_error& e) {  // 316: a string that is not valid UTF-8
      throw std::invalid_argument("FormatRowMapGeoJson: row " + std::to_string(r) +
                                  ": id is not valid UTF-8 (" + e.what() + ")");
    }
    text += r + 1 < map.rows.size() ? ",\n" : "\n";
  }
  text += "]\n}\n";
  return text;
}

void WriteRowMapGeoJson(const geometry::RowMap& map, const std::filesystem::path& path) {
  const std::string text = FormatRowMapGeoJson(map);  // throws before anything touches the disk
  WriteFileAtomically(path, text);                      // checked target, temporary, fsync, rename
}

}  // namespace rowloc::mapio
