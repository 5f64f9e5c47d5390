// Line2: an infinite line of the plane in normal form  n^T x = offset,  |n| = 1  (see
// docs/planar-geometry.md). Donati 2021 writes rows as y = m x + q, which cannot represent a row along
// the y axis (an erratum, not copied); the normal form represents every direction with the same formulas.
//
// Math (x in metres, local ENU):
//   signed distance  d(x) = n^T x - offset      (positive on the side n points to)
//   projection       P(x) = x - d(x) n          (foot of the perpendicular)
//   direction        t    = (n_y, -n_x)         (n is t rotated by +90 deg, i.e. n is "left" of t)
// Line2::Through(a, b) orients the line from a to b, so its normal is the left normal of b - a.
#pragma once

#include <Eigen/Core>

#include <optional>

namespace rowloc::geometry {

struct Line2 {
  Eigen::Vector2d normal = Eigen::Vector2d::UnitY();  ///< unit normal n
  double offset = 0.0;                                ///< n^T x of every point x on the line, metres

  /// The line through a and b, oriented from a to b (normal = left normal of b - a).
  /// Throws std::invalid_argument if a or b is not finite or a == b.
  static Line2 Through(const Eigen::Vector2d& a, const Eigen::Vector2d& b);

  /// The line n^T x = offset for any non-zero finite n; n and offset are scaled so that |n| = 1.
  /// Throws std::invalid_argument if n is zero or not finite, or offset is not finite.
  static Line2 FromNormal(const Eigen::Vector2d& n, double offset);

  /// Unit direction t = (n_y, -n_x); Through(a, b).Direction() points from a to b.
  Eigen::Vector2d Direction() const { return {normal.y(), -normal.x()}; }

  /// Signed distance of x from the line, metres (positive on the side the normal points to).
  double SignedDistance(const Eigen::Vector2d& x) const { return normal.dot(x) - offset; }

  /// Unsigned distance of x from the line, metres.
  double Distance(const Eigen::Vector2d& x) const;

  /// Orthogonal projection of x onto the line.
  Eigen::Vector2d Project(const Eigen::Vector2d& x) const { return x - SignedDistance(x) * normal; }

  /// Intersection point with another line; nullopt if the lines are parallel (|sin angle| <= 1e-12),
  /// including the case of coincident lines.
  std::optional<Eigen::Vector2d> Intersect(const Line2& other) const;
};

}  // namespace rowloc::geometry
