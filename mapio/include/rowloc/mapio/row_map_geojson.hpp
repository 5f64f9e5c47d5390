// Row map files in GeoJSON (RFC 7946), the format the design asks for ("Files: GeoJSON (RFC 7946 in
// WGS84, plus the local origin ...), so that GIS tools open them"). Specified, with an example,
// in docs/map-format.md. In short:
//   - a FeatureCollection with the local ENU origin in the foreign member
//     "rowloc": {"format_version": 1, "origin": {"latitude_deg", "longitude_deg", "altitude_m"}};
//   - one Feature per row, properties {"id": "<non-empty, unique>"} (other properties ignored);
//   - geometry LineString (open row) or Polygon with exactly one closed ring (closed row; the
//     closing position, equal to the first, is not stored in geometry::Row);
//   - positions [longitude_deg, latitude_deg, altitude_m] in WGS84; a 2-element position is at
//     the origin altitude. Positions are converted with mapio::LocalFrame (GeographicLib
//     LocalCartesian) and projected on the tangent plane (the ENU z is dropped);
//   - the writer stores the point of the tangent plane (z = 0), rounded to 1e-12 deg and 1e-6 m,
//     so write -> read reproduces local coordinates to better than 1e-7 m.
#pragma once

#include "rowloc/geometry/row_map.hpp"
#include "rowloc/mapio/map_format_error.hpp"

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

namespace rowloc::mapio {

/// Version written in "rowloc"."format_version"; the reader accepts only this one.
inline constexpr int kRowMapFormatVersion = 1;

/// Limits of the reader (docs/map-format.md, "Limits"): a row of more vertices, or a map of more
/// vertices in all, is refused before its positions are read. 10^5 vertices are a 1 km row with a
/// vertex every centimetre; the file itself is limited to kMaxRowMapFileBytes (input_file.hpp).
inline constexpr std::size_t kMaxRowVertices = 100'000;
inline constexpr std::size_t kMaxMapVertices = 1'000'000;

/// Parses a row map. The result always passes geometry::ValidateRowMap. Throws MapFormatError
/// naming source_name, the location and the reason for any problem (syntax, structure, values).
geometry::RowMap ParseRowMapGeoJson(std::string_view text, std::string_view source_name = "<string>");

/// Reads and parses a file; throws MapFormatError also when it cannot be read.
geometry::RowMap ReadRowMapGeoJson(const std::filesystem::path& path);

/// The GeoJSON text of a map (one Feature per line). Throws std::invalid_argument if
/// geometry::ValidateRowMap rejects the map, an id is not valid UTF-8, or two neighbouring
/// vertices are so close (< ~1e-7 m) that they round to the same position in the file.
std::string FormatRowMapGeoJson(const geometry::RowMap& map);

/// Writes FormatRowMapGeoJson(map) atomically: a temporary file in the same directory is
/// written, flushed to disk (fsync) and renamed over path, so readers see the old or the new
/// file, never a partial one (mapio::OutputFile). Throws std::invalid_argument as
/// FormatRowMapGeoJson (nothing is written then) and OutputFileError (naming the file and the OS
/// reason) on I/O failure or when path exists and is not a regular file (a device, a directory).
void WriteRowMapGeoJson(const geometry::RowMap& map, const std::filesystem::path& path);

}  // namespace rowloc::mapio
