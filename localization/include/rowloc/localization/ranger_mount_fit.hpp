// Ranger mount fit (issue 28): where each ultrasonic ranger really sits on the body, from a
// stretch of driving along a known row map, as one Ceres least-squares problem over every echo.
// `rowloc calibrate` runs it over a recorded drive (calibration/ranger_calibration.hpp); the
// localization session over its last seconds of echoes, to report a ranger that is off.
//
// Unknowns. Per ranger i a correction c_i = (along, across) its beam (m) of its configured lever arm
// l_i (body frame x forward, y left): the mount is l_i + dl_i, dl_i = B_i c_i, B_i = [beam, beam
// rotated +90 degrees] (the across component only with estimate_across_beam); per knot k of the
// reference trajectory (a smoothed or filtered track, ReferenceKnot) a pose correction
// dx_k = (dX, dY, dphi) (m, m, rad), linear in time between knots: the drive's pose at time t is
// x_ref(t) + dx(t).
//
// Residuals (weights are 1-sigma values of the configuration, RangerMountFitConfig; solved by Ceres,
// sparse normal Cholesky; the Huber loss is Huber 1964's):
//  - echo j of ranger i at time t (Huber loss at huber_sigmas):
//      (d_j - r(x_ref(t) + dx(t), l_i + dl_i)) / sigma_j,   sigma_j^2 = range_sigma^2 + sigma_map^2,
//    with r the range model of the map-aided update (localization/map_aided_ranging.hpp: the nearest
//    row surface in the sound cone, the row's smoothed direction), linearized at the current
//    estimate: r ~ r0 + H (dx - dx0) + H_p R(phi) B_i (c_i - c_i0), H = dr/d(X, Y, phi), H_p its
//    position part (moving the sensor by R(phi) dl moves it like the pose does). The problem is
//    re-linearized and the echoes re-associated outer_iterations times.
//  - motion between knots k and k+1 (dt apart): the displacement d and heading change a the knots
//    predict, rotated by the heading correction:
//      (p_ref,k+1 + dp_{k+1} - p_ref,k - dp_k - R(dphi_k) d) / (q_p sqrt(dt)),
//      (phi_ref,k+1 + dphi_{k+1} - phi_ref,k - dphi_k - a) / (q_phi sqrt(dt)),
//    d = p_ref,k+1 - p_ref,k and a = phi_ref,k+1 - phi_ref,k for a smoothed reference (the
//    residuals then say: the reference's own motion, turned by the heading error), or dead-reckoned
//    from the filter's velocity states when the knots carry them (ReferenceKnot::body_rates):
//    d = R(phi_ref,k + a / 2) v dt, a = r dt, v and r the two knots' mean.
//    This ties the heading to the across-row motion (a heading error makes the vehicle drift across
//    the row as it drives), which makes a ranger's offset observable apart from the heading.
//  - anchor: dx_k / (sigma_position, sigma_position, sigma_heading): weak; keeps the corrections
//    bounded where no echo sees a row.
//  - mount prior: c_i / mount_prior_scale_m under a soft-L1 loss: most mounts are right.
//
// Observability (the report states it): a ranger's offset along its beam changes every range it
// measures by the same amount and is observable; across its beam only where the geometry turns
// (row ends, curved rows). One combination is never observable from the echoes: every ranger
// moved by the same body-frame shift is the vehicle moved the other way (the pose corrections take
// it): a gauge freedom in the sense of Triggs et al. 2000, fixed by a choice. The soft-L1 prior
// settles it the way a user expects: the fewest mounts moved (the offset of one wrong ranger among
// correct ones comes out on that ranger, not spread over all). A map whose lane is narrower than the canopy the rangers hear (every ranger reads short) is the same for the
// echoes as every ranger mounted further out; it is reported as the common offset along the beams.
#pragma once

#include "rowloc/localization/map_aided_ranging.hpp"
#include "rowloc/mapio/vehicle_config.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace rowloc::localization {

struct RangerMountFitConfig {
  double association_gate_m = 0.3;            ///< first pass: |measured - predicted range| above it: not used
  double refined_gate_m = 0.08;               ///< later passes (the corrections known), m
  double range_sigma_m = 0.005;               ///< echo noise plus canopy roughness, m (the map's own sigma added)
  double huber_sigmas = 3.0;                  ///< echo residuals beyond this many sigmas count linearly
  double position_walk_mps_per_sqrt_s = 0.01; ///< q_p: the reference's motion error, m / sqrt(s)
  double heading_walk_rad_per_sqrt_s = 0.002; ///< q_phi, rad / sqrt(s)
  double position_anchor_sigma_m = 1.0;       ///< the reference's absolute error (GNSS-grade), m
  double heading_anchor_sigma_rad = 0.1;
  double mount_prior_scale_m = 0.002;         ///< soft-L1 scale of the mount corrections, m
  double max_knot_gap_s = 1.0;                ///< knots further apart: no motion residual (a re-initialisation)
  int outer_iterations = 3;                   ///< re-linearizations (and re-associations), >= 1
  int max_solver_iterations = 100;            ///< Ceres iterations per pass
  std::size_t min_echoes_per_ranger = 50;     ///< fewer: the ranger keeps its configured mount
  /// Fewer of the echoes in the reference's span associated with a row (last pass): refused, the map
  /// is not of this field (or a mount is off by more than association_gate_m).
  double min_associated_fraction = 0.5;
  /// Also estimate each mount across its beam (along the rows for a side-looking ranger): observable
  /// only at row ends and on curved rows; on straight rows the mount prior holds most of it (a 5 cm
  /// error came out as 1-2 cm), so it is off by default and the report says so.
  bool estimate_across_beam = false;
};

class RangerMountFitError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Throws RangerMountFitError when a value is outside its domain.
void ValidateRangerMountFitConfig(const RangerMountFitConfig& config);

/// The result for one ranger.
struct RangerMountEstimate {
  std::string name;
  Eigen::Vector2d configured_lever_arm_m = Eigen::Vector2d::Zero();  ///< body (x, y) of the vehicle file
  Eigen::Vector2d lever_arm_m = Eigen::Vector2d::Zero();             ///< estimated body (x, y)
  double along_beam_m = 0.0;   ///< correction along the beam (+: the sensor is further towards what it hears)
  double across_beam_m = 0.0;  ///< correction across the beam (+: 90 degrees ccw of the beam)
  /// 1-sigma of along_beam_m / across_beam_m from the problem's curvature (Ceres covariance); NaN
  /// where it could not be computed. Conditional on the other rangers' priors (see the header comment).
  double along_beam_sigma_m = 0.0;
  double across_beam_sigma_m = 0.0;
  bool calibrated = false;       ///< false: fewer than min_echoes_per_ranger echoes; kept as configured
  std::size_t echoes = 0;        ///< of this ranger in the drive's calibrated span
  std::size_t echoes_used = 0;   ///< associated with a row in the last pass
  double rms_before_m = 0.0;     ///< residual RMS of the used echoes at the configured mount and the uncorrected reference (first pass)
  double rms_after_m = 0.0;      ///< at the estimate (last pass)
};

struct RangerMountFit {
  std::vector<RangerMountEstimate> rangers;  ///< vehicle order
  /// The mean along-beam correction over the calibrated rangers: indistinguishable from the map's
  /// lanes being narrower (+) or wider than the canopy the rangers hear.
  double common_along_beam_m = 0.0;
  std::size_t knots = 0;
  std::size_t echoes_used = 0;
  std::size_t echoes_unassociated = 0;  ///< no row within the gate (gaps, other rows, outside the map)
  std::size_t echoes_outside_reference = 0;  ///< before the filter initialised, after its end, in a gap
  double position_correction_rms_m = 0.0;    ///< RMS of the knots' position corrections: how far the reference was off
  int solver_iterations = 0;                 ///< over all passes
  std::string solver_report;                 ///< Ceres's brief report of the last pass
};

/// One smoothed or filtered pose of the drive (a knot of the pose corrections).
struct ReferenceKnot {
  double time_s = 0.0;
  Eigen::Vector3d pose = Eigen::Vector3d::Zero();  ///< (X, Y, phi) in the ranging's local frame, (m, m, rad)
  /// The filter's body velocity and yaw rate (v_x, v_y, r), (m/s, m/s, rad/s), if known: the motion
  /// between two knots that both have them is dead-reckoned from them (a filtered trajectory, whose
  /// position updates do not follow its heading); otherwise it is the reference's own displacement
  /// (a smoothed trajectory, consistent with its headings).
  std::optional<Eigen::Vector3d> body_rates;
};

/// One echo (a ping with a range).
struct EchoRecord {
  double time_s = 0.0;
  std::size_t ranger = 0;  ///< index in `mounts`
  double range_m = 0.0;    ///< > 0
};

/// Solves the problem of the header comment. knots: time order, >= 2; echoes: time order, rangers
/// indexing `mounts` (the vehicle's ultrasonic list); cone_half_angle_rad and max_range_m: the
/// sound cone and range limit (filter config map_aided). Throws RangerMountFitError for an invalid
/// configuration, fewer than two knots, a drive whose echoes mostly meet no row (the map is not of
/// this field), and std::invalid_argument for an echo of a ranger `mounts` does not list.
RangerMountFit FitRangerMounts(const RowMapRanging& ranging, const std::vector<mapio::SensorMount>& mounts,
                               double cone_half_angle_rad, double max_range_m, const std::vector<ReferenceKnot>& knots,
                               const std::vector<EchoRecord>& echoes, const RangerMountFitConfig& config = {});

/// dr / d(along, across) of a mount correction: moving the sensor by B c in the body moves it by
/// R(phi) B c in the world, as a pose translation would: H_p R(phi) B (H_p = pose_jacobian's
/// position part, dr/d(X, Y); phi the heading; B the beam frame of beam_angle_rad).
Eigen::RowVector2d MountRangeJacobian(const Eigen::RowVector3d& pose_jacobian, double heading_rad,
                                      double beam_angle_rad);

}  // namespace rowloc::localization
