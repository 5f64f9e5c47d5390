// A change of terrain under a wheel, detected from its speed innovations (issue 28, "ground that
// changes along the row"; docs/localization-filter.md §4).
//
// Without torque sensors the slip-aware odometry's rolling radius R_w absorbs the terrain's steady
// slip: omega = v / R_w with R_w = R (1 - s). Where the terrain changes (grass to mud: s 0.125 to
// 0.25 in the simulator) the wheel's speed steps by 10-20 % while the vehicle's speed, held by the
// IMU and the other wheels, does not: a step in the wheel's innovation that a random walk of R_w
// sized for tyre wear (1e-5 m/sqrt(m)) cannot follow. The filter then either moves the vehicle's
// speed (the along-row error grows at sigma of millimetres) or gates the wheel out.
//
// The detector runs a two-sided CUSUM (Page 1954; Basseville & Nikiforov 1993, ch. 2) on each wheel's
// normalized innovation e_k = nu_k / sqrt(S_kk):
//   g+_k = max(0, g+_{k-1} + e_k - d),  g-_k = max(0, g-_{k-1} - e_k - d),
// and reports the wheel when g+ or g- exceeds h (drift d and threshold h in innovation sigmas;
// both sums restart at 0). For white N(0, 1) innovations and d = 1, h = 10 one side alarms about
// once in 2.5e9 samples (Siegmund's approximation of the average run length, (exp(2 d b) - 2 d b
// - 1) / (2 d^2) with b = h + 1.166; Siegmund 1985; Basseville & Nikiforov 1993, ch. 5); a 4-sigma
// step is reported within 4 samples. The filter then adds (radius_sigma_fraction R_nominal)^2 to
// that wheel's R_w variance: the state is unchanged, the next updates re-estimate the radius
// against the vehicle's speed (a covariance reset, as in
// Willsky & Jones 1976's jump detection followed by re-initialisation of the jumped state).
// The filter watches only while driving straight or on gentle curves (max_yaw_rate_radps): a turn
// changes the slips and gives them back, and a radius re-learnt in the turn from the IMU alone (no
// GNSS) is worse than the one kept (tracked-turns-gnss-loss: final error 0.69 to 1.74 m).
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace rowloc::localization {

/// The detector's settings (filter file: slip_aware_odometry.terrain_change, filter_config.hpp).
struct TerrainChangeConfig {
  bool enabled = true;
  double cusum_drift_sigma = 1.0;       ///< d: the CUSUM's allowance per sample, innovation sigmas, >= 0
  double cusum_threshold_sigma = 10.0;  ///< h: the alarm threshold, innovation sigmas, > 0
  double radius_sigma_fraction = 0.2;   ///< added R_w sigma, a fraction of the nominal radius, > 0
  /// Watched only while the filter's |yaw rate| is at most this, rad/s (>= 0): in a turn the
  /// wheels' slips change with the turn (a skid steer's outer track 0.13 to 0.40 in the simulator)
  /// and come back after it, which the radii must not learn as ground (the sums restart).
  double max_yaw_rate_radps = 0.05;
};

class TerrainChangeDetector {
 public:
  /// wheels: how many; config: its settings (valid: filter_config.hpp's Validate).
  TerrainChangeDetector(std::size_t wheels, const TerrainChangeConfig& config);

  /// One wheels update's normalized innovations (vehicle order; a wheel whose value is not finite,
  /// e.g. an excluded encoder, is skipped and its sums restart). Returns the wheels
  /// whose CUSUM crossed the threshold at this sample (their sums restart), in increasing order.
  const std::vector<std::size_t>& Observe(const Eigen::VectorXd& normalized_innovation);
  /// Restarts every sum (the filter re-initialised, or the wheel update was not made).
  void Reset();

  /// How many alarms each wheel has raised since construction (vehicle order).
  const std::vector<std::size_t>& alarms() const { return alarms_; }
  /// The current sums (g+, g-) of wheel i, innovation sigmas.
  double upper(std::size_t i) const { return upper_[i]; }
  double lower(std::size_t i) const { return lower_[i]; }

 private:
  TerrainChangeConfig config_;
  std::vector<double> upper_, lower_;
  std::vector<std::size_t> alarms_;
  std::vector<std::size_t> fired_;
};

}  // namespace rowloc::localization
