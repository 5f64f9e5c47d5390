#include "rowloc/sim/wheel_slip.hpp"

#include <Eigen/Core>
#include <Eigen/LU>
#include <boost/math/tools/toms748_solve.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

namespace rowloc::sim {
namespace {

void RequireFinite(double value, const char* what) {
  if (!std::isfinite(value)) throw std::invalid_argument(std::string(what) + " must be finite");
}

// f(x) = 1 - (1 - exp(-x))/x for x >= 0, series near 0 to avoid cancellation.
double ShapeFunction(double x) {
  if (x < 1e-3) return x * (0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x / 120.0)));
  return 1.0 + std::expm1(-x) / x;
}

// f'(x) = (1 - exp(-x)(1 + x)) / x^2, series near 0.
double ShapeDerivative(double x) {
  if (x < 1e-3) return 0.5 - x * (1.0 / 3.0 - x * (1.0 / 8.0 - x / 30.0));
  return (-std::expm1(-x) - x * std::exp(-x)) / (x * x);
}

struct SlipWithGradient {
  double slip;
  double d_slip_d_omega;
  double d_slip_d_speed;
};

// Regularized slip (denominator floored at the deadband speed) and its gradient; see header.
SlipWithGradient RegularizedSlip(double omega, double radius, double speed) {
  const double wheel_speed = omega * radius;
  const double denominator = std::max({std::abs(wheel_speed), std::abs(speed), kSlipDeadbandSpeedMps});
  SlipWithGradient result{(wheel_speed - speed) / denominator, 0.0, 0.0};
  if (std::abs(result.slip) >= 1.0) {
    result.slip = std::clamp(result.slip, -1.0, 1.0);
    return result;
  }
  if (denominator == std::abs(wheel_speed)) {  // s = 1 - v/(omega r)
    result.d_slip_d_omega = speed * radius / (wheel_speed * wheel_speed);
    result.d_slip_d_speed = -1.0 / wheel_speed;
  } else if (denominator == std::abs(speed)) {  // s = (omega r - v)/|v|
    result.d_slip_d_omega = radius / std::abs(speed);
    result.d_slip_d_speed = -wheel_speed / (speed * std::abs(speed));
  } else {  // s = (omega r - v)/v_floor
    result.d_slip_d_omega = radius / denominator;
    result.d_slip_d_speed = -1.0 / denominator;
  }
  return result;
}

}  // namespace

double SaeLongitudinalSlip(double wheel_angular_speed_rad_s, double rolling_radius_m,
                           double longitudinal_speed_mps) {
  RequireFinite(wheel_angular_speed_rad_s, "SaeLongitudinalSlip: wheel angular speed");
  RequireFinite(longitudinal_speed_mps, "SaeLongitudinalSlip: longitudinal speed");
  if (!std::isfinite(rolling_radius_m) || rolling_radius_m <= 0.0) {
    throw std::invalid_argument("SaeLongitudinalSlip: rolling radius must be finite and > 0");
  }
  const double wheel_speed = wheel_angular_speed_rad_s * rolling_radius_m;
  const double denominator = std::max(std::abs(wheel_speed), std::abs(longitudinal_speed_mps));
  if (denominator < kSlipDeadbandSpeedMps) return 0.0;
  return std::clamp((wheel_speed - longitudinal_speed_mps) / denominator, -1.0, 1.0);
}

JanosiHanamotoCurve::JanosiHanamotoCurve(double traction_coefficient_max, double shear_slip_constant)
    : mu_max_(traction_coefficient_max), b_(shear_slip_constant) {
  if (!std::isfinite(mu_max_) || mu_max_ <= 0.0) {
    throw std::invalid_argument("JanosiHanamotoCurve: traction_coefficient_max must be finite and > 0");
  }
  if (!std::isfinite(b_) || b_ <= 0.0) {
    throw std::invalid_argument("JanosiHanamotoCurve: shear_slip_constant must be finite and > 0");
  }
}

JanosiHanamotoCurve::JanosiHanamotoCurve(const TerrainSlipParams& terrain)
    : JanosiHanamotoCurve(terrain.traction_coefficient_max, terrain.shear_slip_constant) {}

double JanosiHanamotoCurve::UnboundedTractionCoefficient(double slip) const {
  RequireFinite(slip, "JanosiHanamotoCurve: slip");
  return std::copysign(mu_max_ * ShapeFunction(std::abs(slip) / b_), slip);
}

double JanosiHanamotoCurve::TractionCoefficient(double slip) const {
  if (!(std::abs(slip) <= 1.0)) throw std::invalid_argument("JanosiHanamotoCurve: slip must be in [-1, 1]");
  return UnboundedTractionCoefficient(slip);
}

double JanosiHanamotoCurve::Slope(double slip) const {
  if (!(std::abs(slip) <= 1.0)) throw std::invalid_argument("JanosiHanamotoCurve: slip must be in [-1, 1]");
  return mu_max_ / b_ * ShapeDerivative(std::abs(slip) / b_);
}

double JanosiHanamotoCurve::MaxTractionCoefficient() const { return UnboundedTractionCoefficient(1.0); }

SlipForTraction JanosiHanamotoCurve::SlipFor(double traction_coefficient_demand) const {
  if (std::isnan(traction_coefficient_demand)) {
    throw std::invalid_argument("JanosiHanamotoCurve::SlipFor: demand is NaN");
  }
  const double demand = std::abs(traction_coefficient_demand);
  const double sign = std::copysign(1.0, traction_coefficient_demand);
  if (demand == 0.0) return {0.0, SlipInverseStatus::kOk};
  if (demand > MaxTractionCoefficient()) return {sign, SlipInverseStatus::kWheelSpins};
  if (demand == MaxTractionCoefficient()) return {sign, SlipInverseStatus::kOk};
  const auto residual = [&](double s) { return mu_max_ * ShapeFunction(s / b_) - demand; };
  std::uintmax_t max_iterations = 200;
  const auto tolerance = [](double a, double b) { return std::abs(b - a) <= 1e-13; };
  const auto [low, high] = boost::math::tools::toms748_solve(residual, 0.0, 1.0, -demand,
                                                             MaxTractionCoefficient() - demand,
                                                             tolerance, max_iterations);
  return {sign * 0.5 * (low + high), SlipInverseStatus::kOk};
}

std::optional<std::string> WheelDynamicsParamsProblem(const WheelDynamicsParams& params) {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!positive(params.mass_share_kg)) return "mass_share_kg must be finite and > 0";
  if (!positive(params.wheel_inertia_kg_m2)) return "wheel_inertia_kg_m2 must be finite and > 0";
  if (!positive(params.nominal_radius_m)) return "nominal_radius_m must be finite and > 0";
  if (!positive(params.gravity_mps2)) return "gravity_mps2 must be finite and > 0";
  if (!positive(params.internal_step_s)) return "internal_step_s must be finite and > 0";
  return std::nullopt;
}

namespace {
WheelDynamicsParams Checked(const WheelDynamicsParams& wheel, const TerrainSlipParams& terrain) {
  if (const auto problem = WheelDynamicsParamsProblem(wheel)) {
    throw std::invalid_argument("LongitudinalWheelDynamics: " + *problem);
  }
  if (const auto problem = TerrainSlipParamsProblem(terrain)) {
    throw std::invalid_argument("LongitudinalWheelDynamics: terrain " + *problem);
  }
  return wheel;
}
}  // namespace

LongitudinalWheelDynamics::LongitudinalWheelDynamics(const WheelDynamicsParams& wheel,
                                                     const TerrainSlipParams& terrain)
    : wheel_(Checked(wheel, terrain)),
      terrain_(terrain),
      curve_(terrain),
      rolling_radius_m_(wheel.nominal_radius_m * terrain.rolling_radius_factor),
      normal_load_n_(wheel.mass_share_kg * wheel.gravity_mps2) {}

double LongitudinalWheelDynamics::SteadyStateSlip() const {
  return curve_.SlipFor(terrain_.rolling_resistance_coefficient).slip;
}

WheelState LongitudinalWheelDynamics::InternalStep(const WheelState& x, double torque_nm, double h) const {
  const double r = rolling_radius_m_;
  const double n = normal_load_n_;
  const SlipWithGradient s = RegularizedSlip(x.wheel_angular_speed_rad_s, r, x.vehicle_speed_mps);
  const double force = curve_.TractionCoefficient(s.slip) * n;
  const double d_force_d_slip = curve_.Slope(s.slip) * n;
  const double speed_floor = std::max(std::abs(x.vehicle_speed_mps), kSlipDeadbandSpeedMps);
  const double resistance = rolling_resistance_n() * x.vehicle_speed_mps / speed_floor;
  const double d_resistance_d_speed =
      std::abs(x.vehicle_speed_mps) < kSlipDeadbandSpeedMps ? rolling_resistance_n() / speed_floor : 0.0;

  const double inertia = wheel_.wheel_inertia_kg_m2;
  const double mass = wheel_.mass_share_kg;
  const Eigen::Vector2d rate((torque_nm - r * force) / inertia, (force - resistance) / mass);
  Eigen::Matrix2d jacobian;
  jacobian << -r * d_force_d_slip * s.d_slip_d_omega / inertia, -r * d_force_d_slip * s.d_slip_d_speed / inertia,
      d_force_d_slip * s.d_slip_d_omega / mass, (d_force_d_slip * s.d_slip_d_speed - d_resistance_d_speed) / mass;
  const Eigen::Vector2d delta = (Eigen::Matrix2d::Identity() - h * jacobian).partialPivLu().solve(h * rate);
  return {x.wheel_angular_speed_rad_s + delta.x(), x.vehicle_speed_mps + delta.y()};
}

WheelStepResult LongitudinalWheelDynamics::Step(const WheelState& state, double torque_nm, double dt_s) const {
  RequireFinite(state.wheel_angular_speed_rad_s, "LongitudinalWheelDynamics::Step: wheel angular speed");
  RequireFinite(state.vehicle_speed_mps, "LongitudinalWheelDynamics::Step: vehicle speed");
  RequireFinite(torque_nm, "LongitudinalWheelDynamics::Step: torque");
  if (!std::isfinite(dt_s) || dt_s <= 0.0) {
    throw std::invalid_argument("LongitudinalWheelDynamics::Step: dt_s must be finite and > 0");
  }
  const double count = std::ceil(dt_s / wheel_.internal_step_s);
  if (count > 1e9) throw std::invalid_argument("LongitudinalWheelDynamics::Step: dt_s too long for one call");
  const auto steps = static_cast<std::int64_t>(count);
  const double h = dt_s / static_cast<double>(steps);
  WheelState x = state;
  for (std::int64_t i = 0; i < steps; ++i) x = InternalStep(x, torque_nm, h);

  const SlipWithGradient s = RegularizedSlip(x.wheel_angular_speed_rad_s, rolling_radius_m_, x.vehicle_speed_mps);
  return {.state = x,
          .slip = SaeLongitudinalSlip(x.wheel_angular_speed_rad_s, rolling_radius_m_, x.vehicle_speed_mps),
          .traction_force_n = curve_.TractionCoefficient(s.slip) * normal_load_n_,
          .rolling_radius_m = rolling_radius_m_};
}

}  // namespace rowloc::sim
