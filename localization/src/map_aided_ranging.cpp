#include "rowloc/localization/map_aided_ranging.hpp"

#include "rowloc/geometry/cone_cast.hpp"
#include "rowloc/geometry/ellipsoid.hpp"
#include "rowloc/localization/range_slab.hpp"
#include "rowloc/mapio/local_frame.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rowloc::localization {
namespace {

/// Tolerance for "the hit is a segment end" (segment parameter) and "the foot is inside the cone".
constexpr double kEndTolerance = 1e-9;
constexpr double kConeTolerance = 1e-12;
/// Heading step of the central difference of the slab bounds (ellipsoid cut methods), rad.
constexpr double kHeadingStepRad = 1e-6;

geometry::RowMap InFilterFrame(const geometry::RowMap& map, const geometry::GeoOrigin& filter_origin) {
  if (const auto problem = geometry::ValidateRowMap(map)) throw std::invalid_argument("row map: " + *problem);
  const mapio::LocalFrame to(filter_origin);  // validates the filter origin
  geometry::RowMap local = map;
  local.origin = filter_origin;
  const geometry::GeoOrigin& from_origin = map.origin;
  if (from_origin.latitude_deg == filter_origin.latitude_deg &&
      from_origin.longitude_deg == filter_origin.longitude_deg && from_origin.altitude_m == filter_origin.altitude_m) {
    return local;
  }
  const mapio::LocalFrame from(from_origin);
  for (geometry::Row& row : local.rows) {
    for (Eigen::Vector2d& p : row.points_m) {
      const geometry::GeoOrigin g = from.ToGeodetic(Eigen::Vector3d(p.x(), p.y(), 0.0));
      p = to.ToEnu(g.latitude_deg, g.longitude_deg, g.altitude_m).head<2>();
    }
  }
  return local;
}

/// d(R(phi) l)/d phi = R(phi) (-l_y, l_x).
Eigen::Vector2d RotatedLeverArmDerivative(const Eigen::Rotation2Dd& rotation, const Eigen::Vector2d& lever_arm) {
  return rotation * Eigen::Vector2d(-lever_arm.y(), lever_arm.x());
}

std::optional<EchoCandidate> Linearize(const geometry::SegmentIndex::Hit& hit, const geometry::Segment2& segment,
                                       const Eigen::Vector3d& pose, const RangeSensorMount& mount) {
  const Eigen::Rotation2Dd rotation(pose.z());
  const Eigen::Vector2d sensor = pose.head<2>() + rotation * mount.lever_arm_m;
  const Eigen::Vector2d axis = rotation * Eigen::Vector2d(std::cos(mount.beam_angle_rad), std::sin(mount.beam_angle_rad));
  const Eigen::Vector2d d_sensor_d_phi = RotatedLeverArmDerivative(rotation, mount.lever_arm_m);
  const Eigen::Vector2d& n = hit.hit.normal;  // unit, on the sensor's side
  const double c = n.dot(segment.a);
  EchoCandidate candidate;
  candidate.entry = hit.entry;
  candidate.edge = EdgeLine{n, c};

  const double height = n.dot(sensor) - c;  // perpendicular distance of the sensor, >= 0
  const Eigen::Vector2d foot = sensor - height * n;
  const Eigen::Vector2d ab = segment.b - segment.a;
  const double t = (foot - segment.a).dot(ab) / ab.squaredNorm();
  const bool foot_on_segment = t >= 0.0 && t <= 1.0;
  const bool foot_in_cone = -n.dot(axis) >= std::cos(mount.cone_half_angle_rad) - kConeTolerance;
  if (foot_on_segment && foot_in_cone) {
    candidate.geometry = EchoGeometry::kPerpendicular;
    candidate.predicted_range_m = height;
    candidate.jacobian << n.x(), n.y(), n.dot(d_sensor_d_phi);
    return candidate;
  }
  if (hit.hit.segment_param <= kEndTolerance || hit.hit.segment_param >= 1.0 - kEndTolerance) {
    const Eigen::Vector2d end = hit.hit.segment_param <= 0.5 ? segment.a : segment.b;
    const Eigen::Vector2d offset = sensor - end;
    const double range = offset.norm();
    if (!(range > 0.0)) return std::nullopt;  // the sensor on the vertex: no direction
    const Eigen::Vector2d u = offset / range;
    candidate.geometry = EchoGeometry::kSegmentEnd;
    candidate.predicted_range_m = range;
    candidate.jacobian << u.x(), u.y(), u.dot(d_sensor_d_phi);
    candidate.edge = EdgeLine{u, u.dot(end)};
    return candidate;
  }
  // The hit is on one of the two edge rays of the cone: the one closer to the hit direction.
  const Eigen::Vector2d to_hit = hit.hit.point - sensor;
  const double side = axis.x() * to_hit.y() - axis.y() * to_hit.x();  // > 0: counter-clockwise edge
  RangeSensorMount edge_ray = mount;
  edge_ray.beam_angle_rad = mount.beam_angle_rad + (side >= 0.0 ? 1.0 : -1.0) * mount.cone_half_angle_rad;
  const auto model = RangeToLineJacobian(pose, edge_ray, candidate.edge);
  if (!model) return std::nullopt;
  candidate.geometry = EchoGeometry::kConeEdge;
  candidate.predicted_range_m = model->range_m;
  candidate.jacobian = model->jacobian;
  return candidate;
}

MapAidedMeasurement NoMeasurement(geometry::CutStatus status) {
  MapAidedMeasurement m;
  m.innovation.resize(0);
  m.jacobian.resize(0, 3);
  m.noise.resize(0, 0);
  m.cut_status = status;
  return m;
}

/// The slab of the echo on n^T p, widened by k sigma_phi |d bound / d phi| for the heading.
std::optional<RangeSlab> HeadingWidenedSlab(const EchoCandidate& candidate, const RangeSensorMount& mount,
                                            const Eigen::Vector3d& pose, double heading_sigma_rad,
                                            double measured_range_m, const MapAidedConfig& config) {
  const auto slab = [&](double phi) {
    return MakeRangeSlab(candidate.edge, mount, phi, measured_range_m, config.range_sigma_m, config.k_sigma);
  };
  std::optional<RangeSlab> centre = slab(pose.z());
  const std::optional<RangeSlab> plus = slab(pose.z() + kHeadingStepRad);
  const std::optional<RangeSlab> minus = slab(pose.z() - kHeadingStepRad);
  if (!centre || !plus || !minus || !plus->normal.isApprox(minus->normal)) return std::nullopt;
  const double d_lower = (plus->lower_m - minus->lower_m) / (2.0 * kHeadingStepRad);
  const double d_upper = (plus->upper_m - minus->upper_m) / (2.0 * kHeadingStepRad);
  const double k_sigma_phi = config.k_sigma * heading_sigma_rad;
  centre->lower_m -= k_sigma_phi * std::abs(d_lower);
  centre->upper_m += k_sigma_phi * std::abs(d_upper);
  return centre;
}

}  // namespace

RowMapRanging::RowMapRanging(const geometry::RowMap& map, const geometry::GeoOrigin& filter_origin)
    : index_(geometry::SegmentIndex::FromRowMap(InFilterFrame(map, filter_origin))) {}

std::vector<EchoCandidate> RowMapRanging::Candidates(const Eigen::Vector3d& pose, const RangeSensorMount& mount,
                                                     double max_range_m, double window_m) const {
  if (!pose.allFinite()) throw std::invalid_argument("RowMapRanging::Candidates: pose not finite");
  if (!(window_m >= 0.0)) throw std::invalid_argument("RowMapRanging::Candidates: window must be >= 0");
  const Eigen::Rotation2Dd rotation(pose.z());
  const double beam = pose.z() + mount.beam_angle_rad;
  const geometry::Cone2 cone{pose.head<2>() + rotation * mount.lever_arm_m, Eigen::Vector2d(std::cos(beam), std::sin(beam)),
                             mount.cone_half_angle_rad, max_range_m};
  const std::vector<geometry::SegmentIndex::Hit> hits = index_.ConeCastAll(cone);
  std::vector<EchoCandidate> candidates;
  if (hits.empty()) return candidates;
  // The echo is the nearest point of the outlines in the cone, so within one row only its nearest
  // hit is physical (a farther segment of the same outline is hidden or not the first echo);
  // different rows are alternatives for the data association (a prediction error of a lane).
  const double last_range = hits.front().hit.range_m + window_m;
  std::vector<std::size_t> rows_seen;
  for (const geometry::SegmentIndex::Hit& hit : hits) {
    if (hit.hit.range_m > last_range) break;
    const geometry::SegmentIndex::Entry& entry = index_.entries()[hit.entry];
    if (std::find(rows_seen.begin(), rows_seen.end(), entry.row) != rows_seen.end()) continue;
    rows_seen.push_back(entry.row);
    if (auto c = Linearize(hit, entry.segment, pose, mount)) candidates.push_back(*c);
  }
  return candidates;
}

double RangeNis(const EchoCandidate& candidate, double measured_range_m, const Eigen::Matrix3d& pose_covariance,
                double range_sigma_m) {
  const double y = measured_range_m - candidate.predicted_range_m;
  const double s = candidate.jacobian * pose_covariance * candidate.jacobian.transpose() + range_sigma_m * range_sigma_m;
  return y * y / s;
}

MapAidedMeasurement MakeMapAidedMeasurement(const EchoCandidate& candidate, const RangeSensorMount& mount,
                                            const Eigen::Vector3d& pose, const Eigen::Matrix3d& pose_covariance,
                                            double measured_range_m, const MapAidedConfig& config) {
  if (config.method == MapAidedMethod::kRange) {
    MapAidedMeasurement m;
    m.innovation = Eigen::VectorXd::Constant(1, measured_range_m - candidate.predicted_range_m);
    m.jacobian = candidate.jacobian;
    m.noise = Eigen::MatrixXd::Constant(1, 1, config.range_sigma_m * config.range_sigma_m);
    return m;
  }
  const std::optional<RangeSlab> slab = HeadingWidenedSlab(candidate, mount, pose, std::sqrt(pose_covariance(2, 2)),
                                                           measured_range_m, config);
  if (!slab) return NoMeasurement(geometry::CutStatus::kInvalidInput);
  const Eigen::Vector2d p = pose.head<2>();
  const Eigen::Matrix2d prior = pose_covariance.topLeftCorner<2, 2>();
  const auto ellipse = geometry::Ellipsoid<2>::FromCovariance(p, prior, config.k_sigma);
  const geometry::CutResult<2> cut = geometry::ParallelCut(ellipse, slab->normal, slab->lower_m, slab->upper_m);
  if (cut.status != geometry::CutStatus::kUpdated) return NoMeasurement(cut.status);
  const Eigen::Vector2d centre = cut.ellipsoid.center();
  const Eigen::Matrix2d posterior = cut.ellipsoid.shape() / (config.k_sigma * config.k_sigma);
  MapAidedMeasurement m;
  if (config.method == MapAidedMethod::kEllipsoidCut) {
    m.innovation = centre - p;
    m.jacobian = Eigen::Matrix<double, 2, 3>::Identity();
    m.noise = posterior;
    return m;
  }
  const Eigen::Vector2d& n = slab->normal;
  const double v_prior = n.dot(prior * n);
  const double v_post = n.dot(posterior * n);
  if (!(v_post < v_prior * (1.0 - 1e-9))) return NoMeasurement(geometry::CutStatus::kUnchanged);
  const double r = 1.0 / (1.0 / v_post - 1.0 / v_prior);
  const double m_prior = n.dot(p);
  const double z = r * (n.dot(centre) / v_post - m_prior / v_prior);
  m.innovation = Eigen::VectorXd::Constant(1, z - m_prior);
  m.jacobian.resize(1, 3);
  m.jacobian << n.x(), n.y(), 0.0;
  m.noise = Eigen::MatrixXd::Constant(1, 1, r);
  return m;
}

}  // namespace rowloc::localization
