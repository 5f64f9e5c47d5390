// SegmentIndex: a Boost.Geometry R-tree (R*, bulk-loaded) over the segments of a row map, so that
// the segments near a point or a sensor beam are found in O(log N + k), not by a scan of N
// segments (SPEC §4, "Planar geometry"; docs/planar-geometry.md).
//
// Queries and their exact semantics (the per-segment semantics are those of ray_cast.hpp and
// cone_cast.hpp; ties in range or distance are broken by the lower entry index):
// - Nearest(p, k): the k segments nearest to p (exact point-segment distance), ascending.
// - RayCast / ConeCast: the nearest hit over all segments. The search grows the sector radius
//   r = r0, 2 r0, 4 r0, ... up to max_range: each step queries the R-tree with the bounding box
//   of the sector clipped at r (inflated by 2 kContactTolerance_m) and refines every candidate
//   exactly; it stops as soon as the best hit has range <= r (no nearer hit can exist outside the
//   box), so the work depends on the distance of the hit, not on max_range (which may be +inf).
//   r0 is twice the mean segment length.
// - ConeCastAll: every segment meeting the sector, with its nearest point, by range (at a polygon
//   corner both segments are returned). No occlusion: segments behind others are returned too.
// The index is immutable; copies share the tree and concurrent const queries are safe.
#pragma once

#include "rowloc/geometry/cone_cast.hpp"
#include "rowloc/geometry/ray_cast.hpp"
#include "rowloc/geometry/row_map.hpp"
#include "rowloc/geometry/segment2.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

namespace rowloc::geometry {

class SegmentIndex {
 public:
  struct Entry {
    Segment2 segment;            ///< the segment, metres
    std::size_t row = 0;         ///< row index in the RowMap (or any caller-defined group)
    std::size_t segment_in_row = 0;  ///< index of the segment within its row
  };
  struct Hit {
    RayHit hit;
    std::size_t entry = 0;  ///< index into entries()
  };

  /// Throws std::invalid_argument if a segment is degenerate or not finite (naming the entry).
  /// An empty index is valid: every query returns nothing.
  explicit SegmentIndex(std::vector<Entry> entries);

  /// One entry per segment of every row, in row order (row = index in map.rows).
  static SegmentIndex FromRowMap(const RowMap& map);

  std::size_t size() const;
  const std::vector<Entry>& entries() const;

  /// (distance_m, entry) of the min(k, size()) segments nearest to p, ascending.
  /// Throws std::invalid_argument if p is not finite.
  std::vector<std::pair<double, std::size_t>> Nearest(const Eigen::Vector2d& p, std::size_t k) const;

  /// First hit of the ray; arguments and errors as RayCast(Segment2, ...).
  std::optional<Hit> RayCast(const Eigen::Vector2d& origin, const Eigen::Vector2d& direction,
                             double max_range_m) const;

  /// Nearest hit in the cone's sector; errors as ConeCast(Segment2, ...).
  std::optional<Hit> ConeCast(const Cone2& cone) const;

  /// Every segment meeting the sector, by range (then entry); errors as ConeCast.
  std::vector<Hit> ConeCastAll(const Cone2& cone) const;

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;
};

}  // namespace rowloc::geometry
