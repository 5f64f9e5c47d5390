// Map-aided ultrasonic measurement (issue 5; docs/map-aided-update.md; Donati 2021
// ch. 2-5 without its errata): which row segment an echo comes from, and the measurement
// it gives the filter, by one of three methods (MapAidedMethod, filter_config.hpp).
//
// Echo model. A sensor at lever arm l (body frame) with beam direction b and a sound cone of half
// aperture a sits at p_s = p + R(phi) l. Its echo comes from the nearest reflecting point q of the
// row outlines inside the cone (geometry/cone_cast.hpp): the predicted range is that cast range,
// exact for the map. Its derivative treats the row near q as straight (Donati 2021 ch. 4 models a row
// as a line), with the row's direction averaged over row_smoothing_m of the outline: n is the unit
// normal of that direction towards the sensor, gamma the angle between the beam and -n, and
//   normal inside the cone (gamma <= a):  r = n^T p_s - c                        (kPerpendicular),
//   otherwise (the cone's edge ray e):    r = (c - n^T p_s) / (n^T e)            (kConeEdge),
// with c chosen so that r equals the cast range at the predicted pose (kSegmentEnd: q is a vertex).
// At a corner of the outline (a turn of more than 45 degrees over a quarter of row_smoothing_m: the
// end caps of a canopy polygon, the ends of an open row) the echo comes from that point:
//   r = |p_s - q|, dr/dp = u^T, u = (p_s - q) / r                                (kSegmentEnd).
// Why not the local segment: the slope of each short segment of a canopy outline (leaf roughness,
// width that varies along the row) would make the range depend on the along-row position, and the
// filter would take that as along-row information; it is aliased (the pattern repeats every few
// decimetres to metres) and it locked the along-row estimate 2 m off on the rough-canopy scenario
// with a 1.5 m initial error. With the smoothed direction, along-row information comes only from
// features longer than row_smoothing_m (row ends, curves), which are real. Jacobians: analytic
// (RangeToLineJacobian for the edge ray); the tests compare them with central differences on
// straight rows.
//
// Segment selection (docs/map-aided-update.md, step 2): a cone cast of every row segment from the predicted sensor
// pose (SegmentIndex::ConeCastAll, R-tree); the first hit and every hit within a window of it are
// candidates (a polygon corner gives two; a prediction error may put the true surface second); the
// filter keeps the candidate with the smallest range NIS and gates it (chi-square, 1 dof).
//
// Association checks (not in Donati 2021, whose filter starts in the right lane with a known heading;
// added after twelve-seed sweeps found 4-6 of 12 runs of every vineyard scenario locked in a wrong
// lane or on a wrong heading, docs/map-aided-update.md §3.2). An echo is used only when its
// association is unambiguous at the k-sigma level (k = k_sigma):
// 1. heading: k sigma_phi <= a. Beyond it the predicted beam may or may not contain the surface
//    normal, so r(phi) switches between the perpendicular and the cone-edge model inside the
//    uncertainty; the first echoes after a GNSS initialisation (sigma_phi = 0.2 rad > a / 3) then
//    locked the heading 0.2-0.4 rad off at sigma 0.002 rad.
// 2. inside an outline: the nearest hit in the cone is the inner side of a closed canopy outline,
//    i.e. the predicted sensor is inside the canopy, where no echo comes from. An echo matched to
//    the far side of that canopy held the filter 0.56 m off across the row.
// 3. lane: k sqrt(H P H^T) <= c / 2, with c the candidate's lane clearance: the free distance from
//    its segment, on the sensor's side, to the nearest other row (RowMapRanging::EntryShape). A
//    prediction error of one row pitch (> c) makes an echo fit the neighbouring row as well as the
//    right one; below c / 2 the right row is the nearer hypothesis.
// 4. along (issue 28), for an echo near a corner (a segment within half the row smoothing of arc
//    from one; outline_corners.hpp): k sigma_along <= s, sigma_along the pose's sigma along the
//    row's direction t at the corner, s half the corner's along clearance (the distance along the
//    row to the nearest other corner on its row line) and, for an echo from a point (any geometry
//    but kPerpendicular), at most the cone's footprint r tan(a): over it the point stays in the
//    cone and the range's along-row slope holds (beyond it the range is the row's side, or the
//    next row). Otherwise (CheckAlong) the echo is used across the row only, r = n^T p_s - c with
//    n the normal of t (AcrossOnly), or not at all when |dr/dp . t| > sin(a) (the range is then
//    mostly along-row: a canopy's end face). With plants missing every few metres the corners
//    repeat; the first echoes after a GNSS initialisation (along error 0.5-0.8 m, sigma 0.11 m)
//    matched a corner's point model (slope 0.06 over 6 cm) and made the filter certain of a wrong
//    along position, and the lane followed.
//
// Methods (docs/map-aided-update.md, steps 3-4):
// - range: y = d_m - r(x), H = dr/d(X, Y, phi), R = sigma^2 + sigma_map^2 + (|l| + r)^2
//   sigma_phi^4 / 2 (sigma_map: the accuracy of the row's outline, which a built map carries in
//   its file, geometry::Row::outline_sigma_m; a map treated as exact made the filter certain to a
//   millimetre against outlines a centimetre off, and gate out the echoes that disagree. The last
//   term is the second-order heading term: it keeps the first echoes after initialisation,
//   sigma_phi ~ 0.2 rad, from locking the heading on a linearization error). The consistent method.
// - ellipsoid_cut (Donati 2021 ch. 4): the slab d_m +- k sqrt(sigma^2 + sigma_map^2) (range_slab.hpp: beam/normal angle,
//   cone, lever arm) widened by k sigma_phi |d beta/d phi| for the heading uncertainty, cuts the
//   k-sigma position ellipse E(p, k^2 P_pp) (geometry::ParallelCut); the new centre c+ is a
//   position measurement with covariance P+/k^2 (H = [I 0]). Built from the prior, it counts the
//   prior twice (the thesis's method, kept for comparison; overconfident by construction).
// - ellipsoid_cut_deprior: the cut's variance along n, v+ = n^T P+ n / k^2, and mean m+ = n^T c+
//   against the prior's v = n^T P_pp n, m = n^T p: the information the slab added is
//   1/r = 1/v+ - 1/v, the equivalent scalar measurement z = r (m+/v+ - m/v) of n^T p with variance
//   r (so that fusing it with the prior gives back m+, v+ along n): the prior counted once.
// An empty slab ∩ ellipse is a contradicting echo: reported (CutStatus::kEmpty), never clipped.
#pragma once

#include "rowloc/geometry/ellipsoid_cuts.hpp"
#include "rowloc/geometry/row_map.hpp"
#include "rowloc/geometry/segment_index.hpp"
#include "rowloc/localization/filter_config.hpp"
#include "rowloc/localization/range_to_line_model.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <limits>
#include <optional>
#include <vector>

namespace rowloc::localization {

/// Which point of a segment the echo comes from (at the predicted pose); see the header comment.
enum class EchoGeometry { kPerpendicular, kConeEdge, kSegmentEnd };

/// A row segment an echo may come from, with the range model linearized at the predicted pose.
struct EchoCandidate {
  std::size_t entry = 0;  ///< SegmentIndex entry (row and segment of the map)
  EchoGeometry geometry = EchoGeometry::kPerpendicular;
  double predicted_range_m = 0.0;
  Eigen::RowVector3d jacobian = Eigen::RowVector3d::Zero();  ///< d r / d(X, Y, phi): (1, 1, m/rad)
  /// The local straight row (normal towards the sensor) that the range model and the slabs of the
  /// cut methods use; r(pose) against it equals predicted_range_m.
  EdgeLine edge;
  /// Free distance from the candidate's segment, on the sensor's side, to the nearest segment of
  /// another row (+inf: none within kLaneClearanceSearchM); the lane check's scale.
  double lane_clearance_m = std::numeric_limits<double>::infinity();
  /// The accuracy of the candidate's row outline (geometry::Row::outline_sigma_m), m: added to the
  /// range noise in quadrature.
  double map_sigma_m = 0.0;
  /// Near a corner (check 4): its along clearance (EntryShape::along_clearance_m), the along
  /// check's scale; +inf when no corner is near.
  double along_clearance_m = std::numeric_limits<double>::infinity();
  /// The row's direction at the candidate (unit; near a corner, the corner's): the along check's
  /// axis, and the direction of the row's straight line of AcrossOnly.
  Eigen::Vector2d row_tangent = Eigen::Vector2d::UnitX();
};

/// How far the lane clearance of a segment is searched, m; a clearance beyond it is +inf.
inline constexpr double kLaneClearanceSearchM = 50.0;

/// The row map as reflecting segments in the filter's local frame, with its spatial index.
class RowMapRanging {
 public:
  /// The map's rows are re-expressed from the map's origin to `filter_origin` through WGS84 when the
  /// two differ (GeographicLib; heights taken as the origins'). row_smoothing_m: arc length over
  /// which a row's direction is averaged (0: each segment's own). Throws std::invalid_argument when
  /// the map is invalid (geometry::ValidateRowMap: e.g. no rows), an origin is out of range or
  /// row_smoothing_m is negative or not finite.
  RowMapRanging(const geometry::RowMap& map, const geometry::GeoOrigin& filter_origin, double row_smoothing_m);

  const geometry::SegmentIndex& index() const { return index_; }
  /// The largest outline_sigma_m of the map's rows, m (the candidate window's margin).
  double max_outline_sigma_m() const { return max_outline_sigma_m_; }

  /// The smoothed shape of the outline around one segment (per SegmentIndex entry).
  struct EntryShape {
    Eigen::Vector2d tangent;        ///< row direction at the segment's middle (unit)
    Eigen::Vector2d start_tangent;  ///< at its first vertex (a vertex that is not a corner)
    Eigen::Vector2d end_tangent;    ///< at its second vertex
    bool start_is_corner = false;   ///< a corner: echoes from that vertex use the point model
    bool end_is_corner = false;
    /// A segment within half the row smoothing of arc from a corner (the end of a canopy part,
    /// square or rounded, or of an open row; outline_corners.hpp): the row's direction at the
    /// nearest such corner (the side of the part, not its end; unit) and that corner's along
    /// clearance, the distance along the row to the nearest other corner on the same row line, m:
    /// the along check's axis and scale (check 4). Other segments: `tangent` and +inf.
    Eigen::Vector2d corner_direction = Eigen::Vector2d::UnitX();
    double along_clearance_m = std::numeric_limits<double>::infinity();
    /// Outward unit normal of a closed outline's segment (the side the canopy is not on); zero for
    /// an open row, which reflects on both sides.
    Eigen::Vector2d outward = Eigen::Vector2d::Zero();
    /// Free distance from the segment's middle, along the normal of `tangent` on its left (+90
    /// degrees) and right side, to the nearest segment of another row, m (+inf: none within
    /// kLaneClearanceSearchM).
    double left_clearance_m = std::numeric_limits<double>::infinity();
    double right_clearance_m = std::numeric_limits<double>::infinity();
  };

  /// The direction of the lane that `point` is in (rad, of the rows' smoothed tangent; the lane
  /// runs both ways, so phi and phi + pi are the same answer), or none when `point` is not between
  /// two rows: the nearest segment's tangent t, then rays from `point` along both normals of t must
  /// each meet a row within max_half_width_m whose tangent is within max_turn_rad of +-t, and
  /// `point` must not be inside a canopy outline. For a map-aided initialisation: in a lane the
  /// vehicle drives along the rows. Throws std::invalid_argument for a non-finite point.
  std::optional<double> LaneDirectionAt(const Eigen::Vector2d& point, double max_half_width_m,
                                        double max_turn_rad) const;

  /// Segments a beam from `pose` (X, Y, phi) can hit within max_range_m, nearest first: the first
  /// hit and every hit whose range is within window_m of it. Empty: the cone meets no segment, or
  /// the sensor is inside a closed outline (Buffers::sensor_inside_outline tells which).
  /// Throws std::invalid_argument for a non-finite pose or bad cone parameters.
  std::vector<EchoCandidate> Candidates(const Eigen::Vector3d& pose, const RangeSensorMount& mount,
                                        double max_range_m, double window_m) const;

  /// Storage that Candidates reuses from call to call (a filter keeps one: no allocation per echo),
  /// with the R-tree results of its recent cone casts (geometry::SegmentQueryCache: the same
  /// candidates, found faster while the sensors stay within its 1 m margin).
  struct Buffers {
    std::vector<geometry::SegmentIndex::Hit> hits;
    std::vector<EchoCandidate> candidates;
    geometry::SegmentQueryCache query_cache;
    /// Set by Candidates: the nearest hit was the inner side of a closed outline (the predicted
    /// sensor is inside a canopy); candidates is then empty.
    bool sensor_inside_outline = false;
  };
  /// The same into buffers.candidates (cleared first), which it returns.
  const std::vector<EchoCandidate>& Candidates(const Eigen::Vector3d& pose, const RangeSensorMount& mount,
                                               double max_range_m, double window_m, Buffers& buffers) const;

 private:
  RowMapRanging(const geometry::RowMap& local_map, double row_smoothing_m);
  static std::vector<EntryShape> Shapes(const geometry::RowMap& local_map, double row_smoothing_m);
  /// Fills the shapes' lane clearances by ray casts against index_.
  void MeasureLaneClearances();
  geometry::SegmentIndex index_;
  std::vector<EntryShape> shapes_;  ///< per index entry
  std::vector<geometry::Row> rows_;  ///< the rows in the filter frame (the inside-an-outline test)
  double max_outline_sigma_m_ = 0.0;
};

/// The filter measurement of one echo, in the pose (X, Y, phi) of the state. At most 2 rows: the
/// matrices live in the struct (no heap allocation per echo).
struct MapAidedMeasurement {
  Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 2, 1> innovation;  ///< 1 row (range, deprior) or 2 (ellipsoid cut)
  Eigen::Matrix<double, Eigen::Dynamic, 3, 0, 2, 3> jacobian;    ///< d h / d(X, Y, phi)
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 2, 2> noise;  ///< R
  geometry::CutStatus cut_status = geometry::CutStatus::kUpdated;  ///< cut methods; kUpdated for range
};

/// What the along check (check 4) lets an echo near a corner give the filter.
enum class AlongUse {
  kFull,        ///< its measurement as modelled (along-row information included)
  kAcrossOnly,  ///< the range to the row's straight line (AcrossOnly): across-row information only
  kNone,        ///< nothing: its range is mostly along-row, and the along association is ambiguous
};

/// Check 4: k sigma_along (of the pose covariance along candidate.row_tangent) against the along
/// scale: half the candidate's along clearance, and for an echo from a point (any geometry but
/// kPerpendicular) also the cone's footprint r tan(a). Within it: kFull. Beyond it: kAcrossOnly
/// when the range's along-row slope |dr/dp . t| is at most sin(a) (the range is the across distance
/// to within 1 - cos a), else kNone. A candidate with no corner near (along clearance +inf): kFull.
AlongUse CheckAlong(const EchoCandidate& candidate, const RangeSensorMount& mount,
                    const Eigen::Matrix3d& pose_covariance, double k_sigma);

/// The candidate with the across-only model, for the sensor `mount` at `pose` (the pose the
/// candidate was found at): the range to its row's straight line (direction row_tangent, normal n
/// towards the sensor) at the cast range, d r / d(X, Y, phi) = (n^T, n^T d p_s / d phi), and that
/// line as its edge (the cut methods).
EchoCandidate AcrossOnly(const EchoCandidate& candidate, const Eigen::Vector3d& pose, const RangeSensorMount& mount);

/// Variance of a range against the map for the range method: sigma^2 + sigma_map^2 + (|l| + r)^2
/// sigma_phi^4 / 2 (sigma_map: the row's outline accuracy, candidate.map_sigma_m; the last term is
/// the second-order heading term of the range; see the header comment).
double RangeNoiseVariance(const EchoCandidate& candidate, const RangeSensorMount& mount,
                          const Eigen::Matrix3d& pose_covariance, double range_sigma_m);

/// Range NIS y^2 / (H P H^T + RangeNoiseVariance) of a candidate for the measured range.
double RangeNis(const EchoCandidate& candidate, const RangeSensorMount& mount, double measured_range_m,
                const Eigen::Matrix3d& pose_covariance, double range_sigma_m);

/// The measurement of `config.method` for the chosen candidate. pose / pose_covariance: the
/// predicted (X, Y, phi) and its covariance (positive definite). For the cut methods the result has
/// no rows when the cut is not kUpdated (kEmpty: a contradicting echo; kUnchanged: no information;
/// kInvalidInput: a degenerate slab) and cut_status says which.
MapAidedMeasurement MakeMapAidedMeasurement(const EchoCandidate& candidate, const RangeSensorMount& mount,
                                            const Eigen::Vector3d& pose, const Eigen::Matrix3d& pose_covariance,
                                            double measured_range_m, const MapAidedConfig& config);

}  // namespace rowloc::localization
