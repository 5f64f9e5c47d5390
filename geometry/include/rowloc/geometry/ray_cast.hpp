// Ray cast against a segment (docs/planar-geometry.md): the first point of the segment [a, b]
// met by the ray { o + t d : 0 <= t <= max_range } with |d| = 1.
//
// Math: with e = b - a and w = a - o, o + t d = a + s e gives (cross(u, v) = u_x v_y - u_y v_x)
//   t = cross(w, e) / cross(d, e),   s = cross(w, d) / cross(d, e).
// The ray hits iff s in [0, 1] and t in [0, max_range]. When the ray is parallel to the segment
// (|sin angle(d, e)| <= 1e-12) it hits only if it is collinear (origin within kContactTolerance_m of
// the supporting line); the hit is then the nearest point of the overlap of [0, max_range] with
// the segment's extent along the ray, i.e. max(0, t_near) where t_near is the nearer endpoint.
//
// Semantics (all distances in metres, tests in tests/geometry/ray_cast_test.cpp):
// - origin on the segment: hit at range 0 (the point is the origin's foot on the segment);
// - segment entirely behind the origin (t < 0), including collinear and behind: no hit;
// - the ray passing exactly through an endpoint hits it (segment_param 0 or 1);
// - a hit at exactly max_range counts; nothing beyond it;
// - contacts within kContactTolerance_m (1e-9 m) count as touching (absorbs rounding only).
// RayHit::normal is the unit normal of the segment on the side of the origin; if the origin lies
// on the supporting line it points against the travel direction (the side the ray comes from),
// and for a collinear ray it is the segment's left normal.
#pragma once

#include "rowloc/geometry/segment2.hpp"

#include <Eigen/Core>

#include <optional>

namespace rowloc::geometry {

struct RayHit {
  double range_m = 0.0;                                ///< distance from the ray origin / cone apex
  Eigen::Vector2d point = Eigen::Vector2d::Zero();     ///< hit point (on the segment), metres
  double segment_param = 0.0;                          ///< point = a + segment_param (b - a), in [0, 1]
  Eigen::Vector2d normal = Eigen::Vector2d::UnitY();   ///< unit segment normal, on the origin side
};

/// First hit of the ray {origin + t direction/|direction| : 0 <= t <= max_range_m} on s.
/// Throws std::invalid_argument if s is degenerate or not finite, origin is not finite, direction
/// is zero or not finite, or max_range_m is NaN or <= 0 (+infinity is allowed).
std::optional<RayHit> RayCast(const Segment2& s, const Eigen::Vector2d& origin,
                              const Eigen::Vector2d& direction, double max_range_m);

/// direction / |direction|; throws std::invalid_argument (message prefixed by `what`) if it is
/// zero or not finite.
Eigen::Vector2d UnitDirection(const Eigen::Vector2d& direction, const char* what);

/// Throws std::invalid_argument (message prefixed by `what`) unless max_range_m is in (0, +inf].
void CheckMaxRange(double max_range_m, const char* what);

namespace detail {

/// RayCast without input checks: s proper, origin finite, |unit_direction| = 1, max_range_m > 0.
std::optional<RayHit> RayCastUnchecked(const Segment2& s, const Eigen::Vector2d& origin,
                                       const Eigen::Vector2d& unit_direction, double max_range_m);

/// Unit normal of s on the side of `origin`; if origin is within kContactTolerance_m of the
/// supporting line, the normal opposing `travel` (left normal if travel is along the segment).
Eigen::Vector2d FacingNormal(const Segment2& s, const Eigen::Vector2d& origin,
                             const Eigen::Vector2d& travel);

/// z component of the cross product of two plane vectors.
inline double Cross(const Eigen::Vector2d& u, const Eigen::Vector2d& v) {
  return u.x() * v.y() - u.y() * v.x();
}

}  // namespace detail
}  // namespace rowloc::geometry
