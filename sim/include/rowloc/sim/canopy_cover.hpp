// Canopy cover over a GNSS antenna between rows (issue 3, "degradation and dropouts under canopy";
// the GNSS model takes a cover factor c in [0, 1], gnss_model.hpp).
//
// Model: a receiver between two canopy walls loses the satellites low over the walls. Looking
// across the rows (perpendicular to the row direction, approximated by the vehicle heading), the
// canopy on each side hides the elevations below
//   theta_side = atan2(max(0, H - h_a), d_side),
// with h_a the antenna height above the terrain, H the world's mean canopy top (CanopyParams top_m)
// and d_side the horizontal distance to the nearest canopy on that side, found by a narrow cone
// cast (half-aperture 0.05 rad, up to 20 m) at the mean canopy mid-height. The cover is the hidden
// fraction of the cross-row half-circle of sky:
//   c = (theta_left + theta_right) / pi, in [0, 1).
// No canopy in reach on a side (open field, headland) hides nothing on that side.
// Between 2.5 m rows (walls 1.0 m away) with an antenna at 1.2 m and a 1.8 m canopy top,
// c = 2 atan(0.6 / 1.0) / pi = 0.34 (tests/sim/canopy_cover_test.cpp).
#pragma once

#include "rowloc/sim/ultrasonic_model.hpp"

#include <Eigen/Core>

namespace rowloc::sim {

class CanopyCover {
 public:
  /// Keeps a reference to the caster (and through it the world): both must outlive this object.
  explicit CanopyCover(CanopyCaster& caster, const RowWorld& world);

  /// Cover at an antenna at xy (ENU metres) and height above the terrain, vehicle heading in rad.
  /// Throws std::invalid_argument for non-finite input.
  double At(const Eigen::Vector2d& antenna_xy_m, double antenna_height_m, double heading_rad) const;

 private:
  double HiddenElevation(const Eigen::Vector2d& apex, const Eigen::Vector2d& axis, double antenna_height_m) const;

  CanopyCaster& caster_;
  double canopy_top_m_;
  double cast_height_m_;
};

}  // namespace rowloc::sim
