// From one ultrasonic range to a slab (two parallel half-planes) on the vehicle position.
//
// Donati 2021 ch. 4 turns a measured distance d_m +- k*sigma_d into a pair of parallel cuts on the
// predicted position ellipse; it writes the row as y = m x + q with offsets along x, which is
// undefined for rows along y (an erratum). Here everything is in normal form (docs/map-aided-update.md):
// with the row edge n^T x = c, n oriented towards the sensor (so the beam travels along -n),
// sensor lever arm l and beam direction b in the body frame, heading phi and R(phi) the rotation,
//   cos(gamma) = -n^T R(phi) b      (gamma: angle between the beam and the edge's inward normal),
//   n^T p_s   = c + d cos(gamma)    (p_s = p + R(phi) l, the sensor, at range d along the beam),
// so the reference point p satisfies, for d in [d_m - k sigma, d_m + k sigma] (clamped at 0),
//   c + d_lo cos(gamma) - n^T R(phi) l  <=  n^T p  <=  c + d_hi cos(gamma) - n^T R(phi) l.
// Cone: an ultrasonic echo comes from the nearest reflecting point inside the
// sound cone of half aperture a, not from the beam axis. Against a straight edge that point is
// the foot of the perpendicular when gamma <= a (range = perpendicular distance), else the point
// on the cone edge nearest the normal; so gamma above is replaced by max(0, gamma - a).
// This first version takes the heading as exact; the map-aided measurement (issue 5) widens the
// slab for heading uncertainty.
#pragma once

#include "rowloc/localization/range_to_line_model.hpp"

#include <Eigen/Core>

#include <optional>

namespace rowloc::localization {

/// lower_m <= normal^T p <= upper_m for the vehicle reference point p (world frame, m).
struct RangeSlab {
  Eigen::Vector2d normal;  ///< unit normal of the edge, pointing towards the sensor's side
  double lower_m;
  double upper_m;
  double incidence_cos;    ///< cos(max(0, gamma - a)) > 0: perpendicular distance per metre of range
};

/// Slab from a measured range. Returns nullopt when the range, sigma or k are not finite and
/// positive, the cone half angle is outside [0, pi/2), or when the beam (at the given heading)
/// does not travel towards the line (grazing: cos(gamma) <= kMinBeamIncidenceCosine, or away).
std::optional<RangeSlab> MakeRangeSlab(const EdgeLine& edge, const RangeSensorMount& mount,
                                       double heading_rad, double measured_range_m,
                                       double range_sigma_m, double k_sigma);

}  // namespace rowloc::localization
