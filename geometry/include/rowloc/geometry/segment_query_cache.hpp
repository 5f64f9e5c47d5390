// SegmentQueryCache: the results of a caller's recent R-tree box queries of a SegmentIndex, so that
// a later query whose box lies inside a cached box is answered without the tree (see
// docs/planar-geometry.md). The map-aided filter casts the cones of a few sensors that
// move a few centimetres between two echoes, so most of its queries repeat a neighbourhood.
//
// Exactness: for axis-aligned boxes Q ⊆ C, a segment's bounding box meets Q only if it meets C, so
// the segments of C's result whose boxes meet Q are exactly the segments the tree returns for Q.
// They come in the same order too: the tree returns the values of a query in the fixed order of its
// depth-first traversal, and Q's values are a subsequence of C's. A query answered from the cache
// therefore gives the index's result bit for bit: estimates and replays do not depend on the cache.
//
// A miss queries the tree with the box grown by margin_m on every side (so the next queries of a
// slowly moving sensor fall inside) and stores the result in a slot, the least recently used one
// once all are taken. The cache knows which index filled it (an owner handle that keeps no index
// alive); used with another index it forgets everything first. Not thread-safe: one cache per
// caller (e.g. per filter); the index itself stays shared and const.
#pragma once

#include "rowloc/geometry/segment2.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace rowloc::geometry {

class SegmentQueryCache {
 public:
  /// Closed axis-aligned box, metres (lo <= hi componentwise).
  struct Box {
    Eigen::Vector2d lo = Eigen::Vector2d::Zero();
    Eigen::Vector2d hi = Eigen::Vector2d::Zero();
    bool Contains(const Box& inner) const {
      return lo.x() <= inner.lo.x() && lo.y() <= inner.lo.y() && inner.hi.x() <= hi.x() && inner.hi.y() <= hi.y();
    }
    bool Meets(const Box& other) const {
      return lo.x() <= other.hi.x() && other.lo.x() <= hi.x() && lo.y() <= other.hi.y() && other.lo.y() <= hi.y();
    }
  };
  /// One value of a query: the segment, its bounding box and its index entry.
  struct Item {
    Box box;
    Segment2 segment;
    std::size_t entry = 0;
  };

  static constexpr double kDefaultMarginM = 1.0;
  static constexpr std::size_t kDefaultSlots = 8;

  /// Throws std::invalid_argument unless margin_m is finite and >= 0 and slots >= 1.
  explicit SegmentQueryCache(double margin_m = kDefaultMarginM, std::size_t slots = kDefaultSlots);

  double margin_m() const { return margin_m_; }
  std::size_t slot_count() const { return slots_.size(); }
  std::size_t hits() const { return hits_; }      ///< queries answered from a slot
  std::size_t misses() const { return misses_; }  ///< queries that went to the tree
  /// Forgets every stored result (the counters stay).
  void Clear();

  // The index's side (SegmentIndex), public so that it can be tested on its own:
  /// The items of a stored box that contains `query` and was filled for `owner`, or nullptr. A
  /// different owner than the last one clears the cache first. Counts a hit or a miss.
  const std::vector<Item>* Find(const Box& query, const std::shared_ptr<const void>& owner);
  /// The slot for a miss's result: its box is `query` grown by margin_m, returned in `grown`; the
  /// items are cleared for the caller to fill with the tree's values for `grown`, in tree order.
  std::vector<Item>& Store(const Box& query, Box& grown);

 private:
  struct Slot {
    Box box;
    std::vector<Item> items;
    std::uint64_t last_use = 0;  ///< 0: empty
  };
  double margin_m_;
  std::vector<Slot> slots_;
  std::weak_ptr<const void> owner_;
  std::uint64_t clock_ = 0;
  std::size_t hits_ = 0;
  std::size_t misses_ = 0;
};

}  // namespace rowloc::geometry
