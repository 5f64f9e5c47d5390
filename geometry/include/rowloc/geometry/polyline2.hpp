// Polyline2: an open polyline or a closed polygon of the plane (a row of the row map, row_map.hpp),
// with the queries of segment2.hpp, ray_cast.hpp and cone_cast.hpp (docs/planar-geometry.md).
//
// Segment i joins vertex i to vertex i+1 (for a polygon the last segment joins the last vertex to
// the first). Every query is the minimum over the segments of the per-segment query, so the
// semantics are those of the segment functions; at a shared vertex both segments meet at the same
// range and the lower segment index is reported. For a polygon the distance is the distance to
// its boundary (0 only on the boundary), not to its interior. Queries scan the polyline's own
// segments (O(number of segments)); for a whole map use SegmentIndex, which is O(log N).
#pragma once

#include "rowloc/geometry/cone_cast.hpp"
#include "rowloc/geometry/ray_cast.hpp"
#include "rowloc/geometry/row_map.hpp"
#include "rowloc/geometry/segment2.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <optional>
#include <vector>

namespace rowloc::geometry {

class Polyline2 {
 public:
  /// Throws std::invalid_argument unless there are >= 2 vertices (>= 3 if closed), all finite,
  /// and no segment has zero length.
  Polyline2(std::vector<Eigen::Vector2d> vertices, bool closed);

  /// The outline of a row map row (same checks).
  static Polyline2 FromRow(const Row& row);

  const std::vector<Eigen::Vector2d>& vertices() const { return vertices_; }
  bool closed() const { return closed_; }

  /// n - 1 for an open polyline, n for a polygon.
  std::size_t SegmentCount() const { return closed_ ? vertices_.size() : vertices_.size() - 1; }

  /// Segment i, 0 <= i < SegmentCount(); throws std::out_of_range otherwise.
  Segment2 Segment(std::size_t i) const;

  /// Total length (perimeter for a polygon), metres.
  double Length() const;

  struct Closest {
    Eigen::Vector2d point;  ///< closest point of the polyline / polygon boundary
    double distance_m;      ///< |x - point|
    std::size_t segment;    ///< index of the segment containing point
    double segment_param;   ///< point = a + segment_param (b - a) on that segment
  };
  /// Closest point to x (finite; throws std::invalid_argument otherwise).
  Closest ClosestPoint(const Eigen::Vector2d& x) const;
  double Distance(const Eigen::Vector2d& x) const { return ClosestPoint(x).distance_m; }

  struct Hit {
    RayHit hit;
    std::size_t segment;  ///< index of the segment hit
  };
  /// First hit of the ray; same arguments and errors as RayCast(Segment2, ...).
  std::optional<Hit> RayCast(const Eigen::Vector2d& origin, const Eigen::Vector2d& direction,
                             double max_range_m) const;
  /// Nearest point inside the cone's sector; same errors as ConeCast(Segment2, ...).
  std::optional<Hit> ConeCast(const Cone2& cone) const;
  /// Every segment meeting the sector with its nearest point, by range then segment index.
  std::vector<Hit> ConeCastAll(const Cone2& cone) const;

 private:
  std::vector<Eigen::Vector2d> vertices_;
  bool closed_;
};

}  // namespace rowloc::geometry
