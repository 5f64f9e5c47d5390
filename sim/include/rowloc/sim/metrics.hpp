// Validation metrics of an estimated trajectory against the ground truth (docs/validation.md;
// issue 3 "Metrics and reports"). Pure functions on value types; Evaluate() runs them all.
//
// Math (docs/validation.md gives the full definitions):
//  - Truth at an estimate's time t: linear interpolation between the bracketing truth samples,
//    heading interpolated on the circle (phi0 + s wrap(phi1 - phi0)), per-wheel slip and rolling
//    radius linearly.
//    An estimate outside [t_first, t_last] of the truth is an EvaluationError (no extrapolation).
//  - Error e = estimate - truth (world ENU). Reference direction u: the direction of the row
//    segment nearest to the true position (flipped to agree with the true heading) when a row map
//    is given, else the true heading. along = e.u, across = e.n with n = u rotated +90 deg
//    (left of travel positive). Heading error wrap(phi_est - phi_true) in (-pi, pi].
//  - Statistics: mean, population std (1/N), RMS and max |.|; across uses |across| plus the
//    signed mean.
//  - NEES e' P^-1 e over (x, y, phi) with a 3x3 covariance and a heading (3 dof), otherwise over
//    (x, y) (2 dof, the upper-left block), skipped and counted when that block is singular; NIS v' S^-1 v from the update's innovation and S
//    (Eigen LDLT), compared with the recorded nis (relative difference > 1e-6 is a mismatch).
//    Bands: chi_square_bands.hpp. NIS statistics and whiteness use the accepted updates only;
//    the fraction gated out is reported next to them.
//  - Whiteness (Lindgren et al. 2002, Eq. 42) on the whitened innovations w_k = L_k^-1 v_k (S_k = L_k L_k'):
//    rho(l) = sum_k w_k'w_{k+l} / sqrt(sum_k w_k'w_k * sum_k w_{k+l}'w_{k+l}), k = 1..K-l, for
//    l = 1..L; inside the band when |rho(l)| <= 1.96/sqrt(K m) for innovations of length m. For
//    m = 1 this is the paper's 1.96/sqrt(K); for m > 1 the paper's band is too wide (the variance of
//    rho for whitened m-vectors is 1/(K m): with m = 2 it covers ~99.4 %, not 95 %).
//  - Drift after loss of absolute fixes: every maximal run of truth samples with
//    gnss_available = false lasting >= min duration (from its first sample to the first sample
//    with fixes again, or to the last truth sample if they never return); the position error of
//    the first estimate at or after the start, of the last estimate at or before the end, their
//    difference (growth) and the largest error in between.
//  - Slip: estimate's slip minus the interpolated truth's slip, per wheel named in both.
//  - Rolling radius (the slip-aware odometry's R_w, `wheel_calibration`) against the truth's
//    rolling_radius_m, per wheel named in both: error R_w - R_a, and its NEES
//    (R_w - R_a)^2 / sigma_R^2 (1 dof) over the estimates whose sigma_R > 0.
#pragma once

#include "rowloc/formats/trajectory_streams.hpp"
#include "rowloc/geometry/segment_index.hpp"
#include "rowloc/sim/batch_means.hpp"
#include "rowloc/sim/chi_square_bands.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace rowloc::sim {

/// The streams cannot be compared (e.g. an estimate outside the truth's time span).
class EvaluationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Wraps an angle to (-pi, pi].
double WrapAngle(double angle_rad);

/// Summary statistics of a sample (all zero when count == 0).
struct ErrorStatistics {
  std::size_t count = 0;
  double mean = 0.0;
  double std = 0.0;      ///< population standard deviation (1/N)
  double rms = 0.0;
  double max_abs = 0.0;  ///< largest |value|
};
ErrorStatistics Summarize(const std::vector<double>& values);

/// The truth at one instant.
struct TruthState {
  double t_s = 0.0;
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  double phi_rad = 0.0;
  std::map<std::string, double> wheel_slip;  ///< wheels with a slip in both bracketing samples
  std::map<std::string, double> wheel_rolling_radius_m;  ///< wheels with a radius in both, m
};

/// Truth interpolated at t_s. Throws EvaluationError if the truth is empty or t_s is outside its span.
TruthState InterpolateTruth(const formats::TruthStream& truth, double t_s);

enum class AlongAcrossReference { kTrueHeading, kRowDirection };

/// Unit reference direction u at the true pose (see the header comment).
Eigen::Vector2d AlongDirection(const Eigen::Vector2d& true_position_m, double true_phi_rad,
                               const std::optional<geometry::SegmentIndex>& rows);

/// Error of one estimate.
struct PoseError {
  double t_s = 0.0;
  Eigen::Vector2d error_m = Eigen::Vector2d::Zero();  ///< estimate - truth, world ENU
  double along_m = 0.0;
  double across_m = 0.0;  ///< signed, left of the reference direction positive
  double total_m = 0.0;
  std::optional<double> heading_rad;        ///< wrapped; absent without an estimated heading
  std::optional<double> nees;               ///< absent without a (non-singular) covariance
  bool covariance_singular = false;         ///< covariance given but singular: no NEES
  int nees_dof = 0;                         ///< 3 (x, y, phi) or 2 (x, y)
  std::optional<double> sigma_along_m;      ///< sqrt(u' P_xy u)
  std::optional<double> sigma_across_m;     ///< sqrt(n' P_xy n)
  std::optional<double> sigma_heading_rad;  ///< sqrt(P_phiphi) (3x3 covariance only)
};

/// Errors of every estimate, in stream order. Throws EvaluationError (naming the estimate's
/// line) when an estimate lies outside the truth's time span.
std::vector<PoseError> ComputePoseErrors(const formats::TruthStream& truth, const formats::EstimateStream& estimates,
                                         const std::optional<geometry::SegmentIndex>& rows);

struct PositionSummary {
  ErrorStatistics total_m;
  ErrorStatistics along_m;          ///< signed along-row errors
  ErrorStatistics across_abs_m;     ///< |across|
  double across_signed_mean_m = 0.0;
  ErrorStatistics heading_rad;      ///< count 0 when no estimate has a heading
};
PositionSummary SummarizePoseErrors(const std::vector<PoseError>& errors);

/// A NEES or NIS sequence against its bands.
struct ConsistencySummary {
  std::size_t count = 0;
  double total_dof = 0.0;
  double mean = 0.0;              ///< time average
  ChiSquareBand band;             ///< band of the time average
  bool mean_inside = false;
  double fraction_inside = 0.0;   ///< samples inside their own per-sample interval
  double probability = 0.95;
  /// The band above assumes independent samples; a filter's NEES/NIS is correlated in time
  /// (batch_means.hpp). The batch-means interval of the expected value, from min(20, count /
  /// (4 tau)) batches of at least 4 correlation times each; absent when that is fewer than 5
  /// batches (the run is too short against its correlation time to test its mean).
  /// expected_inside: the interval holds the consistent filter's mean dof.
  std::optional<BatchMeansInterval> batch_means;
  bool expected_inside = false;
  double correlation_time_samples = 1.0;  ///< integrated autocorrelation time tau
  double effective_sample_count = 0.0;    ///< count / tau
};
/// values[k] ~ chi2(dofs[k]) for a consistent filter. Sizes must agree (std::invalid_argument);
/// an empty input gives count == 0.
ConsistencySummary SummarizeConsistency(const std::vector<double>& values, const std::vector<int>& dofs,
                                        double probability = 0.95);

struct WhitenessResult {
  std::size_t sample_count = 0;        ///< K
  std::vector<double> autocorrelation; ///< rho(1..L), L = min(max_lag, K - 1)
  double band_half_width = 0.0;        ///< z / sqrt(K m), m = innovation length
  double fraction_inside = 0.0;
  std::string not_computed;            ///< reason when not computed (too few samples, mixed sizes)
};
/// Eq. 42 of Lindgren et al. 2002 on already whitened innovations.
WhitenessResult InnovationWhiteness(const std::vector<Eigen::VectorXd>& whitened, std::size_t max_lag,
                                    double probability = 0.95);

struct SensorInnovationResult {
  std::string sensor;
  std::size_t update_count = 0;
  std::size_t gated_out_count = 0;
  double gated_out_fraction = 0.0;
  std::size_t nis_mismatch_count = 0;     ///< recorded nis differs by > 1e-6 relative
  double max_nis_relative_difference = 0.0;
  ConsistencySummary nis;                 ///< accepted updates
  WhitenessResult whiteness;              ///< accepted updates
  std::vector<double> times_s;            ///< every update (for plots)
  std::vector<double> nis_values;         ///< recomputed, every update
  std::vector<int> dofs;                  ///< innovation length, every update
};
/// One result per sensor name, sorted by name.
std::vector<SensorInnovationResult> AnalyzeInnovations(const std::vector<formats::UpdateRecord>& updates,
                                                       std::size_t max_lag, double probability = 0.95);

struct DriftInterval {
  double start_s = 0.0;
  double end_s = 0.0;
  bool fixes_returned = false;
  std::size_t estimate_count = 0;  ///< estimates in [start, end]; errors below are 0 when none
  double error_start_m = 0.0;
  double error_end_m = 0.0;
  double growth_m = 0.0;           ///< error_end - error_start
  double max_error_m = 0.0;
};
std::vector<DriftInterval> DriftAfterFixLoss(const formats::TruthStream& truth, const std::vector<PoseError>& errors,
                                             double min_duration_s = 5.0);

struct WheelSlipError {
  std::string wheel;
  ErrorStatistics error;  ///< estimate - truth (mean signed, max |.|, RMS)
};
/// Per wheel named in both an estimate's slip and the interpolated truth, sorted by name.
std::vector<WheelSlipError> CompareWheelSlip(const formats::TruthStream& truth,
                                             const formats::EstimateStream& estimates);

struct RollingRadiusError {
  std::string wheel;
  ErrorStatistics error_m;        ///< R_w - R_a over every estimate with both, m
  ConsistencySummary nees;        ///< (R_w - R_a)^2 / sigma^2, 1 dof, estimates with sigma > 0
  std::size_t zero_sigma_count = 0;  ///< estimates with sigma = 0 (no NEES)
  double final_estimate_m = 0.0;  ///< R_w of the last estimate with both
  double final_sigma_m = 0.0;     ///< its sigma
  double final_truth_m = 0.0;     ///< R_a interpolated at its time
};
/// Per wheel named in both an estimate's `wheel_calibration` and the interpolated truth's
/// rolling radius, sorted by name; empty when no estimate carries a calibration.
std::vector<RollingRadiusError> CompareRollingRadius(const formats::TruthStream& truth,
                                                     const formats::EstimateStream& estimates,
                                                     double probability = 0.95);

struct EvaluationOptions {
  std::size_t max_lag = 50;          ///< whiteness lags 1..max_lag
  double probability = 0.95;         ///< of every band
  double drift_min_duration_s = 5.0;
  std::optional<geometry::SegmentIndex> rows;  ///< row map (reference = row direction)
};

struct EvaluationResult {
  AlongAcrossReference reference = AlongAcrossReference::kTrueHeading;
  std::size_t truth_count = 0;
  std::size_t estimate_count = 0;
  double start_s = 0.0;  ///< first estimate time
  double end_s = 0.0;    ///< last estimate time
  std::vector<PoseError> pose_errors;
  PositionSummary position;
  ConsistencySummary nees;  ///< count 0 without covariances
  std::size_t singular_covariance_count = 0;  ///< estimates whose covariance is singular (no NEES)
  std::vector<SensorInnovationResult> innovations;
  std::vector<DriftInterval> drift;
  std::vector<WheelSlipError> slip;
  std::vector<RollingRadiusError> rolling_radius;
  EvaluationOptions options;
};

/// All metrics. Throws EvaluationError (no estimates, estimate outside the truth span).
EvaluationResult Evaluate(const formats::TruthStream& truth, const formats::EstimateStream& estimates,
                          const EvaluationOptions& options);

}  // namespace rowloc::sim
