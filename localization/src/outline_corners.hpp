// Corners of row outlines (internal to map_aided_ranging.cpp): where an outline turns by more than
// 45 degrees at the scale of the row smoothing (a canopy part's end, square or rounded; the ends of
// an open row), one corner per run of consecutive corner vertices, and for each the distance along
// its row to the nearest other corner that an echo could take it for (the along check,
// map_aided_ranging.hpp check 4).
//
// Along clearance of a corner q with row direction t (unit) and normal n: the smallest |t^T d| over
// the other corners q' of the map, d = q' - q, on the same row line: |n^T d| <= min(|t^T d|,
// kSameLineAcrossM) (a neighbour row's corners are another lane, which the lane check guards; on an
// arc of 30 m radius the same line is 0.42 m off the tangent 5 m on); +inf when none lies within
// kAlongClearanceSearchM. The row direction at a corner is the chord of the longer
// of the two corner-free runs of the outline next to it, over at most the row smoothing length (the
// side of a canopy part, not its end).
#pragma once

#include "rowloc/geometry/row_map.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <limits>
#include <vector>

namespace rowloc::localization::detail {

/// How far the along clearance of a corner is searched, m; a clearance beyond it is +inf.
inline constexpr double kAlongClearanceSearchM = 10.0;
/// Largest across offset of a corner on the same row line, m (below the narrowest row spacings).
inline constexpr double kSameLineAcrossM = 0.6;

/// Arc-length parametrisation of one row's outline (closed: s wraps; open: s is clamped).
class Outline {
 public:
  explicit Outline(const geometry::Row& row);
  double length() const { return arc_.back(); }
  double VertexArc(std::size_t i) const { return arc_[i]; }
  Eigen::Vector2d At(double s) const;

 private:
  const geometry::Row& row_;
  std::vector<double> arc_;  ///< arc length at each vertex (and the total at the end)
};

/// Per vertex of `row`: a corner (see above) at the scale `smoothing_m`.
std::vector<bool> CornerFlags(const geometry::Row& row, const Outline& outline, double smoothing_m);

struct OutlineCorner {
  std::size_t row = 0;     ///< index in the map's rows
  double arc_m = 0.0;      ///< arc length of the corner along its row's outline
  Eigen::Vector2d point = Eigen::Vector2d::Zero();
  Eigen::Vector2d tangent = Eigen::Vector2d::UnitX();  ///< row direction at the corner (unit)
  double along_clearance_m = std::numeric_limits<double>::infinity();
};

/// Every corner of the map's rows with its row direction and along clearance. O(C^2) in the
/// number of corners C (a few per canopy part; thousands in a large map: milliseconds, once).
std::vector<OutlineCorner> MapCorners(const geometry::RowMap& map, double smoothing_m);

}  // namespace rowloc::localization::detail
