// Cone cast (docs/planar-geometry.md): the nearest point of a segment inside a 2-D sector.
// An ultrasonic echo comes from the nearest reflecting point inside the beam, not from the beam
// axis, so the measured range is
//   r*(S, C) = min { |x - apex| : x in S ∩ C },
//   C = { apex + r u : |u| = 1, angle(u, axis) <= half_aperture, 0 <= r <= max_range }.
//
// Math: for half_aperture < pi/2 the unbounded sector is convex, so S ∩ C is a sub-segment [p, q]
// and |x - apex| is convex along it. Its minimum is the point of S closest to the apex if that
// point lies in the sector, otherwise p or q; p and q are endpoints of S inside the sector or
// intersections of S with the two edge rays apex + t R(±half_aperture) axis. ConeCast evaluates
// exactly these candidates (the edge rays with the ray cast of ray_cast.hpp, which handles
// collinear overlap) and keeps the nearest with range <= max_range. Clipping at max_range after the
// minimum is exact: if the unbounded minimum exceeds max_range the bounded set is empty.
//
// Semantics: half_aperture = 0 is a ray cast along the axis; the apex on the segment gives range 0;
// a hit at exactly max_range counts. RayHit::normal faces the apex (detail::FacingNormal with the
// axis as travel direction). Preconditions (std::invalid_argument otherwise): apex finite, axis
// finite and non-zero (it is normalized), half_aperture in [0, pi/2), max_range in (0, +inf].
#pragma once

#include "rowloc/geometry/ray_cast.hpp"
#include "rowloc/geometry/segment2.hpp"

#include <Eigen/Core>

#include <optional>

namespace rowloc::geometry {

struct Cone2 {
  Eigen::Vector2d apex = Eigen::Vector2d::Zero();   ///< sensor position, metres
  Eigen::Vector2d axis = Eigen::Vector2d::UnitX();  ///< beam axis (normalized by the casts)
  double half_aperture_rad = 0.0;                   ///< in [0, pi/2)
  double max_range_m = 0.0;                         ///< in (0, +inf]
};

/// The nearest point of s inside the cone's sector, or nullopt if they do not meet.
/// Throws std::invalid_argument for bad cone parameters (see above) or a degenerate segment.
std::optional<RayHit> ConeCast(const Segment2& s, const Cone2& cone);

/// A validated cone with its edge directions precomputed, for casting many segments.
class PreparedCone {
 public:
  /// Throws std::invalid_argument if the cone breaks the preconditions above.
  explicit PreparedCone(const Cone2& cone);

  const Cone2& cone() const { return cone_; }  ///< with a unit axis
  const Eigen::Vector2d& edge_cw() const { return edge_cw_; }    ///< axis rotated by -half_aperture
  const Eigen::Vector2d& edge_ccw() const { return edge_ccw_; }  ///< axis rotated by +half_aperture

  /// True if x is in the unbounded sector (angle(x - apex, axis) <= half_aperture, or x == apex).
  bool SectorContains(const Eigen::Vector2d& x) const;

  /// The cone cast of s; precondition: s is proper (Segment2::IsProper()).
  std::optional<RayHit> Cast(const Segment2& s) const;

 private:
  Cone2 cone_;
  double cos_half_aperture_;
  Eigen::Vector2d edge_cw_;
  Eigen::Vector2d edge_ccw_;
};

}  // namespace rowloc::geometry
