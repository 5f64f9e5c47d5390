#include "rowloc/geometry/segment_index.hpp"

// Boost 1.74's Boost.Math (pulled in by Boost.Geometry) includes a header it itself deprecated;
// this documented switch silences the resulting "#pragma message" note.
#ifndef BOOST_ALLOW_DEPRECATED_HEADERS
#define BOOST_ALLOW_DEPRECATED_HEADERS
#endif

#include <boost/container/small_vector.hpp>
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
#include <iterator>
#include <stdexcept>
#include <string>

namespace rowloc::geometry {

namespace bg = boost::geometry;
namespace bgi = boost::geometry::index;

namespace {

using BoostPoint = bg::model::point<double, 2, bg::cs::cartesian>;
using BoostSegment = bg::model::segment<BoostPoint>;
using BoostBox = bg::model::box<BoostPoint>;

// Nearest(): values are segments, so the tree's own distances are exact point-segment distances.
using NearestValue = std::pair<BoostSegment, std::size_t>;  // (segment, entry index)
// The casts: values are bounding boxes, whose box-box test is much cheaper than Boost's
// segment-box test. The segment is the box diagonal named by Diagonal (min/max copy coordinates,
// so it is rebuilt bit for bit).
struct Diagonal {
  std::size_t entry = 0;
  bool a_at_min_x = true;  // segment.a.x() == box min x (else max x); likewise for y
  bool a_at_min_y = true;
};
using CastValue = std::pair<BoostBox, Diagonal>;
// Bulk loading (packing) fixes the tree shape; 8 values per node measured fastest for these queries.
using NearestTree = bgi::rtree<NearestValue, bgi::rstar<8>>;
using CastTree = bgi::rtree<CastValue, bgi::rstar<8>>;

BoostPoint ToBoost(const Eigen::Vector2d& p) { return BoostPoint(p.x(), p.y()); }

Eigen::Vector2d FromBoost(const BoostPoint& p) { return {p.get<0>(), p.get<1>()}; }

SegmentQueryCache::Box FromBoost(const BoostBox& box) {
  return {FromBoost(box.min_corner()), FromBoost(box.max_corner())};
}

Segment2 ToSegment(const BoostSegment& s) {
  return Segment2{{bg::get<0, 0>(s), bg::get<0, 1>(s)}, {bg::get<1, 0>(s), bg::get<1, 1>(s)}};
}

CastValue ToCastValue(const Segment2& s, std::size_t entry) {
  const BoostBox box(ToBoost(s.a.cwiseMin(s.b)), ToBoost(s.a.cwiseMax(s.b)));
  return {box, Diagonal{entry, s.a.x() <= s.b.x(), s.a.y() <= s.b.y()}};
}

Segment2 ToSegment(const CastValue& value) {
  const BoostPoint& lo = value.first.min_corner();
  const BoostPoint& hi = value.first.max_corner();
  const Diagonal& d = value.second;
  return Segment2{{(d.a_at_min_x ? lo : hi).get<0>(), (d.a_at_min_y ? lo : hi).get<1>()},
                  {(d.a_at_min_x ? hi : lo).get<0>(), (d.a_at_min_y ? hi : lo).get<1>()}};
}

// A hit is better if nearer, or as near with a lower entry index.
bool Better(const SegmentIndex::Hit& candidate, const std::optional<SegmentIndex::Hit>& best) {
  return !best || candidate.hit.range_m < best->hit.range_m ||
         (candidate.hit.range_m == best->hit.range_m && candidate.entry < best->entry);
}

bool HitOrder(const SegmentIndex::Hit& l, const SegmentIndex::Hit& r) {
  return l.hit.range_m < r.hit.range_m || (l.hit.range_m == r.hit.range_m && l.entry < r.entry);
}

// Bounding box of the part of the sector with range in [inner_m, outer_m] (its corners and the arc
// extremes), inflated so that rounding and the contact tolerance of the casts never drop a
// touching segment.
BoostBox PieceBox(const PreparedCone& sector, double inner_m, double outer_m) {
  const Eigen::Vector2d& apex = sector.cone().apex;
  Eigen::Vector2d lo = apex + inner_m * sector.edge_cw();
  Eigen::Vector2d hi = lo;
  const auto add = [&](const Eigen::Vector2d& x) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  };
  add(apex + inner_m * sector.edge_ccw());
  add(apex + outer_m * sector.edge_cw());
  add(apex + outer_m * sector.edge_ccw());
  const Eigen::Vector2d cardinal[] = {Eigen::Vector2d::UnitX(), -Eigen::Vector2d::UnitX(),
                                      Eigen::Vector2d::UnitY(), -Eigen::Vector2d::UnitY()};
  for (const Eigen::Vector2d& u : cardinal) {
    if (sector.SectorContains(apex + u)) add(apex + outer_m * u);  // outer arc extremes
  }
  const double margin = 2.0 * kContactTolerance_m + 1e-12 * (apex.cwiseAbs().maxCoeff() + outer_m);
  return BoostBox(ToBoost(lo.array() - margin), ToBoost(hi.array() + margin));
}

// The three half-planes that contain the sector (inside of each edge, ahead of the apex). A
// segment with both ends clearly outside one of them cannot be hit: every candidate point of a
// cast lies in the sector or within kContactTolerance_m of an edge ray, and the margin covers that
// plus rounding (relative to the coordinates and to the segment's distance).
class SectorHalfPlanes {
 public:
  explicit SectorHalfPlanes(const PreparedCone& sector)
      : apex_(sector.cone().apex),
        normals_{Eigen::Vector2d(-sector.edge_cw().y(), sector.edge_cw().x()),
                 Eigen::Vector2d(sector.edge_ccw().y(), -sector.edge_ccw().x()),
                 sector.cone().axis},
        margin_m_(4.0 * kContactTolerance_m + 1e-12 * apex_.cwiseAbs().maxCoeff()) {}

  bool MayMeet(const Segment2& s) const {
    const Eigen::Vector2d va = s.a - apex_;
    const Eigen::Vector2d vb = s.b - apex_;
    const double margin_m = margin_m_ + 1e-10 * (va.cwiseAbs().sum() + vb.cwiseAbs().sum());
    return std::none_of(std::begin(normals_), std::end(normals_), [&](const Eigen::Vector2d& n) {
      return n.dot(va) < -margin_m && n.dot(vb) < -margin_m;
    });
  }

 private:
  Eigen::Vector2d apex_;
  Eigen::Vector2d normals_[3];
  double margin_m_;
};

// A cast's range is at least the segment's distance from the apex minus the contact tolerance and
// rounding: a segment farther from the apex than this cannot give a hit at range <= range_m.
double FarthestUsefulDistance(double range_m, const Eigen::Vector2d& apex) {
  return range_m + 4.0 * kContactTolerance_m + 1e-9 * range_m + 1e-12 * apex.cwiseAbs().maxCoeff();
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

template <class Value, class Make>
std::vector<Value> TreeValues(const std::vector<SegmentIndex::Entry>& entries, Make&& make) {
  std::vector<Value> values;
  values.reserve(entries.size());
  for (std::size_t i = 0; i < entries.size(); ++i) values.push_back(make(entries[i].segment, i));
  return values;
}

}  // namespace

struct SegmentIndex::Impl {
  // A query's cache, if any, and the index's handle for it.
  struct CacheUse {
    SegmentQueryCache* cache = nullptr;
    const std::shared_ptr<const void>* owner = nullptr;
  };

  std::vector<Entry> entries;
  NearestTree nearest_tree;
  CastTree cast_tree;
  Eigen::Vector2d bounds_lo = Eigen::Vector2d::Zero();  // bounding box of all segments
  Eigen::Vector2d bounds_hi = Eigen::Vector2d::Zero();
  double initial_radius_m = 1.0;  // outer radius of the first piece of the growing sector search

  explicit Impl(std::vector<Entry> e) : entries(std::move(e)) {
    CheckEntries(entries);
    // Packing (bulk-loading) constructors.
    const auto to_nearest_value = [](const Segment2& s, std::size_t i) {
      return NearestValue(BoostSegment(ToBoost(s.a), ToBoost(s.b)), i);
    };
    const auto nearest_values = TreeValues<NearestValue>(entries, to_nearest_value);
    nearest_tree = NearestTree(nearest_values.begin(), nearest_values.end());
    const auto cast_values = TreeValues<CastValue>(entries, ToCastValue);
    cast_tree = CastTree(cast_values.begin(), cast_values.end());
    if (!entries.empty()) {
      const BoostBox box = cast_tree.bounds();
      bounds_lo = {box.min_corner().get<0>(), box.min_corner().get<1>()};
      bounds_hi = {box.max_corner().get<0>(), box.max_corner().get<1>()};
      double total_length_m = 0.0;
      for (const Entry& entry : entries) total_length_m += entry.segment.Length();
      initial_radius_m = 2.0 * total_length_m / static_cast<double>(entries.size());
    }
  }

  // Distance from x to the farthest corner of the bounds: no segment point is farther.
  double CoverRadius(const Eigen::Vector2d& x) const {
    const Eigen::Vector2d far = (x - bounds_lo).cwiseAbs().cwiseMax((x - bounds_hi).cwiseAbs());
    return far.stableNorm();
  }

  // Calls visit(segment, entry index) for every segment whose bounding box meets box, in the
  // tree's order.
  template <class Visit>
  void VisitCandidates(const BoostBox& box, Visit&& visit) const {
    const auto each = [&](const CastValue& v) { visit(ToSegment(v), v.second.entry); };
    cast_tree.query(bgi::intersects(box), boost::make_function_output_iterator(each));
  }

  // The same, answered from the caller's cache when a stored box holds box (the same segments in
  // the same order: segment_query_cache.hpp); otherwise the tree's result for the grown box is
  // stored first. owner: the index's handle that the cache checks (SegmentIndex::impl_).
  template <class Visit>
  void VisitCandidates(const BoostBox& box, const CacheUse& use, Visit&& visit) const {
    if (use.cache == nullptr) return VisitCandidates(box, visit);
    const SegmentQueryCache::Box query = FromBoost(box);
    const std::vector<SegmentQueryCache::Item>* items = use.cache->Find(query, *use.owner);
    if (items == nullptr) {
      SegmentQueryCache::Box grown;
      std::vector<SegmentQueryCache::Item>& stored = use.cache->Store(query, grown);
      const auto each = [&](const CastValue& v) {
        stored.push_back({FromBoost(v.first), ToSegment(v), v.second.entry});
      };
      cast_tree.query(bgi::intersects(BoostBox(ToBoost(grown.lo), ToBoost(grown.hi))),
                      boost::make_function_output_iterator(each));
      items = &stored;
    }
    for (const SegmentQueryCache::Item& item : *items) {
      if (item.box.Meets(query)) visit(item.segment, item.entry);
    }
  }

  // A segment near a piece of the sector, with its distance from the apex.
  struct PieceCandidate {
    double distance_m;
    Segment2 segment;
    std::size_t entry;
  };

  // The segments whose bounding boxes meet the piece of the sector with range in [inner_m, outer_m]
  // and that may meet the sector, nearest to the apex first (replacing the content of out).
  template <class Out>
  void SortedPieceCandidates(const PreparedCone& sector, const SectorHalfPlanes& half_planes, double inner_m,
                             double outer_m, const CacheUse& use, Out& out) const {
    const Eigen::Vector2d& apex = sector.cone().apex;
    out.clear();
    VisitCandidates(PieceBox(sector, inner_m, outer_m), use, [&](const Segment2& s, std::size_t entry) {
      if (half_planes.MayMeet(s)) out.push_back(PieceCandidate{s.Distance(apex), s, entry});
    });
    std::sort(out.begin(), out.end(),
              [](const PieceCandidate& l, const PieceCandidate& r) { return l.distance_m < r.distance_m; });
  }

  // The growing-radius search (header comment): pieces [r_(k-1), r_k] of the sector, r_k = 2^k r0,
  // each piece's candidates cast nearest first until one is too far to come within window_m of the
  // best hit so far; it stops once best + window_m <= r_k, or at the reach. visit(hit) sees every
  // hit cast (a segment that straddles two pieces twice). Returns the best (nearest) hit.
  template <class Cast, class Visit>
  std::optional<Hit> GrowingSearch(const PreparedCone& sector, double window_m, const CacheUse& use, Cast&& cast,
                                   Visit&& visit) const {
    if (entries.empty()) return std::nullopt;
    const double limit_m = std::min(sector.cone().max_range_m, CoverRadius(sector.cone().apex));
    const Eigen::Vector2d& apex = sector.cone().apex;
    const SectorHalfPlanes half_planes(sector);
    std::optional<Hit> best;
    double inner_m = 0.0;
    boost::container::small_vector<PieceCandidate, 16> candidates;
    for (double radius_m = initial_radius_m;; radius_m *= 2.0) {
      const double outer_m = std::min(radius_m, limit_m);
      SortedPieceCandidates(sector, half_planes, inner_m, outer_m, use, candidates);
      for (const PieceCandidate& c : candidates) {
        if (c.distance_m > FarthestUsefulDistance(best ? best->hit.range_m + window_m : limit_m, apex)) break;
        if (const std::optional<RayHit> hit = cast(c.segment)) {
          const Hit candidate{*hit, c.entry};
          visit(candidate);
          if (Better(candidate, best)) best = candidate;
        }
      }
      if ((best && best->hit.range_m + window_m <= outer_m) || outer_m >= limit_m) return best;
      inner_m = outer_m;
    }
  }

  // Nearest hit of cast(segment) over all entries.
  template <class Cast>
  std::optional<Hit> NearestHit(const PreparedCone& sector, Cast&& cast) const {
    return GrowingSearch(sector, 0.0, CacheUse{}, cast, [](const Hit&) {});
  }

  // Every hit of cast(segment) with range <= (nearest range) + window_m, into hits (unsorted, no
  // entry twice).
  template <class Cast>
  void HitsNearNearest(const PreparedCone& sector, double window_m, const CacheUse& use, Cast&& cast,
                       std::vector<Hit>& hits) const {
    const std::optional<Hit> best = GrowingSearch(sector, window_m, use, cast, [&](const Hit& hit) {
      if (std::none_of(hits.begin(), hits.end(), [&](const Hit& h) { return h.entry == hit.entry; })) {
        hits.push_back(hit);
      }
    });
    if (!best) return;
    const double last_m = best->hit.range_m + window_m;
    hits.erase(std::remove_if(hits.begin(), hits.end(), [&](const Hit& h) { return h.hit.range_m > last_m; }),
               hits.end());
  }
};

SegmentIndex::SegmentIndex(std::vector<Entry> entries)
    : impl_(std::make_shared<const Impl>(std::move(entries))), cache_owner_(impl_) {}

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
  // The distance is computed from the tree's copy of the segment: entries[] is not in the cache.
  impl_->nearest_tree.query(bgi::nearest(ToBoost(p), static_cast<unsigned>(std::min(k, size()))),
                            boost::make_function_output_iterator([&](const NearestValue& value) {
                              result.emplace_back(ToSegment(value.first).Distance(p), value.second);
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

std::vector<SegmentIndex::Hit> SegmentIndex::ConeCastNearest(const Cone2& cone, double window_m) const {
  std::vector<Hit> hits;
  ConeCastNearest(cone, window_m, hits);
  return hits;
}

void SegmentIndex::ConeCastNearest(const Cone2& cone, double window_m, std::vector<Hit>& hits) const {
  ConeCastNearest(cone, window_m, hits, nullptr);
}

void SegmentIndex::ConeCastNearest(const Cone2& cone, double window_m, std::vector<Hit>& hits,
                                   SegmentQueryCache* cache) const {
  if (!(window_m >= 0.0)) {
    throw std::invalid_argument("SegmentIndex::ConeCastNearest: window_m must be >= 0 (not NaN)");
  }
  const PreparedCone sector(cone);
  hits.clear();
  const Impl::CacheUse use{cache, &cache_owner_};
  impl_->HitsNearNearest(sector, window_m, use, [&](const Segment2& s) { return sector.Cast(s); }, hits);
  std::sort(hits.begin(), hits.end(), HitOrder);
}

std::vector<SegmentIndex::Hit> SegmentIndex::ConeCastAll(const Cone2& cone) const { return ConeCastAll(cone, 0.0); }

std::vector<SegmentIndex::Hit> SegmentIndex::ConeCastAll(const Cone2& cone, double min_range_m) const {
  if (!(min_range_m >= 0.0 && std::isfinite(min_range_m))) {
    throw std::invalid_argument("SegmentIndex::ConeCastAll: min_range_m must be finite and >= 0");
  }
  const PreparedCone sector(cone);
  std::vector<Hit> hits;
  if (impl_->entries.empty()) return hits;
  const double reach_m = std::min(sector.cone().max_range_m, impl_->CoverRadius(sector.cone().apex));
  if (min_range_m > reach_m) return hits;
  const SectorHalfPlanes half_planes(sector);
  impl_->VisitCandidates(PieceBox(sector, min_range_m, reach_m), [&](const Segment2& s, std::size_t entry) {
    if (!half_planes.MayMeet(s)) return;
    const std::optional<RayHit> hit = sector.Cast(s);
    if (hit && hit->range_m >= min_range_m) hits.push_back(Hit{*hit, entry});
  });
  std::sort(hits.begin(), hits.end(), HitOrder);
  return hits;
}

}  // namespace rowloc::geometry
