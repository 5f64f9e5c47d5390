// Longitudinal wheel slip: SAE slip, the Janosi-Hanamoto traction curve and its inverse, and a
// single-wheel / point-mass longitudinal dynamics step that produces slip from wheel torque
// (issue 3, "Longitudinal slip from wheel torque through the Janosi-Hanamoto curve").
//
// SAE slip (Danzi 2026 ch. 7):
//   s = (omega r - v) / max(|omega r|, |v|),  0 when both |omega r| and |v| are below 0.05 m/s,
//   saturated to [-1, 1] (omega r and v of opposite signs would give |s| up to 2).
//
// Janosi-Hanamoto curve (Lindgren et al. 2002 eq. (21)), in normalized form mu(s) = T(s) / (N r_roll):
//   mu(s) = mu_max [1 - (B/s)(1 - exp(-s/B))]  for s > 0,  mu(-s) = -mu(s) (braking), mu(0) = 0.
// mu is strictly increasing, mu'(0) = mu_max / (2B) (Lindgren et al. 2002 eq. (23): k_s = T_max / (2B)) and
// mu -> mu_max as s -> infinity; on the physical range |s| <= 1 its largest value is mu(1).
//
// Dynamics of one wheel carrying the mass share m (normal load N = m g) on flat ground:
//   I domega/dt = T - r_roll F,   m dv/dt = F - R(v),
//   F = mu(s_reg) N,  R(v) = c_rr N v / max(|v|, 0.05 m/s)  (rolling resistance, smooth at rest),
// where s_reg is the SAE slip with the denominator max(|omega r|, |v|, 0.05 m/s) instead of the
// deadband: it equals the SAE slip whenever either speed is >= 0.05 m/s and stays continuous at
// standstill (the deadband is a property of the estimator, not of the physics). The step is the
// linearly implicit ("semi-implicit") Euler method (Press et al., Numerical Recipes, §16.6):
//   x_{k+1} = x_k + h (1 - h J(x_k))^{-1} f(x_k),  x = (omega, v),
// with the analytic Jacobian J; it is stable for the stiff slip mode (time constant ~ I v /
// (r^2 dF/ds), milliseconds on tiles) and its fixed point is exactly f(x) = 0, so the steady slip
// solves mu(s*) = c_rr independently of the step size (docs/simulation-slip.md).
#pragma once

#include "rowloc/sim/terrain.hpp"

namespace rowloc::sim {

/// Speed under which SAE slip is defined as 0 (Danzi 2026 ch. 7: 0.05 m/s).
inline constexpr double kSlipDeadbandSpeedMps = 0.05;

/// SAE longitudinal slip in [-1, 1]. rolling_radius_m > 0. Throws std::invalid_argument on a
/// non-finite input or a non-positive radius.
double SaeLongitudinalSlip(double wheel_angular_speed_rad_s, double rolling_radius_m,
                           double longitudinal_speed_mps);

/// Outcome of inverting the traction curve.
enum class SlipInverseStatus {
  kOk,           ///< the demand is met at the returned slip
  kWheelSpins,   ///< the demand exceeds mu(1): the wheel spins (slip = +1) or locks (slip = -1)
};

struct SlipForTraction {
  double slip = 0.0;
  SlipInverseStatus status = SlipInverseStatus::kOk;
};

/// The normalized Janosi-Hanamoto curve mu(s) of one terrain.
class JanosiHanamotoCurve {
 public:
  /// mu_max > 0 and B > 0, finite; throws std::invalid_argument otherwise.
  JanosiHanamotoCurve(double traction_coefficient_max, double shear_slip_constant);
  explicit JanosiHanamotoCurve(const TerrainSlipParams& terrain);

  /// mu(s) for any finite s (odd extension; used to check the limit mu_max). Throws on NaN/inf.
  double UnboundedTractionCoefficient(double slip) const;
  /// mu(s) on the physical range s in [-1, 1]; throws std::invalid_argument outside it.
  double TractionCoefficient(double slip) const;
  /// dmu/ds on s in [-1, 1] (analytic; mu_max/(2B) at 0). Throws outside [-1, 1].
  double Slope(double slip) const;
  /// mu(1): the largest traction coefficient reachable with |s| <= 1.
  double MaxTractionCoefficient() const;

  /// The slip s in [-1, 1] with mu(s) = demand (bracketed TOMS 748 root find, |error| <= 1e-12),
  /// or status kWheelSpins with s = sign(demand) when |demand| > mu(1). Throws on a NaN demand.
  SlipForTraction SlipFor(double traction_coefficient_demand) const;

  double traction_coefficient_max() const { return mu_max_; }
  double shear_slip_constant() const { return b_; }

 private:
  double mu_max_;
  double b_;
};

/// Wheel, load and integration settings of one wheel (point-mass share of the vehicle).
struct WheelDynamicsParams {
  double mass_share_kg = 20.0;          ///< m > 0: vehicle mass carried by this wheel
  double wheel_inertia_kg_m2 = 0.05;    ///< I > 0: wheel + drive inertia about the axle
  double nominal_radius_m = 0.1;        ///< r_nominal > 0; r_roll = r_nominal * terrain factor
  double gravity_mps2 = 9.80665;        ///< g > 0
  double internal_step_s = 1e-4;        ///< h > 0: largest internal integration step
};

/// Why the parameters are unusable (naming the field), or nullopt.
std::optional<std::string> WheelDynamicsParamsProblem(const WheelDynamicsParams& params);

struct WheelState {
  double wheel_angular_speed_rad_s = 0.0;  ///< omega
  double vehicle_speed_mps = 0.0;          ///< v, longitudinal speed of the wheel centre
};

/// Exact ground truth after a step.
struct WheelStepResult {
  WheelState state;
  double slip = 0.0;                 ///< SAE slip of the final state (with the 0.05 m/s deadband)
  double traction_force_n = 0.0;     ///< F of the final state
  double rolling_radius_m = 0.0;     ///< r_roll on this terrain
};

class LongitudinalWheelDynamics {
 public:
  /// Throws std::invalid_argument on unusable parameters.
  LongitudinalWheelDynamics(const WheelDynamicsParams& wheel, const TerrainSlipParams& terrain);

  /// Integrates for dt_s > 0 (in ceil(dt/h) equal internal steps) with constant torque_nm.
  /// Throws std::invalid_argument on non-finite input or dt_s <= 0.
  WheelStepResult Step(const WheelState& state, double torque_nm, double dt_s) const;

  /// The slip held at any constant speed >= 0.05 m/s: mu(s*) = c_rr (analytic, from the inverse).
  double SteadyStateSlip() const;
  double rolling_radius_m() const { return rolling_radius_m_; }
  double normal_load_n() const { return normal_load_n_; }
  double rolling_resistance_n() const { return terrain_.rolling_resistance_coefficient * normal_load_n_; }

 private:
  WheelState InternalStep(const WheelState& x, double torque_nm, double h) const;

  WheelDynamicsParams wheel_;
  TerrainSlipParams terrain_;
  JanosiHanamotoCurve curve_;
  double rolling_radius_m_;
  double normal_load_n_;
};

}  // namespace rowloc::sim
