#include "rowloc/geometry/segment_index.hpp"

// Boost 1.74's Boost.Math (pulled in by Boost.Geometry) includes a header it itself deprecated;
// this documented switch silences the resulting "#pragma message" note.
#ifndef BOOST_ALLOW_DEPRECATED_HEADERS
#define BOOST_ALLOW_DEPRECATED_HEADERS
#endif

#include <boost/geometry/algorithms/comparable_distance.hpp>
#include <boost/geometry/algorithms/intersects.hpp>
#include <boost/geometry/geometries/box.hpp>
#include <boost/geometry/geometries/point.hpp>
#include <boost/geometry/geometries/segment.hpp>
#include <boost/geometry/index/rtree.hpp>
#include <boost/geometry/strategies/strategies.hpp>
#include <boost/iterator/function_output_iterator.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rowloc::geometry {

namespace bg = boost::geometry;
namespace bgi = boost::geometry::index;

namespace {

using BoostPoint = bg::model::point<double, 2, bg::cs::cartesian>;
using BoostSegment = bg::model::segment<BoostPoint>;
using BoostBox = bg::model::box<BoostPoint>;
using TreeValue = std::pair<BoostSegment, std::size_t>;  // (segment, entry index)
// Bulk loading (packing) fixes the tree shape; 8 values per node measured fastest for these queries.
using Tree = bgi::rtree<TreeValue, bgi::rstar<8>>;

BoostPoint ToBoost(const Eigen::Vector2d& p) { return BoostPoint(p.x(), p.y()); }

// A hit is better if nearer, or as near with a lower entry index.
bool Better(const SegmentIndex::Hit& candidate, const std::optional<SegmentIndex::Hit>& best) {
  return !best || candidate.hit.range_m < best->hit.range_m ||
         (candidate.hit.range_m == best->hit.range_m && candidate.entry < best->entry);
}

bool HitOrder(const SegmentIndex::Hit& l, const SegmentIndex::Hit& r) {
  return l.hit.range_m < r.hit.range_m || (l.hit.range_m == r.hit.range_m && l.entry < r.entry);
}

// Bounding box of the sector clipped at radius reach_m, inflated so that rounding and the
// contact tolerance of the casts never drop a touching segment.
BoostBox SectorBox(const PreparedCone& sector, double reach_m) {
  const Eigen::Vector2d& apex = sector.cone().apex;
  Eigen::Vector2d lo = apex;
  Eigen::Vector2d hi = apex;
  const auto add = [&](const Eigen::Vector2d& x) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  };
  add(apex + reach_m * sector.edge_cw());
  add(apex + reach_m * sector.edge_ccw());
  const Eigen::Vector2d cardinal[] = {Eigen::Vector2d::UnitX(), -Eigen::Vector2d::UnitX(),
                                      Eigen::Vector2d::UnitY(), -Eigen::Vector2d::UnitY()};
  for (const Eigen::Vector2d& u : cardinal) {
    if (sector.SectorContains(apex + u)) add(apex + reach_m * u);  // arc extremes
  }
  const double margin = 2.0 * kContactTolerance_m + 1e-12 * (apex.cwiseAbs().maxCoeff() + reach_m);
  return BoostBox(ToBoost(lo.array() - margin), ToBoost(hi.array() + margin));
}

void CheckEntries(const std::vector<SegmentIndex::Entry>& entries) {
  for (std::size_t i = 0; i < entries.size(); ++i) {
    if (!entries[i].segment.IsProper()) {
      throw std::invalid_argument("SegmentIndex: entry " + std::to_string(i) + " (row " +
                                  std::to_string(entries[i].row) + ", segment " +
                                  std::to_string(entries[i].segment_in_row) +
                                  ") is degenerate or not finite");
    }
  }
}

}  // namespace

struct SegmentIndex::Impl {
  std::vector<Entry> entries;
  Tree tree;
  Eigen::Vector2d bounds_lo = Eigen::Vector2d::Zero();  // bounding box of all segments
  Eigen::Vector2d bounds_hi = Eigen::Vector2d::Zero();
  double initial_radius_m = 1.0;  // first search radius of the growing sector search

  explicit Impl(std::vector<Entry> e) : entries(std::move(e)) {
    CheckEntries(entries);
    std::vector<TreeValue> values;
    values.reserve(entries.size());
    double total_length_m = 0.0;
    for (std::size_t i = 0; i < entries.size(); ++i) {
      const Segment2& s = entries[i].segment;
      values.emplace_back(BoostSegment(ToBoost(s.a), ToBoost(s.b)), i);
      total_length_m += s.Length();
    }
    tree = Tree(values.begin(), values.end());  // packing (bulk-loading) constructor
    if (!entries.empty()) {
      const BoostBox box = tree.bounds();
      bounds_lo = {box.min_corner().get<0>(), box.min_corner().get<1>()};
      bounds_hi = {box.max_corner().get<0>(), box.max_corner().get<1>()};
      initial_radius_m = 2.0 * total_length_m / static_cast<double>(entries.size());
    }
  }

  // Distance from x to the farthest corner of the bounds: no segment point is farther.
  double CoverRadius(const Eigen::Vector2d& x) const {
    const Eigen::Vector2d far = (x - bounds_lo).cwiseAbs().cwiseMax((x - bounds_hi).cwiseAbs());
    return far.stableNorm();
  }

  // Calls visit(entry index) for every segment meeting the sector's box clipped at reach_m.
  template <class Visit>
  void VisitCandidates(const PreparedCone& sector, double reach_m, Visit&& visit) const {
    tree.query(bgi::intersects(SectorBox(sector, reach_m)),
               boost::make_function_output_iterator(
                   [&](const TreeValue& value) { visit(value.second); }));
  }

  // Nearest hit of cast(segment) over all entries, by the growing-radius search.
  template <class Cast>
  std::optional<Hit> NearestHit(const PreparedCone& sector, Cast&& cast) const {
    if (entries.empty()) return std::nullopt;
    const double limit_m = std::min(sector.cone().max_range_m, CoverRadius(sector.cone().apex));
    std::optional<Hit> best;
    for (double radius_m = initial_radius_m;; radius_m *= 2.0) {
      const double reach_m = std::min(radius_m, limit_m);
      VisitCandidates(sector, reach_m, [&](std::size_t entry) {
        if (const std::optional<RayHit> hit = cast(entries[entry].segment)) {
          const Hit candidate{*hit, entry};
          if (Better(candidate, best)) best = candidate;
        }
      });
      if ((best && best->hit.range_m <= reach_m) || reach_m >= limit_m) return best;
    }
  }
};

SegmentIndex::SegmentIndex(std::vector<Entry> entries)
    : impl_(std::make_shared<const Impl>(std::move(entries))) {}

SegmentIndex SegmentIndex::FromRowMap(const RowMap& map) {
  std::vector<Entry> entries;
  entries.reserve(map.SegmentCount());
  for (std::size_t r = 0; r < map.rows.size(); ++r) {
    const Row& row = map.rows[r];
    for (std::size_t i = 0; i < row.SegmentCount(); ++i) {
      const auto [a, b] = row.Segment(i);
      entries.push_back(Entry{Segment2{a, b}, r, i});
    }
  }
  return SegmentIndex(std::move(entries));
}

std::size_t SegmentIndex::size() const { return impl_->entries.size(); }

const std::vector<SegmentIndex::Entry>& SegmentIndex::entries() const { return impl_->entries; }

std::vector<std::pair<double, std::size_t>> SegmentIndex::Nearest(const Eigen::Vector2d& p,
                                                                  std::size_t k) const {
  if (!p.allFinite()) throw std::invalid_argument("SegmentIndex::Nearest: point must be finite");
  std::vector<std::pair<double, std::size_t>> result;
  if (k == 0 || impl_->entries.empty()) return result;
  result.reserve(std::min(k, impl_->entries.size()));
  impl_->tree.query(bgi::nearest(ToBoost(p), static_cast<unsigned>(std::min(k, size()))),
                    boost::make_function_output_iterator([&](const TreeValue& value) {
                      result.emplace_back(impl_->entries[value.second].segment.Distance(p),
                                          value.second);
                    }));
  std::sort(result.begin(), result.end());
  return result;
}

std::optional<SegmentIndex::Hit> SegmentIndex::RayCast(const Eigen::Vector2d& origin,
                                                       const Eigen::Vector2d& direction,
                                                       double max_range_m) const {
  constexpr const char* kWhat = "SegmentIndex::RayCast";
  if (!origin.allFinite()) throw std::invalid_argument("SegmentIndex::RayCast: origin must be finite");
  const Eigen::Vector2d d = UnitDirection(direction, kWhat);
  CheckMaxRange(max_range_m, kWhat);
  const PreparedCone ray(Cone2{origin, d, 0.0, max_range_m});
  return impl_->NearestHit(ray, [&](const Segment2& s) {
    return detail::RayCastUnchecked(s, origin, d, max_range_m);
  });
}

std::optional<SegmentIndex::Hit> SegmentIndex::ConeCast(const Cone2& cone) const {
  const PreparedCone sector(cone);
  return impl_->NearestHit(sector, [&](const Segment2& s) { return sector.Cast(s); });
}

std::vector<SegmentIndex::Hit> SegmentIndex::ConeCastAll(const Cone2& cone) const {
  const PreparedCone sector(cone);
  std::vector<Hit> hits;
  if (impl_->entries.empty()) return hits;
  const double reach_m = std::min(sector.cone().max_range_m, impl_->CoverRadius(sector.cone().apex));
  impl_->VisitCandidates(sector, reach_m, [&](std::size_t entry) {
    if (const std::optional<RayHit> hit = sector.Cast(impl_->entries[entry].segment)) {
      hits.push_back(Hit{*hit, entry});
    }
  });
  std::sort(hits.begin(), hits.end(), HitOrder);
  return hits;
}

}  // namespace rowloc::geometry
