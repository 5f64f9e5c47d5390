#include "rowloc/localization/range_slab.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace rowloc::localization {

std::optional<RangeSlab> MakeRangeSlab(const EdgeLine& edge, const RangeSensorMount& mount,
                                       double heading_rad, double measured_range_m,
                                       double range_sigma_m, double k_sigma) {
  const bool finite_inputs = std::isfinite(heading_rad) && std::isfinite(measured_range_m) &&
                             std::isfinite(range_sigma_m) && std::isfinite(k_sigma) &&
                             edge.normal.allFinite() && std::isfinite(edge.offset_m) &&
                             mount.lever_arm_m.allFinite() && std::isfinite(mount.beam_angle_rad);
  if (!finite_inputs || measured_range_m <= 0.0 || range_sigma_m <= 0.0 || k_sigma <= 0.0 ||
      !(mount.cone_half_angle_rad >= 0.0 && mount.cone_half_angle_rad < 0.5 * std::numbers::pi)) {
    return std::nullopt;
  }
  const double norm = edge.normal.norm();
  if (!(norm > 0.0)) return std::nullopt;
  const Eigen::Rotation2Dd rotation(heading_rad);
  const Eigen::Vector2d beam =
      rotation * Eigen::Vector2d(std::cos(mount.beam_angle_rad), std::sin(mount.beam_angle_rad));
  Eigen::Vector2d n = edge.normal / norm;
  double c = edge.offset_m / norm;
  if (n.dot(beam) > 0.0) {  // orient the normal towards the sensor: the beam travels along -n
    n = -n;
    c = -c;
  }
  const double cos_axis = -n.dot(beam);
  if (cos_axis <= kMinBeamIncidenceCosine) return std::nullopt;
  const double gamma = std::acos(std::min(1.0, cos_axis));
  const double cos_gamma = std::cos(std::max(0.0, gamma - mount.cone_half_angle_rad));
  const double lever_shift = n.dot(rotation * mount.lever_arm_m);
  const double half_width = k_sigma * range_sigma_m;
  const double d_lo = std::max(0.0, measured_range_m - half_width);
  const double d_hi = measured_range_m + half_width;
  return RangeSlab{n, c + d_lo * cos_gamma - lever_shift, c + d_hi * cos_gamma - lever_shift,
                   cos_gamma};
}

}  // namespace rowloc::localization
