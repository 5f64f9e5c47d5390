#include "rowloc/localization/range_to_line_model.hpp"

#include <ceres/jet.h>

namespace rowloc::localization {

std::optional<RangeWithJacobian> RangeToLineJacobian(const Eigen::Vector3d& pose,
                                                     const RangeSensorMount& mount,
                                                     const EdgeLine& line) {
  double range = 0.0;
  if (!RangeToLine(pose.data(), mount, line, &range)) return std::nullopt;
  // r = gap / (n^T u). d gap/dp = -n^T; d gap/dphi = -n^T R'(phi) l; d(n^T u)/dphi = n^T R'(phi) b,
  // with R'(phi) = R(phi) J, J = [0 -1; 1 0] (rotation by +90 degrees).
  const double c = std::cos(pose.z());
  const double s = std::sin(pose.z());
  Eigen::Matrix2d dR;
  dR << -s, -c, c, -s;
  const Eigen::Vector2d b(std::cos(mount.beam_angle_rad), std::sin(mount.beam_angle_rad));
  Eigen::Matrix2d rot;
  rot << c, -s, s, c;
  const double n_dot_u = line.normal.dot(rot * b);
  const double dgap_dphi = -line.normal.dot(dR * mount.lever_arm_m);
  const double dndotu_dphi = line.normal.dot(dR * b);
  RangeWithJacobian out;
  out.range_m = range;
  out.jacobian << -line.normal.x() / n_dot_u, -line.normal.y() / n_dot_u,
      (dgap_dphi - range * dndotu_dphi) / n_dot_u;
  return out;
}

std::optional<RangeWithJacobian> RangeToLineJacobianAutoDiff(const Eigen::Vector3d& pose,
                                                             const RangeSensorMount& mount,
                                                             const EdgeLine& line) {
  using Jet = ceres::Jet<double, 3>;
  const Jet jet_pose[3] = {Jet(pose.x(), 0), Jet(pose.y(), 1), Jet(pose.z(), 2)};
  Jet range;
  if (!RangeToLine(jet_pose, mount, line, &range)) return std::nullopt;
  return RangeWithJacobian{range.a, range.v.transpose()};
}

}  // namespace rowloc::localization
