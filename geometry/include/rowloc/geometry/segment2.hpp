// Segment2: the closed segment [a, b] = { a + s (b - a) : s in [0, 1] } of the plane (see
// docs/planar-geometry.md), coordinates in metres.
//
// Math: with e = b - a, the closest point to x is a + s* e with s* = clamp((x - a)^T e / |e|^2, 0, 1);
// the distance is |x - (a + s* e)|. A degenerate segment (a == b) is a point: its closest point
// is a and its distance is |x - a|; only Direction() and SupportingLine() reject it.
#pragma once

#include "rowloc/geometry/line2.hpp"

#include <Eigen/Core>

namespace rowloc::geometry {

/// Two points closer than this are treated as touching by the ray and cone casts (metres).
/// It absorbs rounding only: it is far below any physical size in a row map.
inline constexpr double kContactTolerance_m = 1e-9;

struct Segment2 {
  Eigen::Vector2d a = Eigen::Vector2d::Zero();  ///< start point, metres
  Eigen::Vector2d b = Eigen::Vector2d::Zero();  ///< end point, metres

  /// |b - a|, metres.
  double Length() const { return (b - a).norm(); }

  /// True if both endpoints are finite and distinct and |b - a|^2 does not overflow (what every
  /// cast and the index require).
  bool IsProper() const;

  /// Unit vector from a to b. Throws std::invalid_argument for a degenerate or non-finite segment.
  Eigen::Vector2d Direction() const;

  /// Unit normal on the left of a -> b (Direction() rotated by +90 deg). Same preconditions.
  Eigen::Vector2d LeftNormal() const;

  /// Point a + s (b - a) for the parameter s (not clamped).
  Eigen::Vector2d PointAt(double s) const { return a + s * (b - a); }

  /// Parameter s in [0, 1] of the point of the segment closest to x (0 for a degenerate segment).
  double ClosestParam(const Eigen::Vector2d& x) const;

  /// Point of the segment closest to x.
  Eigen::Vector2d ClosestPoint(const Eigen::Vector2d& x) const { return PointAt(ClosestParam(x)); }

  /// Euclidean distance from x to the segment, metres.
  double Distance(const Eigen::Vector2d& x) const { return (x - ClosestPoint(x)).norm(); }

  /// The infinite line through a and b, oriented from a to b. Throws like Line2::Through.
  Line2 SupportingLine() const { return Line2::Through(a, b); }
};

}  // namespace rowloc::geometry
