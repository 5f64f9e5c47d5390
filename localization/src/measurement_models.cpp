#include "rowloc/localization/measurement_models.hpp"

#include "rowloc/localization/wheel_slip_estimate.hpp"

#include <cmath>
#include <stdexcept>

namespace rowloc::localization {

using L = StateLayout;

namespace {

/// out: h = rows zeros, H = rows x cols zeros; resizes only on a size change.
void SetZero(LinearizedMeasurement& out, Eigen::Index rows, Eigen::Index cols) {
  out.predicted.setZero(rows);
  out.jacobian.setZero(rows, cols);
}

double SteeringAngle(const Eigen::VectorXd& x, const StateLayout& layout, std::size_t i) {
  return layout.steering[i] >= 0 ? x(layout.steering[i]) : 0.0;
}

/// Wheel i's centre velocity (vx - r l_y, vy + r l_x) in the body frame and the cos/sin of its
/// steering angle: what the wheel-speed and non-holonomic models (and their Jacobians) share.
struct WheelCentre {
  double c, s, along_x, along_y;
  double longitudinal() const { return c * along_x + s * along_y; }
  double lateral() const { return -s * along_x + c * along_y; }
};

/// The traction coefficient the body acceleration demands of a wheel: its acceleration along the
/// wheel over g (WheelTractionCoefficient).
double TractionFromAcceleration(const Eigen::VectorXd& x, const WheelCentre& w) {
  return (w.c * x(L::kAx) + w.s * x(L::kAy)) / kStandardGravityMps2;
}

WheelCentre CentreOf(const Eigen::VectorXd& x, const mapio::VehicleConfig& vehicle, const StateLayout& layout,
                     std::size_t i) {
  const Eigen::Vector2d& l = vehicle.wheels[i].position_m;
  const double r = x(L::kYawRate), delta = SteeringAngle(x, layout, i);
  return {std::cos(delta), std::sin(delta), x(L::kVx) - r * l.y(), x(L::kVy) + r * l.x()};
}

}  // namespace

void GpsAntennaModel(const Eigen::VectorXd& x, const Eigen::Vector2d& l, int gnss_bias_index, LinearizedMeasurement& m) {
  SetZero(m, 2, x.size());
  const double c = std::cos(x(L::kPhi)), s = std::sin(x(L::kPhi));
  m.predicted << x(L::kX) + c * l.x() - s * l.y(), x(L::kY) + s * l.x() + c * l.y();
  m.jacobian(0, L::kX) = 1.0;
  m.jacobian(1, L::kY) = 1.0;
  m.jacobian(0, L::kPhi) = -s * l.x() - c * l.y();
  m.jacobian(1, L::kPhi) = c * l.x() - s * l.y();
  if (gnss_bias_index >= 0) {
    m.predicted += x.segment<2>(gnss_bias_index);
    m.jacobian(0, gnss_bias_index) = 1.0;
    m.jacobian(1, gnss_bias_index + 1) = 1.0;
  }
}

void ImuModel(const Eigen::VectorXd& x, const Eigen::Vector2d& l, int accel_bias_index, LinearizedMeasurement& m) {
  SetZero(m, 3, x.size());
  const double r = x(L::kYawRate);
  m.predicted << x(L::kAx) - r * r * l.x(), x(L::kAy) - r * r * l.y(), r + x(L::kGyroBias);
  m.jacobian(0, L::kAx) = 1.0;
  m.jacobian(0, L::kYawRate) = -2.0 * r * l.x();
  m.jacobian(1, L::kAy) = 1.0;
  m.jacobian(1, L::kYawRate) = -2.0 * r * l.y();
  m.jacobian(2, L::kYawRate) = 1.0;
  m.jacobian(2, L::kGyroBias) = 1.0;
  if (accel_bias_index >= 0) {
    m.predicted(0) += x(accel_bias_index);
    m.predicted(1) += x(accel_bias_index + 1);
    m.jacobian(0, accel_bias_index) = 1.0;
    m.jacobian(1, accel_bias_index + 1) = 1.0;
  }
}

double WheelLongitudinalVelocity(const Eigen::VectorXd& x, const mapio::VehicleConfig& vehicle,
                                 const StateLayout& layout, std::size_t i) {
  return CentreOf(x, vehicle, layout, i).longitudinal();
}

double WheelTractionScaleNm(const mapio::VehicleConfig& vehicle, std::size_t i) {
  const double load_n = vehicle.mass_kg * kStandardGravityMps2 / static_cast<double>(vehicle.wheels.size());
  return load_n * vehicle.wheels[i].nominal_radius_m;
}

double WheelRollingRadius(const Eigen::VectorXd& x, const mapio::VehicleConfig& vehicle,
                          const StateLayout& layout, std::size_t i) {
  return layout.rolling_radius[i] >= 0 ? x(layout.rolling_radius[i]) : vehicle.wheels[i].nominal_radius_m;
}

TurningTraction TurningResistanceTraction(const mapio::VehicleConfig& vehicle, std::size_t i, double yaw_rate_radps) {
  if (vehicle.kind != mapio::VehicleKind::kSkidSteer || !vehicle.tracks || vehicle.wheels.size() != 2) return {};
  const double gauge_m = std::abs(vehicle.wheels[0].position_m.y() - vehicle.wheels[1].position_m.y());
  const double scale = -std::copysign(1.0, vehicle.wheels[i].position_m.y()) *
                       vehicle.tracks->turning_resistance_coefficient * vehicle.tracks->contact_length_m / (2.0 * gauge_m);
  const double full_radps = 2.0 * kSlipDeadbandMps / gauge_m;          // r_0
  const double start_radps = kTurningTractionDeadZone * full_radps;    // r_0 / 2
  const double turn_radps = std::abs(yaw_rate_radps);
  if (turn_radps <= start_radps) return {};
  const double sign = std::copysign(1.0, yaw_rate_radps);
  if (turn_radps >= full_radps) return {scale * sign, 0.0};
  const double ramp = 1.0 / (full_radps - start_radps);
  return {scale * sign * (turn_radps - start_radps) * ramp, scale * ramp};
}

namespace {
/// The traction coefficient of wheel i (WheelTractionCoefficient's rule): the traction state when
/// the torques measure one, else the torque over N r, else the motion's (centre() gives the
/// wheel's direction: called only then), else 0.
template <typename Centre>
double Traction(const Eigen::VectorXd& x, const mapio::VehicleConfig& vehicle, const StateLayout& layout, std::size_t i,
                const std::optional<std::vector<double>>& torque_nm, bool from_acceleration, Centre&& centre) {
  if (torque_nm && layout.traction[i] >= 0) return x(layout.traction[i]);
  if (torque_nm) return (*torque_nm)[i] / WheelTractionScaleNm(vehicle, i);
  if (!from_acceleration) return 0.0;
  return TractionFromAcceleration(x, centre()) + TurningResistanceTraction(vehicle, i, x(L::kYawRate)).value;
}
}  // namespace

double WheelTractionCoefficient(const Eigen::VectorXd& x, const mapio::VehicleConfig& vehicle, const StateLayout& layout,
                                std::size_t i, const std::optional<std::vector<double>>& torque_nm,
                                bool from_acceleration) {
  if (i >= vehicle.wheels.size()) throw std::invalid_argument("traction coefficient: no such wheel");
  if (torque_nm && torque_nm->size() != vehicle.wheels.size()) {
    throw std::invalid_argument("traction coefficient: one torque per wheel");
  }
  return Traction(x, vehicle, layout, i, torque_nm, from_acceleration, [&] { return CentreOf(x, vehicle, layout, i); });
}

void WheelSpeedModel(const Eigen::VectorXd& x, const mapio::VehicleConfig& vehicle, const StateLayout& layout,
                     const std::optional<std::vector<double>>& torque_nm, double encoder_lag_s,
                     bool traction_from_acceleration, LinearizedMeasurement& m) {
  const std::size_t n = vehicle.wheels.size();
  if (torque_nm && torque_nm->size() != n) throw std::invalid_argument("wheel model: one torque per wheel");
  if (!(std::isfinite(encoder_lag_s) && encoder_lag_s >= 0.0)) {
    throw std::invalid_argument("wheel model: encoder lag must be finite and >= 0");
  }
  SetZero(m, static_cast<Eigen::Index>(n), x.size());
  const double tau = encoder_lag_s, r = x(L::kYawRate), vx = x(L::kVx), vy = x(L::kVy);
  const double ax = x(L::kAx) + r * vy, ay = x(L::kAy) - r * vx;  // d(vx, vy)/dt of the motion model
  for (std::size_t i = 0; i < n; ++i) {
    const auto row = static_cast<Eigen::Index>(i);
    const Eigen::Vector2d& l = vehicle.wheels[i].position_m;
    const WheelCentre w = CentreOf(x, vehicle, layout, i);
    const double c = w.c, s = w.s;
    const double v = w.longitudinal() - tau * (c * ax + s * ay);  // the speed the encoder reports
    const double radius = WheelRollingRadius(x, vehicle, layout, i);
    double gain = 1.0;      // 1 / (1 - kappa mu) = k_s / (k_s - T)
    double dh_dmu = 0.0;    // of a traction from the acceleration (0 with torques)
    if (layout.slip_aware()) {
      const double kappa = x(layout.slip_compliance[i]);
      const bool mu_state = torque_nm && layout.traction[i] >= 0;  // the torques measure the state mu
      const double mu = Traction(x, vehicle, layout, i, torque_nm, traction_from_acceleration, [&] { return w; });
      gain = 1.0 / (1.0 - kappa * mu);
      m.jacobian(row, layout.slip_compliance[i]) = v / radius * mu * gain * gain;
      m.jacobian(row, layout.rolling_radius[i]) = -v * gain / (radius * radius);
      if (mu_state) m.jacobian(row, layout.traction[i]) = v / radius * kappa * gain * gain;
      if (!torque_nm && traction_from_acceleration) dh_dmu = v / radius * kappa * gain * gain;
    }
    const double dv = gain / radius;  // d h / d v
    m.predicted(row) = v * dv;
    m.jacobian(row, L::kVx) = dv * (c + tau * s * r);
    m.jacobian(row, L::kVy) = dv * (s - tau * c * r);
    m.jacobian(row, L::kYawRate) = dv * ((-c * l.y() + s * l.x()) - tau * (c * vy - s * vx));
    if (tau > 0.0) {
      m.jacobian(row, L::kAx) = -dv * tau * c;
      m.jacobian(row, L::kAy) = -dv * tau * s;
    }
    if (layout.steering[i] >= 0) {  // d v / d delta
      m.jacobian(row, layout.steering[i]) = dv * (w.lateral() - tau * (-s * ax + c * ay));
    }
    if (dh_dmu != 0.0) {  // mu = (c a_x + s a_y) / g + tau_i(r)
      const double g = kStandardGravityMps2;
      m.jacobian(row, L::kAx) += dh_dmu * c / g;
      m.jacobian(row, L::kAy) += dh_dmu * s / g;
      m.jacobian(row, L::kYawRate) += dh_dmu * TurningResistanceTraction(vehicle, i, r).d_yaw_rate;
      if (layout.steering[i] >= 0) m.jacobian(row, layout.steering[i]) += dh_dmu * (-s * x(L::kAx) + c * x(L::kAy)) / g;
    }
  }
}

void WheelLateralVelocityModel(const Eigen::VectorXd& x, const mapio::VehicleConfig& vehicle,
                               const StateLayout& layout, LinearizedMeasurement& m) {
  const std::size_t n = vehicle.wheels.size();
  SetZero(m, static_cast<Eigen::Index>(n), x.size());
  for (std::size_t i = 0; i < n; ++i) {
    const auto row = static_cast<Eigen::Index>(i);
    const Eigen::Vector2d& l = vehicle.wheels[i].position_m;
    const WheelCentre w = CentreOf(x, vehicle, layout, i);
    const double c = w.c, s = w.s;
    m.predicted(row) = w.lateral();
    m.jacobian(row, L::kVx) = -s;
    m.jacobian(row, L::kVy) = c;
    m.jacobian(row, L::kYawRate) = s * l.y() + c * l.x();
    if (layout.steering[i] >= 0) m.jacobian(row, layout.steering[i]) = -w.longitudinal();  // d lateral / d delta
  }
}

namespace {
/// h_j = x(index_of(j)), j < count, with unit rows in H.
template <typename IndexOf>
void UnitRows(const Eigen::VectorXd& x, std::size_t count, IndexOf&& index_of, LinearizedMeasurement& m) {
  SetZero(m, static_cast<Eigen::Index>(count), x.size());
  for (std::size_t j = 0; j < count; ++j) {
    const int index = index_of(j);
    m.predicted(static_cast<Eigen::Index>(j)) = x(index);
    m.jacobian(static_cast<Eigen::Index>(j), index) = 1.0;
  }
}
}  // namespace

void SelectedStatesModel(const Eigen::VectorXd& x, const std::vector<int>& indices, LinearizedMeasurement& m) {
  UnitRows(x, indices.size(), [&](std::size_t j) {
    if (indices[j] < 0 || indices[j] >= x.size()) throw std::invalid_argument("selected states: no such state");
    return indices[j];
  }, m);
}

void SteeringModel(const Eigen::VectorXd& x, const StateLayout& layout, const std::vector<std::size_t>& wheels,
                   LinearizedMeasurement& m) {
  UnitRows(x, wheels.size(), [&](std::size_t j) {
    const int index = layout.steering.at(wheels[j]);
    if (index < 0) throw std::invalid_argument("steering model: wheel is not steerable");
    return index;
  }, m);
}

void VioModel(const Eigen::VectorXd& x, const Eigen::Vector2d& l, LinearizedMeasurement& m) {
  SetZero(m, 2, x.size());
  const double r = x(L::kYawRate);
  m.predicted << x(L::kVx) - r * l.y(), x(L::kVy) + r * l.x();
  m.jacobian(0, L::kVx) = 1.0;
  m.jacobian(0, L::kYawRate) = -l.y();
  m.jacobian(1, L::kVy) = 1.0;
  m.jacobian(1, L::kYawRate) = l.x();
}

// The value-returning forms.

LinearizedMeasurement GpsAntennaModel(const Eigen::VectorXd& x, const Eigen::Vector2d& lever_arm_m,
                                      int gnss_bias_index) {
  LinearizedMeasurement m;
  GpsAntennaModel(x, lever_arm_m, gnss_bias_index, m);
  return m;
}

LinearizedMeasurement ImuModel(const Eigen::VectorXd& x, const Eigen::Vector2d& lever_arm_m, int accel_bias_index) {
  LinearizedMeasurement m;
  ImuModel(x, lever_arm_m, accel_bias_index, m);
  return m;
}

LinearizedMeasurement WheelSpeedModel(const Eigen::VectorXd& x, const mapio::VehicleConfig& vehicle,
                                      const StateLayout& layout,
                                      const std::optional<std::vector<double>>& torque_nm, double encoder_lag_s,
                                      bool traction_from_acceleration) {
  LinearizedMeasurement m;
  WheelSpeedModel(x, vehicle, layout, torque_nm, encoder_lag_s, traction_from_acceleration, m);
  return m;
}

LinearizedMeasurement WheelLateralVelocityModel(const Eigen::VectorXd& x, const mapio::VehicleConfig& vehicle,
                                                const StateLayout& layout) {
  LinearizedMeasurement m;
  WheelLateralVelocityModel(x, vehicle, layout, m);
  return m;
}

LinearizedMeasurement SteeringModel(const Eigen::VectorXd& x, const StateLayout& layout,
                                    const std::vector<std::size_t>& wheels) {
  LinearizedMeasurement m;
  SteeringModel(x, layout, wheels, m);
  return m;
}

LinearizedMeasurement VioModel(const Eigen::VectorXd& x, const Eigen::Vector2d& lever_arm_m) {
  LinearizedMeasurement m;
  VioModel(x, lever_arm_m, m);
  return m;
}

}  // namespace rowloc::localization
