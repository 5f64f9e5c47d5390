// The wheel torques and the traction states' measurement (traction_updater.hpp).
#include "rowloc/localization/traction_updater.hpp"

#include "rowloc/localization/kalman_update.hpp"

#include <stdexcept>
#include <string>

namespace rowloc::localization {

TractionUpdater::TractionUpdater(const mapio::VehicleConfig& vehicle, const FilterConfig& config,
                                 const StateLayout& layout)
    : torque_sigma_nm_(config.slip_aware_odometry.torque_sigma_nm), states_(layout.traction) {
  if (layout.wheel_count() != vehicle.wheels.size()) {
    throw std::invalid_argument("traction: the layout has " + std::to_string(layout.wheel_count()) +
                                " wheels, the vehicle '" + vehicle.name + "' " + std::to_string(vehicle.wheels.size()));
  }
  for (std::size_t i = 0; i < vehicle.wheels.size(); ++i) scale_nm_.push_back(WheelTractionScaleNm(vehicle, i));
  if (layout.has_traction()) {
    gate_ = ChiSquareGate(static_cast<int>(vehicle.wheels.size()), config.wheels.gate_probability);
  }
}

void TractionUpdater::ObserveTorques(const formats::WheelsMessage& wheels, const std::vector<std::size_t>& wheel_index) {
  if (!wheels.torque_nm) {
    last_torque_nm_.reset();
    return;
  }
  if (!last_torque_nm_) last_torque_nm_.emplace(scale_nm_.size(), 0.0);
  for (std::size_t j = 0; j < wheel_index.size(); ++j) (*last_torque_nm_)[wheel_index[j]] = (*wheels.torque_nm)[j];
}

const TractionMeasurement& TractionUpdater::Measure(const Eigen::VectorXd& x) {
  if (states_.empty() || states_.front() < 0) throw std::logic_error("traction update: no traction states");
  if (!last_torque_nm_) throw std::logic_error("traction update: no torques");
  TractionMeasurement& m = measurement_;
  const auto n = static_cast<Eigen::Index>(scale_nm_.size());
  m.measured.resize(n);
  m.noise.setZero(n, n);
  for (std::size_t i = 0; i < scale_nm_.size(); ++i) {
    const auto row = static_cast<Eigen::Index>(i);
    const double sigma = torque_sigma_nm_ / scale_nm_[i];
    m.measured(row) = (*last_torque_nm_)[i] / scale_nm_[i];
    m.noise(row, row) = sigma * sigma;
  }
  SelectedStatesModel(x, states_, m.model);
  m.innovation = m.measured - m.model.predicted;
  m.gate = gate_;
  return m;
}

TractionPrior TractionUpdater::Initial(std::size_t wheel) const {
  const double sigma = torque_sigma_nm_ / scale_nm_.at(wheel);
  if (!last_torque_nm_) return {0.0, 0.25};
  return {(*last_torque_nm_)[wheel] / scale_nm_[wheel], sigma * sigma};
}

}  // namespace rowloc::localization
