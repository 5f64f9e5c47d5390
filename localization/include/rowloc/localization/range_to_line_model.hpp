// Range of a body-mounted ultrasonic beam to a straight row edge, as a function of the planar pose.
//
// Pose x = (X, Y, phi): vehicle reference point in the local ENU frame (m) and heading from +East,
// counter-clockwise (rad). The sensor sits at lever arm l (body frame: x forward, y left, m)
// and points along body angle theta_b. With R(phi) the planar rotation,
//   sensor position   p_s = p + R(phi) l,
//   beam direction    u   = R(phi) (cos theta_b, sin theta_b),
// and the row edge in normal form n^T x = c (|n| = 1; normal form, because Donati 2021's
// y = m x + q breaks for rows along y), the beam meets the line after
//   r(x) = (c - n^T p_s) / (n^T u)            (Donati 2021 ch. 4 geometry, rewritten in normal form)
// which is valid when the beam points at the line from the sensor's side: r > 0 and n^T u != 0.
//
// The model is templated on the scalar so that ceres::Jet gives its Jacobian by automatic
// differentiation; RangeToLineJacobian() is the analytic Jacobian, and the tests compare both
// with central differences.
#pragma once

#include <Eigen/Core>

#include <cmath>
#include <optional>

namespace rowloc::localization {

/// Mounting of one range sensor on the body (x forward, y left).
struct RangeSensorMount {
  Eigen::Vector2d lever_arm_m = Eigen::Vector2d::Zero();  ///< sensor position in the body frame, m
  double beam_angle_rad = 0.0;                            ///< beam direction in the body frame, rad
  double cone_half_angle_rad = 0.0;  ///< half aperture of the sound cone (0: a ray); used by slabs
};

/// A straight edge n^T x = c in the world frame, |n| = 1.
struct EdgeLine {
  Eigen::Vector2d normal = Eigen::Vector2d::UnitY();  ///< unit normal
  double offset_m = 0.0;                              ///< c, m
};

/// Smallest |n^T u| accepted: below it the beam grazes the line (about 89.4 degrees off normal).
inline constexpr double kMinBeamIncidenceCosine = 1e-2;

/// r(x) for pose (X, Y, phi) of any scalar type T (double or ceres::Jet). Returns false, leaving
/// range untouched, when the beam is (nearly) parallel to the line or points away from it.
template <typename T>
bool RangeToLine(const T* pose, const RangeSensorMount& mount, const EdgeLine& line, T* range_m) {
  using std::abs;
  using std::cos;
  using std::sin;
  const T c_phi = cos(pose[2]);
  const T s_phi = sin(pose[2]);
  const double lx = mount.lever_arm_m.x();
  const double ly = mount.lever_arm_m.y();
  const T sensor_x = pose[0] + c_phi * lx - s_phi * ly;
  const T sensor_y = pose[1] + s_phi * lx + c_phi * ly;
  const double bx = std::cos(mount.beam_angle_rad);
  const double by = std::sin(mount.beam_angle_rad);
  const T beam_x = c_phi * bx - s_phi * by;
  const T beam_y = s_phi * bx + c_phi * by;
  const T n_dot_u = line.normal.x() * beam_x + line.normal.y() * beam_y;
  const T gap = line.offset_m - (line.normal.x() * sensor_x + line.normal.y() * sensor_y);
  // Valid only if the beam travels towards the line: gap and n^T u share their sign.
  if (!(abs(n_dot_u) > kMinBeamIncidenceCosine) || !(gap / n_dot_u > 0.0)) return false;
  *range_m = gap / n_dot_u;
  return true;
}

/// Range and its analytic Jacobian dr/d(X, Y, phi); nullopt where RangeToLine() is invalid.
struct RangeWithJacobian {
  double range_m;
  Eigen::RowVector3d jacobian;  ///< (dr/dX, dr/dY, dr/dphi), (1, 1, m/rad)
};
std::optional<RangeWithJacobian> RangeToLineJacobian(const Eigen::Vector3d& pose,
                                                     const RangeSensorMount& mount,
                                                     const EdgeLine& line);

/// The same Jacobian by forward-mode automatic differentiation with ceres::Jet<double, 3>.
std::optional<RangeWithJacobian> RangeToLineJacobianAutoDiff(const Eigen::Vector3d& pose,
                                                             const RangeSensorMount& mount,
                                                             const EdgeLine& line);

}  // namespace rowloc::localization
