// Row map: the crop rows of a field as 2-D polylines or closed polygons in a local
// East-North-Up frame, plus the WGS84 origin of that frame (docs/map-format.md).
//
// A row is the outline of the canopy at the slice height h_ref above the terrain: either an
// open polyline (one side of a row, or its centre line) or a closed polygon (the whole outline).
// Coordinates are metres East (x) and North (y) of the origin. The file format (GeoJSON) lives
// in rowloc::mapio; this header is plain data so that localization can use it without I/O.
#pragma once

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace rowloc::geometry {

/// Georeferenced origin of the local ENU frame (WGS84 ellipsoid).
struct GeoOrigin {
  double latitude_deg = 0.0;   ///< geodetic latitude, degrees north, in [-90, 90]
  double longitude_deg = 0.0;  ///< longitude, degrees east, in [-180, 180]
  double altitude_m = 0.0;     ///< height above the WGS84 ellipsoid, metres
};

/// One row of the map.
struct Row {
  std::string id;                        ///< unique, non-empty identifier
  std::vector<Eigen::Vector2d> points_m; ///< vertices in local ENU metres, >= 2 (>= 3 if closed)
  bool closed = false;                   ///< true: polygon (last vertex joins the first)
  /// Accuracy of the outline across it, m (1 sigma of its distance from the canopy surface it
  /// stands for, as its map build estimated it); 0: exact or unknown. The map-aided update adds
  /// it to the range noise of echoes from this row.
  double outline_sigma_m = 0.0;

  /// Number of segments: n-1 for a polyline, n for a polygon.
  std::size_t SegmentCount() const {
    if (points_m.size() < 2) return 0;
    return closed ? points_m.size() : points_m.size() - 1;
  }
  /// Endpoints of segment i (0 <= i < SegmentCount()).
  std::pair<Eigen::Vector2d, Eigen::Vector2d> Segment(std::size_t i) const {
    return {points_m[i], points_m[(i + 1) % points_m.size()]};
  }
};

/// A complete row map.
struct RowMap {
  GeoOrigin origin;
  std::vector<Row> rows;

  std::size_t SegmentCount() const {
    std::size_t n = 0;
    for (const Row& r : rows) n += r.SegmentCount();
    return n;
  }
};

/// Why a row map is not usable; empty if it is. Checks: at least one row, non-empty unique ids,
/// >= 2 vertices (>= 3 when closed), finite coordinates, no zero-length segment, origin in range,
/// outline_sigma_m finite and >= 0.
/// Not checked: self-intersecting or zero-area polygons (they are still usable as sets of
/// reflecting segments, which is all that localization needs).
std::optional<std::string> ValidateRowMap(const RowMap& map);

/// Whether `point` lies strictly inside a closed row's outline (Boost.Geometry `within`, either
/// vertex order); false for an open row and for a point on the outline. A self-intersecting
/// outline gives Boost.Geometry's answer for it. Throws std::invalid_argument for a non-finite
/// point.
bool InsideOutline(const Row& row, const Eigen::Vector2d& point);

/// Signed area of a closed row's outline, m^2: > 0 when its vertices run counter-clockwise
/// (Boost.Geometry `area`); 0 for an open row.
double OutlineSignedArea(const Row& row);

/// Parameters of the synthetic sample map shipped in maps/ (see docs/map-format.md, "The sample map").
struct SampleRowMapParams {
  int row_count = 10;               ///< number of rows
  double row_spacing_m = 2.5;       ///< distance between neighbouring row centre lines
  double row_length_m = 50.0;       ///< length of every row along its chord
  double canopy_width_m = 0.5;      ///< width of the canopy outline at slice height
  double bow_m = 0.6;               ///< lateral sag of the rows at mid-length (0: straight)
  double heading_rad = 0.35;        ///< direction of the rows, from +East counter-clockwise
  double vertex_spacing_m = 2.0;    ///< distance between polyline vertices along a row
  GeoOrigin origin{45.0703, 7.6869, 240.0};
};

/// Builds slightly curved rows as closed canopy outlines (polygons): every row centre line is
/// the chord direction plus a parabolic sag of bow_m at mid-length, and the outline is that line
/// offset by +-canopy_width_m/2 along its normal. Throws std::invalid_argument on bad parameters:
/// non-finite or non-positive sizes, canopy as wide as the spacing, more than 10^4 rows or 10^5
/// segments per row, an invalid origin, or a bow so large that the outline would fold.
RowMap MakeSampleRowMap(const SampleRowMapParams& params);

}  // namespace rowloc::geometry
