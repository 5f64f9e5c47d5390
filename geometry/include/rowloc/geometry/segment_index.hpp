// SegmentIndex: Boost.Geometry R-trees (R*, bulk-loaded) over the segments of a row map, so that
// the segments near a point or a sensor beam are found in O(log N + k), not by a scan of N
// segments (docs/planar-geometry.md).
//
// Queries and their exact semantics (the per-segment semantics are those of ray_cast.hpp and
// cone_cast.hpp; ties in range or distance are broken by the lower entry index):
// - Nearest(p, k): the k segments nearest to p (exact point-segment distance), ascending.
// - RayCast / ConeCast: the nearest hit over all segments, by a growing search over pieces of the
//   sector: piece k holds the ranges [r_(k-1), r_k], r_k = 2^k r0 (r_(-1) = 0), clipped at
//   max_range. For each piece it queries an R-tree of segment bounding boxes with the piece's
//   bounding box (inflated by 2 kContactTolerance), drops segments with both ends outside one of
//   the sector's three half-planes (the two edges and ahead of the apex), sorts the rest by
//   distance from the apex and casts them exactly in that order until a segment is too far to beat
//   the best hit (a hit's range is never below its segment's distance minus the contact tolerance).
//   It stops as soon as the best hit has range <= r_k (no nearer hit can exist in later pieces),
//   so the work depends on the distance of the hit, not on max_range (which may be +inf); no
//   segment is fetched twice unless it straddles two pieces. r0 is twice the mean segment length.
//   A best-first traversal (Boost's incremental nearest query) measured 1.3-2x slower: its
//   type-erased iterator allocates and sorts at every node.
// - ConeCastNearest: the nearest hit and every hit within a window behind it, by the same growing
//   search, which then stops when the window ends inside the pieces searched. A caller that casts
//   from nearby poses again and again (a filter's sensors) may pass a SegmentQueryCache: the piece
//   queries inside a box it stored skip the tree, with the same result.
// - ConeCastAll: every segment meeting the sector, with its nearest point, by range (at a polygon
//   corner both segments are returned). No occlusion: segments behind others are returned too.
//   One query with the bounding box of the whole sector (or of its piece beyond a minimum range),
//   the same half-plane filter, exact casts.
// Nearest uses a second R-tree over the segments themselves (exact point-segment distances); the
// casts use the bounding-box tree because Boost's segment-box test costs more than the box-box one.
// The index is immutable; copies share the trees and concurrent const queries are safe.
#pragma once

#include "rowloc/geometry/cone_cast.hpp"
#include "rowloc/geometry/ray_cast.hpp"
#include "rowloc/geometry/row_map.hpp"
#include "rowloc/geometry/segment2.hpp"
#include "rowloc/geometry/segment_query_cache.hpp"

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

  /// The nearest hit in the cone's sector and every other hit with range <= its range + window_m,
  /// by range (then entry): ConeCastAll restricted to [nearest, nearest + window_m] in one search
  /// (the growing search of ConeCast, each piece's segments cast until one is too far to come
  /// within the window; +inf: every hit, as ConeCastAll). Empty when the sector meets no segment.
  /// Throws std::invalid_argument for a negative or NaN window_m; errors otherwise as ConeCast.
  std::vector<Hit> ConeCastNearest(const Cone2& cone, double window_m) const;
  /// The same into `hits` (cleared first): a caller that keeps the vector allocates nothing per query.
  void ConeCastNearest(const Cone2& cone, double window_m, std::vector<Hit>& hits) const;
  /// The same with the caller's query cache (nullptr: none): the same result bit for bit, the box
  /// queries of the search answered from `cache` when they fall inside a stored box
  /// (segment_query_cache.hpp).
  void ConeCastNearest(const Cone2& cone, double window_m, std::vector<Hit>& hits, SegmentQueryCache* cache) const;

  /// Every segment meeting the sector, by range (then entry); errors as ConeCast.
  std::vector<Hit> ConeCastAll(const Cone2& cone) const;
  /// The same restricted to hits with range >= min_range_m (the query box is then the bounding box
  /// of the sector's piece [min_range_m, max_range_m] only: a segment's hit is its nearest point in
  /// the sector, so it lies in that piece). Throws std::invalid_argument for a min_range_m that is
  /// negative or not finite; errors otherwise as ConeCast.
  std::vector<Hit> ConeCastAll(const Cone2& cone, double min_range_m) const;

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;
  std::shared_ptr<const void> cache_owner_;  ///< impl_ as the owner handle of query caches
};

}  // namespace rowloc::geometry
