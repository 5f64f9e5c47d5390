#include "rowloc/localization/map_aided_ranging.hpp"

#include "rowloc/geometry/collinear_vertices.hpp"
#include "rowloc/geometry/cone_cast.hpp"
#include "rowloc/geometry/ellipsoid.hpp"
#include "rowloc/localization/range_slab.hpp"
#include "outline_corners.hpp"
#include "rowloc/mapio/local_frame.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rowloc::localization {
namespace {

using detail::CornerFlags;
using detail::Outline;

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

/// Vertices closer than this to the chord of their kept neighbours are dropped before indexing: a
/// micrometre is far below any range's precision and above the rounding of coordinates in metres,
/// so only straight runs of vertices go (a dense straight row costs what its one segment costs:
/// docs/map-aided-update.md, "Dense rows"). Rows along a curve keep every vertex.
constexpr double kCollinearToleranceM = 1e-6;

geometry::RowMap WithoutCollinearVertices(geometry::RowMap map) {
  for (geometry::Row& row : map.rows) {
    std::vector<Eigen::Vector2d> kept = geometry::DropCollinearVertices(row.points_m, row.closed, kCollinearToleranceM);
    if (kept.size() >= (row.closed ? 3U : 2U)) row.points_m = std::move(kept);
  }
  return map;
}

/// The sensor at a vehicle pose (X, Y, phi): its position p_s = p + R(phi) l, its beam axis
/// R(phi) b, and d p_s / d phi = R(phi) (-l_y, l_x).
struct SensorAtPose {
  Eigen::Vector2d position;
  Eigen::Vector2d axis;
  Eigen::Vector2d d_position_d_phi;
};

SensorAtPose SensorAt(const Eigen::Vector3d& pose, const RangeSensorMount& mount) {
  const Eigen::Rotation2Dd rotation(pose.z());
  const Eigen::Vector2d& l = mount.lever_arm_m;
  return {pose.head<2>() + rotation * l,
          rotation * Eigen::Vector2d(std::cos(mount.beam_angle_rad), std::sin(mount.beam_angle_rad)),
          rotation * Eigen::Vector2d(-l.y(), l.x())};
}

/// Unit chord of the outline over +-smoothing_m / 2 of arc length around `centre`, stopped at the
/// corners on either side (a corner at `centre` itself does not stop it); `fallback` when the
/// window is shorter than `min_length` or folds back.
Eigen::Vector2d SmoothedTangent(const Outline& outline, const std::vector<double>& corner_arcs, double period,
                                double centre, double smoothing_m, double min_length,
                                const Eigen::Vector2d& fallback) {
  double lo = centre - 0.5 * smoothing_m, hi = centre + 0.5 * smoothing_m;
  for (const double corner : corner_arcs) {
    for (const double c : {corner - period, corner, corner + period}) {
      if (c < centre - 1e-9) lo = std::max(lo, c);
      if (c > centre + 1e-9) hi = std::min(hi, c);
    }
  }
  const Eigen::Vector2d chord = outline.At(hi) - outline.At(lo);
  if (hi - lo < min_length || chord.norm() < 0.5 * (hi - lo)) return fallback;
  return chord.normalized();
}

/// Distance from `origin` along `direction` (unit) to the first segment of a row other than
/// `own_row`, +inf when there is none within kLaneClearanceSearchM: ray casts through the index,
/// each restarted just past a hit on own_row (a concave outline may be crossed more than once).
double ClearanceAlong(const geometry::SegmentIndex& index, std::size_t own_row, const Eigen::Vector2d& origin,
                      const Eigen::Vector2d& direction) {
  constexpr double kStepPastHitM = 1e-6;
  constexpr int kMaxOwnCrossings = 64;
  double travelled = kStepPastHitM;  // start off the segment itself
  for (int crossing = 0; crossing < kMaxOwnCrossings && travelled < kLaneClearanceSearchM; ++crossing) {
    const auto hit = index.RayCast(origin + travelled * direction, direction, kLaneClearanceSearchM - travelled);
    if (!hit) break;
    travelled += hit->hit.range_m;
    if (index.entries()[hit->entry].row != own_row) return travelled;
    travelled += kStepPastHitM;
  }
  return std::numeric_limits<double>::infinity();
}

}  // namespace

void RowMapRanging::MeasureLaneClearances() {
  for (std::size_t e = 0; e < shapes_.size(); ++e) {
    const geometry::SegmentIndex::Entry& entry = index_.entries()[e];
    const Eigen::Vector2d middle = 0.5 * (entry.segment.a + entry.segment.b);
    const Eigen::Vector2d left(-shapes_[e].tangent.y(), shapes_[e].tangent.x());
    shapes_[e].left_clearance_m = ClearanceAlong(index_, entry.row, middle, left);
    shapes_[e].right_clearance_m = ClearanceAlong(index_, entry.row, middle, -left);
  }
}

namespace {

/// Each segment within half the smoothing length of arc from a corner (the end of a canopy part,
/// rounded or square; a long segment that ends there too) takes that corner's row direction and
/// along clearance (check 4): its echoes' along-row information is the corner's. The nearest
/// corner of arc wins, the smaller clearance between equals.
void AssignCornerReach(const geometry::RowMap& map, double smoothing_m, std::vector<RowMapRanging::EntryShape>& shapes) {
  std::vector<std::size_t> first_entry(map.rows.size() + 1, 0);
  for (std::size_t r = 0; r < map.rows.size(); ++r) first_entry[r + 1] = first_entry[r] + map.rows[r].SegmentCount();
  for (RowMapRanging::EntryShape& shape : shapes) shape.corner_direction = shape.tangent;
  std::vector<double> nearest_arc(shapes.size(), std::numeric_limits<double>::infinity());
  const double reach = 0.5 * smoothing_m;
  std::size_t last_row = map.rows.size();
  std::optional<Outline> outline;
  for (const detail::OutlineCorner& corner : detail::MapCorners(map, smoothing_m)) {
    const geometry::Row& row = map.rows[corner.row];
    if (corner.row != last_row) outline.emplace(row), last_row = corner.row;
    const double corner_arc = corner.arc_m;
    const double length = outline->length();
    for (std::size_t i = 0; i < row.SegmentCount(); ++i) {
      // Arc from the corner to the nearer point of the segment (0 when the segment holds it).
      const double start = outline->VertexArc(i), end = outline->VertexArc(i + 1);
      const auto gap = [&](double c) { return c < start ? start - c : (c > end ? c - end : 0.0); };
      double arc = gap(corner_arc);
      if (row.closed) arc = std::min({arc, gap(corner_arc - length), gap(corner_arc + length)});
      const std::size_t e = first_entry[corner.row] + i;
      if (arc > reach || arc > nearest_arc[e] ||
          (arc == nearest_arc[e] && !(corner.along_clearance_m < shapes[e].along_clearance_m))) {
        continue;
      }
      nearest_arc[e] = arc;
      shapes[e].corner_direction = corner.tangent;
      shapes[e].along_clearance_m = corner.along_clearance_m;
    }
  }
}

}  // namespace

std::vector<RowMapRanging::EntryShape> RowMapRanging::Shapes(const geometry::RowMap& map, double smoothing_m) {
  std::vector<EntryShape> shapes;
  for (const geometry::Row& row : map.rows) {
    const Outline outline(row);
    const std::vector<bool> corner = CornerFlags(row, outline, smoothing_m);
    std::vector<double> corner_arcs;
    for (std::size_t k = 0; k < corner.size(); ++k) {
      if (corner[k]) corner_arcs.push_back(outline.VertexArc(k));
    }
    const double period = row.closed ? outline.length() : 0.0;
    const std::size_t n = row.points_m.size();
    const double orientation = row.closed ? (geometry::OutlineSignedArea(row) >= 0.0 ? 1.0 : -1.0) : 0.0;
    for (std::size_t i = 0; i < row.SegmentCount(); ++i) {
      const auto [a, b] = row.Segment(i);
      const double length = (b - a).norm();
      const Eigen::Vector2d own = (b - a) / length;
      const double start = outline.VertexArc(i);
      const auto tangent = [&](double centre, double min_length) {
        return SmoothedTangent(outline, corner_arcs, period, centre, smoothing_m, min_length, own);
      };
      EntryShape shape{tangent(start + 0.5 * length, length), tangent(start, 0.0), tangent(start + length, 0.0),
                       corner[i], corner[(i + 1) % n]};
      shape.outward = orientation * Eigen::Vector2d(own.y(), -own.x());  // right of a counter-clockwise ring
      shapes.push_back(shape);
    }
  }
  AssignCornerReach(map, smoothing_m, shapes);
  return shapes;
}

namespace {

/// The range to the local straight row: the line with the row's (smoothed) normal n that lies at
/// the cast range from the sensor; r = (n^T p_s - c) / cos(max(0, gamma - a)).
std::optional<EchoCandidate> Linearize(const geometry::SegmentIndex::Hit& hit, const geometry::Segment2& segment,
                                       const RowMapRanging::EntryShape& shape, const Eigen::Vector3d& pose,
                                       const RangeSensorMount& mount, const SensorAtPose& at) {
  const Eigen::Vector2d& sensor = at.position;
  const Eigen::Vector2d& axis = at.axis;
  const bool at_start = hit.hit.segment_param <= kEndTolerance;
  const bool at_end = at_start || hit.hit.segment_param >= 1.0 - kEndTolerance;
  if (at_end && (at_start ? shape.start_is_corner : shape.end_is_corner)) {
    // A corner (row end, polygon end cap): the echo comes from that point, r = |p_s - q|.
    const Eigen::Vector2d corner = at_start ? segment.a : segment.b;
    const Eigen::Vector2d offset = sensor - corner;
    const double range = offset.norm();
    if (!(range > 0.0)) return std::nullopt;  // the sensor on the corner: no direction
    const Eigen::Vector2d u = offset / range;
    EchoCandidate candidate;
    candidate.entry = hit.entry;
    candidate.geometry = EchoGeometry::kSegmentEnd;
    candidate.predicted_range_m = range;
    candidate.jacobian << u.x(), u.y(), u.dot(at.d_position_d_phi);
    candidate.edge = EdgeLine{u, u.dot(corner)};
    return candidate;
  }
  const Eigen::Vector2d& row_tangent = !at_end ? shape.tangent : (at_start ? shape.start_tangent : shape.end_tangent);
  Eigen::Vector2d n(-row_tangent.y(), row_tangent.x());
  if (n.dot(hit.hit.normal) < 0.0) n = -n;  // towards the sensor
  const double range = hit.hit.range_m;
  const double cos_axis = -n.dot(axis);
  if (!(cos_axis > kMinBeamIncidenceCosine) || !(range > 0.0)) return std::nullopt;  // grazing, or on the wall
  const double gamma = std::acos(std::min(1.0, cos_axis));
  const bool normal_in_cone = gamma <= mount.cone_half_angle_rad + kConeTolerance;
  const double incidence_cos = std::cos(std::max(0.0, gamma - mount.cone_half_angle_rad));
  EchoCandidate candidate;
  candidate.entry = hit.entry;
  candidate.predicted_range_m = range;
  candidate.edge = EdgeLine{n, n.dot(sensor) - range * incidence_cos};
  if (normal_in_cone) {
    candidate.geometry = at_end ? EchoGeometry::kSegmentEnd : EchoGeometry::kPerpendicular;
    candidate.jacobian << n.x(), n.y(), n.dot(at.d_position_d_phi);
    return candidate;
  }
  // The nearest point is on the edge ray of the cone closer to the normal.
  const Eigen::Vector2d to_normal = -n;
  const double side = axis.x() * to_normal.y() - axis.y() * to_normal.x();  // > 0: counter-clockwise edge
  RangeSensorMount edge_ray = mount;
  edge_ray.beam_angle_rad = mount.beam_angle_rad + (side >= 0.0 ? 1.0 : -1.0) * mount.cone_half_angle_rad;
  const auto model = RangeToLineJacobian(pose, edge_ray, candidate.edge);
  if (!model) return std::nullopt;
  candidate.geometry = at_end ? EchoGeometry::kSegmentEnd : EchoGeometry::kConeEdge;
  candidate.jacobian = model->jacobian;
  return candidate;
}

/// The along check's data of a candidate (check 4): the row's direction and along clearance of its
/// segment.
void WithAlongCheckData(const RowMapRanging::EntryShape& shape, EchoCandidate& candidate) {
  candidate.row_tangent = shape.corner_direction;
  candidate.along_clearance_m = shape.along_clearance_m;
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
    // The row's outline accuracy widens the slab as it widens the range method's noise.
    const double sigma_m = std::hypot(config.range_sigma_m, candidate.map_sigma_m);
    return MakeRangeSlab(candidate.edge, mount, phi, measured_range_m, sigma_m, config.k_sigma);
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

double CheckedSmoothing(double row_smoothing_m) {
  if (!(std::isfinite(row_smoothing_m) && row_smoothing_m >= 0.0)) {
    throw std::invalid_argument("RowMapRanging: row smoothing length must be finite and >= 0");
  }
  return row_smoothing_m;
}

}  // namespace

RowMapRanging::RowMapRanging(const geometry::RowMap& map, const geometry::GeoOrigin& filter_origin,
                             double row_smoothing_m)
    : RowMapRanging(WithoutCollinearVertices(InFilterFrame(map, filter_origin)), CheckedSmoothing(row_smoothing_m)) {}

RowMapRanging::RowMapRanging(const geometry::RowMap& local_map, double row_smoothing_m)
    : index_(geometry::SegmentIndex::FromRowMap(local_map)),
      shapes_(Shapes(local_map, row_smoothing_m)),
      rows_(local_map.rows) {
  for (const geometry::Row& row : rows_) max_outline_sigma_m_ = std::max(max_outline_sigma_m_, row.outline_sigma_m);
  MeasureLaneClearances();
}

std::optional<double> RowMapRanging::LaneDirectionAt(const Eigen::Vector2d& point, double max_half_width_m,
                                                     double max_turn_rad) const {
  if (!point.allFinite()) throw std::invalid_argument("LaneDirectionAt: the point must be finite");
  const auto nearest = index_.Nearest(point, 1);
  if (nearest.empty()) return std::nullopt;
  for (const geometry::Row& row : rows_) {
    if (geometry::InsideOutline(row, point)) return std::nullopt;
  }
  const Eigen::Vector2d tangent = shapes_[nearest.front().second].tangent;
  const Eigen::Vector2d normal(-tangent.y(), tangent.x());
  const double min_alignment = std::cos(max_turn_rad);
  for (const double side : {1.0, -1.0}) {
    const auto hit = index_.RayCast(point, side * normal, max_half_width_m);
    if (!hit || std::abs(shapes_[hit->entry].tangent.dot(tangent)) < min_alignment) return std::nullopt;
  }
  return std::atan2(tangent.y(), tangent.x());
}

std::vector<EchoCandidate> RowMapRanging::Candidates(const Eigen::Vector3d& pose, const RangeSensorMount& mount,
                                                     double max_range_m, double window_m) const {
  Buffers buffers;
  Candidates(pose, mount, max_range_m, window_m, buffers);
  return std::move(buffers.candidates);
}

const std::vector<EchoCandidate>& RowMapRanging::Candidates(const Eigen::Vector3d& pose, const RangeSensorMount& mount,
                                                            double max_range_m, double window_m,
                                                            Buffers& buffers) const {
  if (!pose.allFinite()) throw std::invalid_argument("RowMapRanging::Candidates: pose not finite");
  if (!(window_m >= 0.0)) throw std::invalid_argument("RowMapRanging::Candidates: window must be >= 0");
  const SensorAtPose at = SensorAt(pose, mount);
  const geometry::Cone2 cone{at.position, at.axis, mount.cone_half_angle_rad, max_range_m};
  std::vector<EchoCandidate>& candidates = buffers.candidates;
  candidates.clear();
  // The nearest hit and every segment within the window behind it, in one search of the R-tree.
  const std::vector<geometry::SegmentIndex::Hit>& hits = buffers.hits;
  index_.ConeCastNearest(cone, window_m, buffers.hits, &buffers.query_cache);
  // From inside a closed outline the nearest hit is its inner side (a hit at a vertex may show the
  // inner side of a segment from outside too: the outline itself decides).
  buffers.sensor_inside_outline = false;
  if (!hits.empty()) {
    const geometry::SegmentIndex::Hit& nearest = hits.front();
    const std::size_t row = index_.entries()[nearest.entry].row;
    if (nearest.hit.normal.dot(shapes_[nearest.entry].outward) < 0.0 && geometry::InsideOutline(rows_[row], at.position)) {
      buffers.sensor_inside_outline = true;
      return candidates;
    }
  }
  // The echo is the nearest point of the outlines in the cone, so within one row only its nearest
  // hit is physical (a farther segment of the same outline is hidden or not the first echo);
  // different rows are alternatives for the data association (a prediction error of a lane).
  const auto row_of = [&](const geometry::SegmentIndex::Hit& hit) { return index_.entries()[hit.entry].row; };
  for (auto hit = hits.begin(); hit != hits.end(); ++hit) {
    const geometry::SegmentIndex::Entry& entry = index_.entries()[hit->entry];
    if (std::any_of(hits.begin(), hit, [&](const auto& nearer) { return row_of(nearer) == entry.row; })) continue;
    const EntryShape& shape = shapes_[hit->entry];
    if (auto c = Linearize(*hit, entry.segment, shape, pose, mount, at)) {
      const bool sensor_on_left = hit->hit.normal.dot(Eigen::Vector2d(-shape.tangent.y(), shape.tangent.x())) >= 0.0;
      c->lane_clearance_m = sensor_on_left ? shape.left_clearance_m : shape.right_clearance_m;
      c->map_sigma_m = rows_[entry.row].outline_sigma_m;
      WithAlongCheckData(shape, *c);
      candidates.push_back(*c);
    }
  }
  return candidates;
}

AlongUse CheckAlong(const EchoCandidate& candidate, const RangeSensorMount& mount,
                    const Eigen::Matrix3d& pose_covariance, double k_sigma) {
  if (!std::isfinite(candidate.along_clearance_m)) return AlongUse::kFull;
  const Eigen::Vector2d& t = candidate.row_tangent;
  const double along_sigma = std::sqrt(t.dot(pose_covariance.topLeftCorner<2, 2>() * t));
  double along_scale_m = 0.5 * candidate.along_clearance_m;
  if (candidate.geometry != EchoGeometry::kPerpendicular) {
    along_scale_m = std::min(along_scale_m, candidate.predicted_range_m * std::tan(mount.cone_half_angle_rad));
  }
  if (k_sigma * along_sigma <= along_scale_m) return AlongUse::kFull;
  const double along_slope = std::abs(candidate.jacobian.head<2>().dot(t));
  return along_slope <= std::sin(mount.cone_half_angle_rad) + 1e-9 ? AlongUse::kAcrossOnly : AlongUse::kNone;
}

EchoCandidate AcrossOnly(const EchoCandidate& candidate, const Eigen::Vector3d& pose, const RangeSensorMount& mount) {
  const SensorAtPose at = SensorAt(pose, mount);
  const Eigen::Vector2d& t = candidate.row_tangent;
  Eigen::Vector2d n(-t.y(), t.x());
  if (n.dot(candidate.jacobian.head<2>()) < 0.0) n = -n;  // towards the sensor, as the range grows
  EchoCandidate across = candidate;
  across.jacobian << n.x(), n.y(), n.dot(at.d_position_d_phi);
  across.edge = EdgeLine{n, n.dot(at.position) - candidate.predicted_range_m};
  return across;
}

double RangeNoiseVariance(const EchoCandidate& candidate, const RangeSensorMount& mount,
                          const Eigen::Matrix3d& pose_covariance, double range_sigma_m) {
  // Second-order term of the heading: |d2r/dphi2| <= |l| + r (lever arm turning, beam tilting),
  // and E[(r''/2 dphi^2)^2] - E[r''/2 dphi^2]^2 = r''^2 sigma_phi^4 / 2 for a Gaussian heading
  // error; negligible once the heading is known, it keeps the first echoes after initialisation
  // (sigma_phi ~ 0.2 rad) from locking the heading on a linearization error.
  const double curvature = mount.lever_arm_m.norm() + candidate.predicted_range_m;
  const double heading_variance = pose_covariance(2, 2);
  return range_sigma_m * range_sigma_m + candidate.map_sigma_m * candidate.map_sigma_m +
         0.5 * curvature * curvature * heading_variance * heading_variance;
}

double RangeNis(const EchoCandidate& candidate, const RangeSensorMount& mount, double measured_range_m,
                const Eigen::Matrix3d& pose_covariance, double range_sigma_m) {
  const double y = measured_range_m - candidate.predicted_range_m;
  const double s = candidate.jacobian * pose_covariance * candidate.jacobian.transpose() +
                   RangeNoiseVariance(candidate, mount, pose_covariance, range_sigma_m);
  return y * y / s;
}

MapAidedMeasurement MakeMapAidedMeasurement(const EchoCandidate& candidate, const RangeSensorMount& mount,
                                            const Eigen::Vector3d& pose, const Eigen::Matrix3d& pose_covariance,
                                            double measured_range_m, const MapAidedConfig& config) {
  if (config.method == MapAidedMethod::kRange) {
    MapAidedMeasurement m;
    m.innovation.setConstant(1, measured_range_m - candidate.predicted_range_m);
    m.jacobian = candidate.jacobian;
    m.noise.setConstant(1, 1, RangeNoiseVariance(candidate, mount, pose_covariance, config.range_sigma_m));
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
  m.innovation.setConstant(1, z - m_prior);
  m.jacobian.resize(1, 3);
  m.jacobian << n.x(), n.y(), 0.0;
  m.noise.setConstant(1, 1, r);
  return m;
}

}  // namespace rowloc::localization
