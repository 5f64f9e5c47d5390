// The wheel torques and the traction states (issue 29 item 2; docs/notes/2026-12-02-localization-
// filter.md §5.5): the last wheels message's torques, an input of the wheel-speed model whatever the
// layout (WheelSpeedModel, WheelTractionCoefficient in measurement_models.hpp), and, with
// slip_aware_odometry.torque_sigma_nm > 0, their measurement of one traction coefficient state
// mu_i = T_i / (N r_i) per wheel (WheelTractionScaleNm: N r_i, N the wheel's share of the weight):
//   z_i = T_i / (N r_i),   h(x) = mu_i (unit rows, SelectedStatesModel),   R = diag(sigma_T / (N r_i))^2,
// gated at wheels.gate_probability. A torque step (the drive changed its command) fails the gate;
// the filter then re-anchors each mu_i to z_i with variance R_ii, uncorrelated with the rest.
// The filter (VehicleEkf) applies the measurement to its full state and does the re-anchoring.
#pragma once

#include "rowloc/formats/sensor_messages.hpp"
#include "rowloc/localization/filter_config.hpp"
#include "rowloc/localization/measurement_models.hpp"
#include "rowloc/localization/state_layout.hpp"
#include "rowloc/mapio/vehicle_config.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <optional>
#include <vector>

namespace rowloc::localization {

/// The torque update of the traction states (TractionUpdater::Measure); vehicle order.
struct TractionMeasurement {
  Eigen::VectorXd measured;    ///< z_i = T_i / (N r_i), dimensionless
  LinearizedMeasurement model;  ///< h(x) = mu_i, H: unit rows of the traction states
  Eigen::VectorXd innovation;  ///< z - h(x)
  Eigen::MatrixXd noise;       ///< R, diagonal
  double gate = 0.0;           ///< chi-square gate of one row per wheel
};

/// A traction state's value and variance at the filter's (re-)initialisation.
struct TractionPrior {
  double value = 0.0;     ///< mu
  double variance = 0.0;  ///< mu^2
};

class TractionUpdater {
 public:
  /// layout: the filter's (traction states, if any, in layout.traction). Throws
  /// std::invalid_argument when the layout does not have the vehicle's wheel count.
  TractionUpdater(const mapio::VehicleConfig& vehicle, const FilterConfig& config, const StateLayout& layout);

  /// Records the message's torques in vehicle order (wheel_index: message wheel j -> vehicle wheel
  /// wheel_index[j]), or their absence. The message's sizes are the caller's to check.
  void ObserveTorques(const formats::WheelsMessage& wheels, const std::vector<std::size_t>& wheel_index);
  /// The last wheels message's torques, N m, vehicle order; none when it carried none.
  const std::optional<std::vector<double>>& last_torque_nm() const { return last_torque_nm_; }

  /// The torque measurement at state x. std::logic_error without traction states or torques.
  const TractionMeasurement& Measure(const Eigen::VectorXd& x);
  /// Wheel `wheel`'s traction state at initialisation: the last torques with the torque noise, or
  /// 0 with variance 0.25 (|mu| ~ 0.5) before any torque.
  TractionPrior Initial(std::size_t wheel) const;

 private:
  std::vector<double> scale_nm_;     ///< N r_i per wheel, N m (WheelTractionScaleNm)
  double torque_sigma_nm_ = 0.0;
  std::vector<int> states_;          ///< layout.traction
  double gate_ = 0.0;                ///< set only with traction states (a quantile is costly)
  std::optional<std::vector<double>> last_torque_nm_;
  TractionMeasurement measurement_;  ///< reused: no allocation per message once sizes repeat
};

}  // namespace rowloc::localization
