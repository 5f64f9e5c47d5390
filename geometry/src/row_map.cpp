#include "rowloc/geometry/row_map.hpp"

// Boost 1.74's Boost.Math (pulled in by Boost.Geometry) includes a header it itself deprecated
// (as in segment_index.cpp): without this the build prints a deprecation note.
#ifndef BOOST_ALLOW_DEPRECATED_HEADERS
#define BOOST_ALLOW_DEPRECATED_HEADERS
#endif
#include <boost/geometry/algorithms/area.hpp>
#include <boost/geometry/algorithms/correct.hpp>
#include <boost/geometry/algorithms/within.hpp>
#include <boost/geometry/geometries/point_xy.hpp>
#include <boost/geometry/geometries/ring.hpp>

#include <cmath>
#include <set>
#include <stdexcept>

namespace rowloc::geometry {

namespace {

bool IsValidOrigin(const GeoOrigin& o) {
  return std::isfinite(o.latitude_deg) && std::abs(o.latitude_deg) <= 90.0 &&
         std::isfinite(o.longitude_deg) && std::abs(o.longitude_deg) <= 180.0 &&
         std::isfinite(o.altitude_m);
}

}  // namespace

std::optional<std::string> ValidateRowMap(const RowMap& map) {
  if (!IsValidOrigin(map.origin)) return "origin is not a valid WGS84 position";
  if (map.rows.empty()) return "the map has no rows";
  std::set<std::string> ids;
  for (std::size_t r = 0; r < map.rows.size(); ++r) {
    const Row& row = map.rows[r];
    const std::string where = "row " + std::to_string(r) + " ('" + row.id + "')";
    if (row.id.empty()) return "row " + std::to_string(r) + " has an empty id";
    if (!ids.insert(row.id).second) return where + ": duplicate id";
    if (!(std::isfinite(row.outline_sigma_m) && row.outline_sigma_m >= 0.0)) {
      return where + ": outline_sigma_m must be finite and >= 0";
    }
    const std::size_t min_points = row.closed ? 3 : 2;
    if (row.points_m.size() < min_points) {
      return where + ": needs at least " + std::to_string(min_points) + " vertices, has " +
             std::to_string(row.points_m.size());
    }
    for (std::size_t i = 0; i < row.points_m.size(); ++i) {
      if (!row.points_m[i].allFinite()) return where + ": vertex " + std::to_string(i) + " is not finite";
    }
    for (std::size_t s = 0; s < row.SegmentCount(); ++s) {
      const auto [a, b] = row.Segment(s);
      if ((b - a).norm() == 0.0) return where + ": segment " + std::to_string(s) + " has zero length";
    }
  }
  return std::nullopt;
}

namespace {

// Upper bounds that keep the sample generator's memory and integer arithmetic sane.
constexpr int kMaxSampleRows = 10'000;
constexpr double kMaxSampleSegmentsPerRow = 100'000.0;

void CheckSampleParams(const SampleRowMapParams& p) {
  const bool ok = p.row_count >= 1 && p.row_count <= kMaxSampleRows &&
                  std::isfinite(p.row_spacing_m) && p.row_spacing_m > 0 &&
                  std::isfinite(p.row_length_m) && p.row_length_m > 0 &&
                  std::isfinite(p.canopy_width_m) && p.canopy_width_m > 0 &&
                  p.canopy_width_m < p.row_spacing_m && std::isfinite(p.bow_m) &&
                  std::isfinite(p.heading_rad) && std::isfinite(p.vertex_spacing_m) &&
                  p.vertex_spacing_m > 0 && p.vertex_spacing_m <= p.row_length_m &&
                  p.row_length_m / p.vertex_spacing_m <= kMaxSampleSegmentsPerRow &&
                  IsValidOrigin(p.origin);
  if (!ok) throw std::invalid_argument("MakeSampleRowMap: parameters out of range");
  // The centre line's tightest radius of curvature is L^2 / (8 |bow|) (at mid-length); an outline
  // offset by more than that radius would fold over itself.
  if (std::abs(p.bow_m) * 8.0 * 0.5 * p.canopy_width_m >= p.row_length_m * p.row_length_m) {
    throw std::invalid_argument("MakeSampleRowMap: bow too large for the row length: outline folds");
  }
}

}  // namespace

RowMap MakeSampleRowMap(const SampleRowMapParams& p) {
  CheckSampleParams(p);
  const Eigen::Vector2d along(std::cos(p.heading_rad), std::sin(p.heading_rad));
  const Eigen::Vector2d across(-along.y(), along.x());
  const int segments = static_cast<int>(std::ceil(p.row_length_m / p.vertex_spacing_m));
  const double half_width = 0.5 * p.canopy_width_m;
  RowMap map;
  map.origin = p.origin;
  for (int r = 0; r < p.row_count; ++r) {
    // Centre line c(u) = u*along + (r*spacing + bow*(1 - (2u/L - 1)^2))*across, u in [0, L].
    std::vector<Eigen::Vector2d> left, right;
    for (int i = 0; i <= segments; ++i) {
      const double u = p.row_length_m * i / segments;
      const double xi = 2.0 * u / p.row_length_m - 1.0;
      const double offset = r * p.row_spacing_m + p.bow_m * (1.0 - xi * xi);
      const double slope = -2.0 * p.bow_m * xi * 2.0 / p.row_length_m;  // d offset / du
      const Eigen::Vector2d centre = u * along + offset * across;
      const Eigen::Vector2d tangent = (along + slope * across).normalized();
      const Eigen::Vector2d normal(-tangent.y(), tangent.x());
      left.push_back(centre + half_width * normal);
      right.push_back(centre - half_width * normal);
    }
    Row row;
    row.id = "row-" + std::to_string(r + 1);
    row.closed = true;
    row.points_m = right;
    row.points_m.insert(row.points_m.end(), left.rbegin(), left.rend());
    map.rows.push_back(std::move(row));
  }
  return map;
}

double OutlineSignedArea(const Row& row) {
  if (!row.closed || row.points_m.size() < 3) return 0.0;
  // An open (not repeated last vertex), counter-clockwise ring: Boost.Geometry's area is then
  // positive for counter-clockwise vertices and negative for clockwise ones.
  using BoostPoint = boost::geometry::model::d2::point_xy<double>;
  boost::geometry::model::ring<BoostPoint, false, false> ring;
  ring.reserve(row.points_m.size());
  for (const Eigen::Vector2d& p : row.points_m) ring.emplace_back(p.x(), p.y());
  return boost::geometry::area(ring);
}

bool InsideOutline(const Row& row, const Eigen::Vector2d& point) {
  if (!point.allFinite()) throw std::invalid_argument("InsideOutline: point not finite");
  if (!row.closed || row.points_m.size() < 3) return false;
  using BoostPoint = boost::geometry::model::d2::point_xy<double>;
  boost::geometry::model::ring<BoostPoint> ring;
  ring.reserve(row.points_m.size() + 1);
  for (const Eigen::Vector2d& p : row.points_m) ring.emplace_back(p.x(), p.y());
  boost::geometry::correct(ring);  // closes the ring and orders it clockwise, as the model expects
  return boost::geometry::within(BoostPoint(point.x(), point.y()), ring);
}

}  // namespace rowloc::geometry
