// The GNSS bias (issue 29 item 2; gps.estimate_bias): the slowly varying part of the receiver's
// position error (multipath under canopy) as two states b = (b_E, b_N) (StateLayout::gnss_bias),
// per horizontal axis a first-order Gauss-Markov process b' = -b / tau + w (Gelb, "Applied Optimal
// Estimation", 1974, table 3.8-1; Brown & Hwang, "Introduction to Random Signals and Applied Kalman
// Filtering", 4th ed., §2.9), discretized exactly over a step dt:
//   b <- a b,   a = exp(-dt / tau),   Q_b = sigma_b^2 (1 - a^2)
// so that a stationary variance sigma_b^2 stays sigma_b^2 and the autocorrelation is
// sigma_b^2 exp(-|t| / tau). F is diagonal on the bias states and the base step does not touch
// them: their rows and columns of P are scaled by a (PredictStep, process_model.hpp, calls Propagate).
// The fix measures the antenna position plus the bias: h(x) = antenna(x) + b, H(:, b) = I
// (GpsAntennaModel, measurement_models.hpp). At (re-)initialisation the bias starts at 0 with its
// stationary variance; a position taken from a fix is that fix minus the bias, (x, b) = (z - b, b):
// P_xx += sigma_b^2 I and P_xb = -sigma_b^2 I.
// Without bias states (the layout's gnss_bias -1) every function leaves the state alone.
// The filter (VehicleEkf) applies the measurement to its full state and records the transition
// a I for the smoother.
#pragma once

#include "rowloc/localization/filter_config.hpp"
#include "rowloc/localization/measurement_models.hpp"
#include "rowloc/localization/state_layout.hpp"

#include <Eigen/Core>

namespace rowloc::localization {

class GnssBiasModel {
 public:
  /// gps: bias_sigma_m and bias_time_constant_s (checked by FilterConfigProblem); layout: the
  /// filter's (the bias states, if any, at layout.gnss_bias and the next index).
  GnssBiasModel(const GpsNoise& gps, const StateLayout& layout);

  bool estimated() const { return index_ >= 0; }
  /// Index of b_E (b_N follows), or -1.
  int index() const { return index_; }

  /// a = exp(-dt / tau), the bias's factor over a step of dt_s (1 without bias states).
  double Decay(double dt_s) const;
  /// The transition of the two bias states over dt_s: a I (for the smoother).
  Eigen::Matrix2d Transition(double dt_s) const { return Decay(dt_s) * Eigen::Matrix2d::Identity(); }
  /// The Gauss-Markov step of the bias states of (x, P) over dt_s (nothing without bias states).
  void Propagate(Eigen::VectorXd& x, Eigen::MatrixXd& p, double dt_s) const;

  /// sigma_b^2, the stationary (and initial) variance per axis, m^2.
  double StationaryVariance() const { return sigma_m_ * sigma_m_; }
  /// At (re-)initialisation, after the pose block of (x, P) is set: b = 0 with the stationary
  /// variance; position_from_gnss: the position is a fix's, so it carries the bias (P_xx += sigma_b^2 I,
  /// P_xb = -sigma_b^2 I). Nothing without bias states.
  void Initialise(Eigen::VectorXd& x, Eigen::MatrixXd& p, bool position_from_gnss) const;

  /// The GNSS antenna measurement at x (lever_arm_m: the antenna in the body frame), with the bias
  /// added and its unit columns when estimated.
  void MeasureAntenna(const Eigen::VectorXd& x, const Eigen::Vector2d& lever_arm_m, LinearizedMeasurement& out) const;

 private:
  int index_ = -1;
  double sigma_m_ = 0.0;
  double time_constant_s_ = 0.0;
};

}  // namespace rowloc::localization
