// When and how the encoders' cumulative angles update the wheel-angle states (issue 29 item 2;
// wheel_angle_model.hpp states the model: one state theta_i per wheel, z_i = theta_i + e_i with
// Var e_i = wheels.angle_sigma_rad^2). The angle's offset is arbitrary, so the states are anchored
// to the first measured angles (theta_i = z_i with variance sigma^2, uncorrelated with the rest),
// and again whenever the update cannot be trusted. For each wheels message with angles:
//   - anchored, and no wheel ticked since the last message (the same angles): the vehicle is at
//     rest, the quantization error frozen, a bias the update would keep integrating: the speeds
//     are used instead (kUseSpeeds);
//   - anchored, and a predicted angle's sigma above wheels.angle_max_prediction_sigma_rad (the
//     wheel rates not yet known to about a tick per sample: a precise angle linearized far from
//     the truth can drive the filter away, docs/notes/2026-12-02-localization-filter.md §5.7):
//     re-anchored, and the speeds used (kAnchorAndUseSpeeds);
//   - anchored otherwise: the update (kUpdate); the filter re-anchors when its gate refuses it;
//   - not anchored (the first angles since (re-)initialisation): anchored (kAnchor).
// The filter (VehicleEkf) makes the update of its full state and the anchoring, and reports them
// with MarkAnchored / Unanchor.
#pragma once

#include "rowloc/formats/sensor_messages.hpp"
#include "rowloc/localization/filter_config.hpp"
#include "rowloc/localization/measurement_models.hpp"
#include "rowloc/localization/state_layout.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace rowloc::localization {

/// What the filter does with a wheels message's angles (see the header comment).
enum class WheelAngleStep { kUseSpeeds, kAnchorAndUseSpeeds, kUpdate, kAnchor };

/// The wheel-angle update (WheelAngleUpdater::Measure); vehicle order.
struct WheelAngleMeasurement {
  LinearizedMeasurement model;  ///< h(x) = theta_i, H: unit rows of the angle states
  Eigen::VectorXd innovation;   ///< z - h(x), rad
  Eigen::MatrixXd noise;        ///< R = angle_sigma_rad^2 I, rad^2
  double gate = 0.0;            ///< chi-square gate of one row per wheel
};

class WheelAngleUpdater {
 public:
  /// layout: the filter's (the angle states, if any, in layout.wheel_angle).
  WheelAngleUpdater(const WheelNoise& config, const StateLayout& layout);

  /// Takes the message's angles (rad, vehicle order through wheel_index: message wheel j ->
  /// vehicle wheel wheel_index[j]) as measured() and says what to do with them; p: the filter's
  /// covariance (its angle states' variances). std::logic_error without angle states or angles.
  WheelAngleStep Plan(const formats::WheelsMessage& wheels, const std::vector<std::size_t>& wheel_index,
                      const Eigen::MatrixXd& p);
  /// The update of the planned angles at state x (kUpdate).
  const WheelAngleMeasurement& Measure(const Eigen::VectorXd& x);

  /// The last planned angles, rad, vehicle order: what the states are anchored to.
  const Eigen::VectorXd& measured() const { return measured_; }
  /// The variance of an anchored angle state, rad^2 (angle_sigma_rad^2).
  double anchor_variance() const { return config_.angle_sigma_rad * config_.angle_sigma_rad; }
  bool anchored() const { return anchored_; }
  /// The filter anchored the angle states to measured().
  void MarkAnchored() { anchored_ = true; }
  /// The angle states no longer hold the encoders' angles (the filter was (re-)initialised).
  void Unanchor() { anchored_ = false; }

 private:
  WheelNoise config_;
  StateLayout layout_;
  double gate_ = 0.0;  ///< set only with angle states (a quantile is costly)
  bool anchored_ = false;
  Eigen::VectorXd incoming_;           ///< the message's angles, vehicle order (scratch)
  Eigen::VectorXd measured_;           ///< the last planned angles
  WheelAngleMeasurement measurement_;  ///< reused: no allocation per message once sizes repeat
};

}  // namespace rowloc::localization
