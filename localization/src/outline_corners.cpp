#include "outline_corners.hpp"

#include <algorithm>
#include <cmath>

namespace rowloc::localization::detail {

Outline::Outline(const geometry::Row& row) : row_(row) {
  arc_.push_back(0.0);
  for (std::size_t i = 0; i < row.SegmentCount(); ++i) {
    const auto [a, b] = row.Segment(i);
    arc_.push_back(arc_.back() + (b - a).norm());
  }
}

Eigen::Vector2d Outline::At(double s) const {
  if (row_.closed) {
    s = std::fmod(s, length());
    if (s < 0.0) s += length();
  } else {
    s = std::clamp(s, 0.0, length());
  }
  const std::size_t i = std::min<std::size_t>(
      static_cast<std::size_t>(std::upper_bound(arc_.begin(), arc_.end(), s) - arc_.begin()) - 1,
      row_.SegmentCount() - 1);
  const auto [a, b] = row_.Segment(i);
  const double t = (s - arc_[i]) / (arc_[i + 1] - arc_[i]);
  return a + std::clamp(t, 0.0, 1.0) * (b - a);
}

namespace {

constexpr double kCornerTurnRad = 0.7853981633974483;  // 45 degrees

/// The corners of one row: each run of consecutive corner vertices (a square end flags its cap and
/// the ends of the sides next to it; a rounded end, the vertices of its curve) is one corner at the
/// run's middle vertex, its direction the chord of the longer corner-free run next to it, over at
/// most the smoothing length.
void AppendRowCorners(const geometry::Row& row, std::size_t row_index, double smoothing_m,
                      std::vector<OutlineCorner>& corners) {
  const Outline outline(row);
  const std::vector<bool> flags = CornerFlags(row, outline, smoothing_m);
  const std::size_t n = flags.size();
  const double length = outline.length();
  struct Run { std::size_t first, last; };  // vertices, inclusive (last < first: wraps)
  // Consecutive corner vertices within half the smoothing length of arc of each other are one run.
  const double join = 0.5 * smoothing_m;
  const auto arc_before = [&](std::size_t k) {  // arc from the previous vertex to k (+inf: none)
    if (k == 0) return row.closed ? length - outline.VertexArc(n - 1) : std::numeric_limits<double>::infinity();
    return outline.VertexArc(k) - outline.VertexArc(k - 1);
  };
  const auto joins_previous = [&](std::size_t k) { return flags[(k + n - 1) % n] && arc_before(k) <= join; };
  // Start at a corner vertex that does not join its predecessor (none: the whole ring is one run).
  std::size_t start = n;
  for (std::size_t k = 0; k < n && start == n; ++k) {
    if (flags[k] && !joins_previous(k)) start = k;
  }
  std::vector<Run> runs;
  if (start == n) {
    if (flags[0]) runs.push_back({0, n - 1});
  } else {
    for (std::size_t step = 0; step < n; ++step) {
      const std::size_t k = (start + step) % n;
      if (!flags[k]) continue;
      if (step > 0 && joins_previous(k)) runs.back().last = k;
      else runs.push_back({k, k});
    }
  }
  const auto arc_of = [&](std::size_t k) { return outline.VertexArc(k); };
  const auto span = [&](double from, double to) {  // arc from -> to along the outline
    return row.closed ? std::fmod(to - from + length, length) : to - from;
  };
  for (std::size_t c = 0; c < runs.size(); ++c) {
    const Run& run = runs[c];
    const double first = arc_of(run.first), last = arc_of(run.last);
    const double extent = span(first, last);
    const double middle = first + 0.5 * extent;
    // Corner-free arc before the run and after it (an open row's ends: none beyond them).
    double before = 0.0, after = 0.0;
    if (runs.size() > 1 || !row.closed) {
      if (row.closed) {
        before = span(arc_of(runs[(c + runs.size() - 1) % runs.size()].last), first);
        after = span(last, arc_of(runs[(c + 1) % runs.size()].first));
      } else {
        before = c > 0 ? first - arc_of(runs[c - 1].last) : first;
        after = c + 1 < runs.size() ? arc_of(runs[c + 1].first) - last : length - last;
      }
    }
    const double longer = std::max(before, after);
    const double reach = smoothing_m > 0.0 ? std::min(longer, smoothing_m) : longer;
    const Eigen::Vector2d chord = after >= before ? Eigen::Vector2d(outline.At(last + reach) - outline.At(last))
                                                  : Eigen::Vector2d(outline.At(first) - outline.At(first - reach));
    OutlineCorner corner;
    corner.row = row_index;
    corner.arc_m = row.closed ? std::fmod(middle, length) : middle;
    corner.point = outline.At(middle);
    corner.tangent = chord.norm() > 0.0 ? Eigen::Vector2d(chord.normalized()) : Eigen::Vector2d::UnitX();
    corners.push_back(corner);
  }
}

}  // namespace

std::vector<bool> CornerFlags(const geometry::Row& row, const Outline& outline, double smoothing_m) {
  const std::size_t n = row.points_m.size();
  std::vector<bool> corner(n, false);
  const double q = 0.25 * smoothing_m;
  for (std::size_t k = 0; k < n; ++k) {
    const double s = outline.VertexArc(k);
    const Eigen::Vector2d before = outline.At(s) - outline.At(s - q);
    const Eigen::Vector2d after = outline.At(s + q) - outline.At(s);
    const double norms = before.norm() * after.norm();
    corner[k] = norms > 0.0 && before.dot(after) < std::cos(kCornerTurnRad) * norms;
  }
  if (!row.closed) corner.front() = corner.back() = true;
  return corner;
}

std::vector<OutlineCorner> MapCorners(const geometry::RowMap& map, double smoothing_m) {
  std::vector<OutlineCorner> corners;
  for (std::size_t r = 0; r < map.rows.size(); ++r) AppendRowCorners(map.rows[r], r, smoothing_m, corners);
  // Sorted by x, the search of each corner stops kAlongClearanceSearchM away in x.
  std::sort(corners.begin(), corners.end(), [](const auto& a, const auto& b) { return a.point.x() < b.point.x(); });
  for (std::size_t i = 0; i < corners.size(); ++i) {
    OutlineCorner& c = corners[i];
    const Eigen::Vector2d n(-c.tangent.y(), c.tangent.x());
    const auto consider = [&](const OutlineCorner& other) {
      const Eigen::Vector2d d = other.point - c.point;
      const double along = std::abs(c.tangent.dot(d)), across = std::abs(n.dot(d));
      if (across > std::min(along, kSameLineAcrossM)) return;
      if (along <= kAlongClearanceSearchM) c.along_clearance_m = std::min(c.along_clearance_m, along);
    };
    for (std::size_t j = i + 1; j < corners.size() && corners[j].point.x() - c.point.x() <= kAlongClearanceSearchM; ++j)
      consider(corners[j]);
    for (std::size_t j = i; j-- > 0 && c.point.x() - corners[j].point.x() <= kAlongClearanceSearchM;) consider(corners[j]);
  }
  return corners;
}

}  // namespace rowloc::localization::detail
