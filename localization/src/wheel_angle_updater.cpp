// When and how the encoders' angles update the wheel-angle states (wheel_angle_updater.hpp).
#include "rowloc/localization/wheel_angle_updater.hpp"

#include "rowloc/localization/kalman_update.hpp"
#include "rowloc/localization/wheel_angle_model.hpp"

#include <stdexcept>

namespace rowloc::localization {

WheelAngleUpdater::WheelAngleUpdater(const WheelNoise& config, const StateLayout& layout)
    : config_(config), layout_(layout) {
  if (layout_.has_wheel_angles()) gate_ = ChiSquareGate(static_cast<int>(layout_.wheel_count()), config_.gate_probability);
}

WheelAngleStep WheelAngleUpdater::Plan(const formats::WheelsMessage& wheels, const std::vector<std::size_t>& wheel_index,
                                       const Eigen::MatrixXd& p) {
  if (!layout_.has_wheel_angles()) throw std::logic_error("wheel angles: the layout has no wheel-angle states");
  if (!wheels.angle_rad) throw std::logic_error("wheel angles: the message has no angles");
  incoming_.resize(static_cast<Eigen::Index>(layout_.wheel_angle.size()));
  for (std::size_t j = 0; j < wheel_index.size(); ++j) {
    incoming_(static_cast<Eigen::Index>(wheel_index[j])) = (*wheels.angle_rad)[j];
  }
  if (anchored_ && incoming_ == measured_) return WheelAngleStep::kUseSpeeds;  // at rest
  measured_ = incoming_;
  if (!anchored_) return WheelAngleStep::kAnchor;
  const double max_sigma = config_.angle_max_prediction_sigma_rad;
  const double max_variance = max_sigma * max_sigma;
  for (const int k : layout_.wheel_angle) {
    if (p(k, k) > max_variance) return WheelAngleStep::kAnchorAndUseSpeeds;
  }
  return WheelAngleStep::kUpdate;
}

const WheelAngleMeasurement& WheelAngleUpdater::Measure(const Eigen::VectorXd& x) {
  WheelAngleMeasurement& m = measurement_;
  WheelAngleModel(x, layout_, m.model);
  const double s = config_.angle_sigma_rad;
  m.noise.setZero(measured_.size(), measured_.size());
  m.noise.diagonal().setConstant(s * s);
  m.innovation = measured_ - m.model.predicted;
  m.gate = gate_;
  return m;
}

}  // namespace rowloc::localization
