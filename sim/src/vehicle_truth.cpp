#include "rowloc/sim/vehicle_truth.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <stdexcept>
#include <string>

namespace rowloc::sim {

VehicleTruthSampler::VehicleTruthSampler(const Route& route, const VehicleModel& vehicle,
                                         const TerrainMap& terrain_map, const TerrainSurface* terrain)
    : route_(route), vehicle_(vehicle), terrain_map_(terrain_map), terrain_(terrain) {}

double VehicleTruthSampler::TerrainHeight(const Eigen::Vector2d& xy_m) const {
  return terrain_ == nullptr ? 0.0 : terrain_->HeightAt(xy_m);
}

VehicleTruth VehicleTruthSampler::At(double time_s) const {
  VehicleTruth truth;
  truth.route = route_.At(time_s);
  const RoutePoint& p = truth.route;
  truth.motion = BodyMotion{p.speed_mps, 0.0, p.yaw_rate_radps, p.accel_mps2, 0.0, p.yaw_accel_radps2};
  truth.position_m << p.position_m, TerrainHeight(p.position_m);
  if (terrain_ != nullptr) {
    const Eigen::Vector2d gradient = terrain_->GradientAt(p.position_m);
    const Eigen::Vector2d forward(std::cos(p.heading_rad), std::sin(p.heading_rad));
    truth.grade = {gradient.dot(forward), gradient.dot(Eigen::Vector2d(-forward.y(), forward.x()))};
  }
  std::vector<TerrainClass> classes;
  classes.reserve(vehicle_.config().wheels.size());
  for (const WheelGeometry& wheel : vehicle_.config().wheels) {
    classes.push_back(terrain_map_.ClassAt(WorldPoint(truth, {wheel.position_m.x(), wheel.position_m.y(), 0.0}).head<2>()));
  }
  try {
    truth.wheels = vehicle_.Wheels(truth.motion, classes);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("vehicle '" + vehicle_.config().name + "' cannot drive the route at t = " +
                                std::to_string(truth.route.time_s) + " s: " + e.what());
  }
  return truth;
}

Eigen::Vector3d VehicleTruthSampler::WorldPoint(const VehicleTruth& truth, const Eigen::Vector3d& body_point_m) const {
  const Eigen::Vector2d xy =
      truth.route.position_m + Eigen::Rotation2Dd(truth.route.heading_rad) * body_point_m.head<2>();
  return {xy.x(), xy.y(), TerrainHeight(xy) + body_point_m.z()};
}

Eigen::Vector2d VehicleTruthSampler::WorldDirection(const VehicleTruth& truth, double body_yaw_rad) {
  const double angle = truth.route.heading_rad + body_yaw_rad;
  return {std::cos(angle), std::sin(angle)};
}

Eigen::Vector2d VehicleTruthSampler::SpecificForce(const VehicleTruth& truth, const Eigen::Vector2d& body_point_m) const {
  const Eigen::Vector2d& s = truth.grade;
  const Eigen::Vector2d gravity(s.x() / std::sqrt(1.0 + s.x() * s.x()), s.y() / std::sqrt(1.0 + s.y() * s.y()));
  return PointAcceleration(truth.motion, body_point_m) + kVehicleGravityMps2 * gravity;
}

}  // namespace rowloc::sim
