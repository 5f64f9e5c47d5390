#include "rowloc/geometry/polyline2.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

namespace rowloc::geometry {

namespace {

void CheckVertices(const std::vector<Eigen::Vector2d>& vertices, bool closed) {
  const std::size_t min_count = closed ? 3 : 2;
  if (vertices.size() < min_count) {
    throw std::invalid_argument("Polyline2: needs at least " + std::to_string(min_count) +
                                " vertices, got " + std::to_string(vertices.size()));
  }
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    if (!vertices[i].allFinite()) {
      throw std::invalid_argument("Polyline2: vertex " + std::to_string(i) + " is not finite");
    }
  }
  const std::size_t segments = closed ? vertices.size() : vertices.size() - 1;
  for (std::size_t i = 0; i < segments; ++i) {
    if (vertices[i] == vertices[(i + 1) % vertices.size()]) {
      throw std::invalid_argument("Polyline2: segment " + std::to_string(i) + " has zero length");
    }
  }
}

// Keeps the nearer of two optional hits (ties: the one already kept, i.e. the lower index).
void KeepNearest(std::optional<Polyline2::Hit>& best, const std::optional<RayHit>& hit,
                 std::size_t segment) {
  if (hit && (!best || hit->range_m < best->hit.range_m)) best = Polyline2::Hit{*hit, segment};
}

}  // namespace

Polyline2::Polyline2(std::vector<Eigen::Vector2d> vertices, bool closed)
    : vertices_(std::move(vertices)), closed_(closed) {
  CheckVertices(vertices_, closed_);
}

Polyline2 Polyline2::FromRow(const Row& row) { return Polyline2(row.points_m, row.closed); }

Segment2 Polyline2::Segment(std::size_t i) const {
  if (i >= SegmentCount()) {
    throw std::out_of_range("Polyline2::Segment: index " + std::to_string(i) + " >= " +
                            std::to_string(SegmentCount()));
  }
  return Segment2{vertices_[i], vertices_[(i + 1) % vertices_.size()]};
}

double Polyline2::Length() const {
  double length = 0.0;
  for (std::size_t i = 0; i < SegmentCount(); ++i) length += Segment(i).Length();
  return length;
}

Polyline2::Closest Polyline2::ClosestPoint(const Eigen::Vector2d& x) const {
  if (!x.allFinite()) throw std::invalid_argument("Polyline2::ClosestPoint: point must be finite");
  Closest best{vertices_.front(), std::numeric_limits<double>::infinity(), 0, 0.0};
  for (std::size_t i = 0; i < SegmentCount(); ++i) {
    const Segment2 s = Segment(i);
    const double param = s.ClosestParam(x);
    const Eigen::Vector2d point = s.PointAt(param);
    const double distance = (x - point).norm();
    if (distance < best.distance_m) best = Closest{point, distance, i, param};
  }
  return best;
}

std::optional<Polyline2::Hit> Polyline2::RayCast(const Eigen::Vector2d& origin,
                                                 const Eigen::Vector2d& direction,
                                                 double max_range_m) const {
  constexpr const char* kWhat = "Polyline2::RayCast";
  if (!origin.allFinite()) throw std::invalid_argument("Polyline2::RayCast: origin must be finite");
  const Eigen::Vector2d d = UnitDirection(direction, kWhat);
  CheckMaxRange(max_range_m, kWhat);
  std::optional<Hit> best;
  for (std::size_t i = 0; i < SegmentCount(); ++i) {
    KeepNearest(best, detail::RayCastUnchecked(Segment(i), origin, d, max_range_m), i);
  }
  return best;
}

std::optional<Polyline2::Hit> Polyline2::ConeCast(const Cone2& cone) const {
  const PreparedCone prepared(cone);
  std::optional<Hit> best;
  for (std::size_t i = 0; i < SegmentCount(); ++i) KeepNearest(best, prepared.Cast(Segment(i)), i);
  return best;
}

std::vector<Polyline2::Hit> Polyline2::ConeCastAll(const Cone2& cone) const {
  const PreparedCone prepared(cone);
  std::vector<Hit> hits;
  for (std::size_t i = 0; i < SegmentCount(); ++i) {
    if (auto hit = prepared.Cast(Segment(i))) hits.push_back(Hit{*hit, i});
  }
  std::stable_sort(hits.begin(), hits.end(),
                   [](const Hit& l, const Hit& r) { return l.hit.range_m < r.hit.range_m; });
  return hits;
}

}  // namespace rowloc::geometry
