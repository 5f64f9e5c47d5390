// Exact ground truth of a simulated run at any time (issue 3, "exact ground truth of pose,
// velocities and per-wheel slip"). The vehicle tracks its route exactly and drives
// forwards along it, so the body motion at time t is
//   v_x = v(t), v_y = 0, r = kappa(s(t)) v(t), dv_x = a(t), dv_y = 0, dr = route yaw acceleration
// (route.hpp). VehicleModel (vehicle_model.hpp) turns it into per-wheel steering, speed, slip and
// torque on the terrain class under each wheel centre (TerrainMap).
//
// Height and slope: the reference point sits on the terrain, z = z_terrain(x, y); a body point at
// height h is at z_terrain + h (the body is treated as level for positions: at the shipped grades
// below 10 % the error is under h * grade^2 / 2). The planar IMU model reads the specific force of
// the planar motion plus the gravity component along the tilted body axes:
//   f = a_planar + g (s_x / sqrt(1 + s_x^2), s_y / sqrt(1 + s_y^2)),
// s_x, s_y the terrain grades along the body x (heading) and y axes (positive uphill), i.e. the
// exact value for a slope along one body axis. Cross-coupling of both grades and the vertical
// undulation acceleration are neglected; both vanish on the shipped (flat) worlds.
#pragma once

#include "rowloc/sim/route.hpp"
#include "rowloc/sim/terrain_map.hpp"
#include "rowloc/sim/terrain_surface.hpp"
#include "rowloc/sim/vehicle_model.hpp"

#include <Eigen/Core>

#include <vector>

namespace rowloc::sim {

struct VehicleTruth {
  RoutePoint route;                 ///< time, station, position, heading, speed, curvature, ...
  BodyMotion motion;                ///< body-frame motion of the reference point
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  ///< reference point on the terrain, ENU
  Eigen::Vector2d grade = Eigen::Vector2d::Zero();       ///< terrain grades along body x, y
  std::vector<WheelTruth> wheels;   ///< config order
};

class VehicleTruthSampler {
 public:
  /// Keeps references: all three must outlive the sampler. terrain may be null (flat, z = 0).
  VehicleTruthSampler(const Route& route, const VehicleModel& vehicle, const TerrainMap& terrain_map,
                      const TerrainSurface* terrain);

  double duration_s() const { return route_.duration_s(); }
  /// The truth at time t (clamped to the route's span). Throws std::invalid_argument naming the
  /// time if the vehicle cannot drive the motion (VehicleModel::MotionProblem).
  VehicleTruth At(double time_s) const;

  /// World ENU position of a body point (x, y forward/left, z above the terrain).
  Eigen::Vector3d WorldPoint(const VehicleTruth& truth, const Eigen::Vector3d& body_point_m) const;
  /// World direction of a body-frame yaw angle (unit 2-vector).
  static Eigen::Vector2d WorldDirection(const VehicleTruth& truth, double body_yaw_rad);
  /// Specific force (m/s^2, body x, y) at a body point, planar motion plus gravity on the slope.
  Eigen::Vector2d SpecificForce(const VehicleTruth& truth, const Eigen::Vector2d& body_point_m) const;

 private:
  double TerrainHeight(const Eigen::Vector2d& xy_m) const;

  const Route& route_;
  const VehicleModel& vehicle_;
  const TerrainMap& terrain_map_;
  const TerrainSurface* terrain_;
};

}  // namespace rowloc::sim
