#include "rowloc/localization/track_slip_observer.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace rowloc::localization {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

std::string Format(double value) {
  std::ostringstream out;
  out.precision(12);
  out << value;
  return out.str();
}

/// Wraps to (-pi, pi].
double WrapAngle(double angle_rad) {
  const double wrapped = std::remainder(angle_rad, 2.0 * std::numbers::pi);
  return wrapped <= -std::numbers::pi ? wrapped + 2.0 * std::numbers::pi : wrapped;
}

/// sin(a)/a, with its series near 0.
double Sinc(double a) {
  if (std::abs(a) < 1e-4) return 1.0 - a * a / 6.0;
  return std::sin(a) / a;
}

/// exp(m) by scaling and squaring: Taylor series of degree 16 (Horner) on m / 2^s with
/// ||m / 2^s||_1 <= 1/2 (truncation below 1e-19 relative), then s squarings.
Matrix6d Exponential(const Matrix6d& m) {
  const double norm = m.cwiseAbs().colwise().sum().maxCoeff();
  const int squarings = norm > 0.5 ? static_cast<int>(std::ceil(std::log2(norm / 0.5))) : 0;
  const Matrix6d scaled = m / std::ldexp(1.0, squarings);
  Matrix6d result = Matrix6d::Identity();
  for (int k = 16; k >= 1; --k) result = Matrix6d::Identity() + scaled * result / static_cast<double>(k);
  for (int i = 0; i < squarings; ++i) result = result * result;
  return result;
}

/// Psi of eq. (5) averaged over an arc starting at heading theta0 and turning by `turn` at a
/// constant rate: cos and sin of the mid heading shrink by sinc(turn / 2); the theta row is constant.
Eigen::Matrix<double, 3, 2> MeanRegressor(double theta0_rad, double turn_rad, double v_right_mps,
                                          double v_left_mps, double track_width_m) {
  const double mid_heading = theta0_rad + 0.5 * turn_rad;
  const double shrink = Sinc(0.5 * turn_rad);
  const double mean_cos = std::cos(mid_heading) * shrink;
  const double mean_sin = std::sin(mid_heading) * shrink;
  Eigen::Matrix<double, 3, 2> psi;
  psi << 0.5 * mean_cos * v_right_mps, 0.5 * mean_cos * v_left_mps,  //
      0.5 * mean_sin * v_right_mps, 0.5 * mean_sin * v_left_mps,     //
      v_right_mps / track_width_m, -v_left_mps / track_width_m;
  return psi;
}

bool PositiveFinite(double value) { return std::isfinite(value) && value > 0.0; }

std::optional<std::string> GainsProblem(const Eigen::VectorXd& gains, const char* name) {
  for (Eigen::Index i = 0; i < gains.size(); ++i) {
    if (!PositiveFinite(gains[i])) {
      return std::string(name) + "[" + std::to_string(i) + "] must be finite and > 0 (got " +
             Format(gains[i]) + ")";
    }
  }
  return std::nullopt;
}

void RequireFinite(double value, const char* field) {
  if (!std::isfinite(value)) {
    throw std::invalid_argument(std::string("TrackSlipObserver::Update: ") + field +
                                " must be finite (got " + Format(value) + ")");
  }
}

void RequireSpeed(double value, const char* field) {
  RequireFinite(value, field);
  if (std::abs(value) > kMaxTrackSpeedMps) {
    throw std::invalid_argument(std::string("TrackSlipObserver::Update: ") + field + " " + Format(value) +
                                " is beyond +-" + Format(kMaxTrackSpeedMps) + " m/s");
  }
}

void RequireValid(const TrackSlipInput& input) {
  RequireFinite(input.time_s, "time_s");
  RequireFinite(input.x_m, "x_m");
  RequireFinite(input.y_m, "y_m");
  RequireFinite(input.theta_rad, "theta_rad");
  RequireSpeed(input.v_right_mps, "v_right_mps");
  RequireSpeed(input.v_left_mps, "v_left_mps");
}

}  // namespace

std::optional<std::string> TrackSlipObserverConfigProblem(const TrackSlipObserverConfig& config) {
  if (!PositiveFinite(config.track_width_m)) {
    return "track_width_m must be finite and > 0 (got " + Format(config.track_width_m) + ")";
  }
  if (auto problem = GainsProblem(config.injection_gains_per_s, "injection_gains_per_s")) return problem;
  if (auto problem = GainsProblem(config.adaptation_gains, "adaptation_gains")) return problem;
  if (!(config.eta_min >= 0.0 && config.eta_min < config.eta_max && config.eta_max <= 2.0)) {
    return "eta_min and eta_max must satisfy 0 <= eta_min < eta_max <= 2 (Tazzari et al. n.d., eq. (4)); got [" +
           Format(config.eta_min) + ", " + Format(config.eta_max) + "]";
  }
  for (const auto& [value, name] : {std::pair{config.initial_eta_right, "initial_eta_right"},
                                    std::pair{config.initial_eta_left, "initial_eta_left"}}) {
    if (!(value >= config.eta_min && value <= config.eta_max)) {
      return std::string(name) + " must be in [eta_min, eta_max] (got " + Format(value) + ")";
    }
  }
  if (config.max_step_s && !PositiveFinite(*config.max_step_s)) {
    return "max_step_s must be finite and > 0 when set (got " + Format(*config.max_step_s) + ")";
  }
  return std::nullopt;
}

TrackSlipObserver::TrackSlipObserver(const TrackSlipObserverConfig& config) : config_(config) {
  if (const auto problem = TrackSlipObserverConfigProblem(config_)) {
    throw std::invalid_argument("TrackSlipObserver: " + *problem);
  }
  eta_hat_ = {config_.initial_eta_right, config_.initial_eta_left};
}

TrackSlipStep TrackSlipObserver::Update(const TrackSlipInput& input) {
  RequireValid(input);
  if (!initialised_) {
    Initialise(input);
    return TrackSlipStep::kInitialised;
  }
  const double step_s = input.time_s - last_input_.time_s;
  if (step_s < 0.0) {
    throw std::invalid_argument("TrackSlipObserver::Update: time_s " + Format(input.time_s) +
                                " is before the previous time_s " + Format(last_input_.time_s));
  }
  if (step_s == 0.0) return TrackSlipStep::kSameTime;
  if (config_.max_step_s && step_s > *config_.max_step_s) {
    Initialise(input);
    return TrackSlipStep::kGapRestarted;
  }
  Integrate(input, step_s);
  return TrackSlipStep::kIntegrated;
}

void TrackSlipObserver::Reset() {
  initialised_ = false;
  pose_hat_.setZero();
  error_.setZero();
  eta_hat_ = {config_.initial_eta_right, config_.initial_eta_left};
}

std::optional<double> TrackSlipObserver::last_time_s() const {
  if (!initialised_) return std::nullopt;
  return last_input_.time_s;
}

double TrackSlipObserver::Lyapunov(double true_eta_right, double true_eta_left) const {
  const Eigen::Vector2d eta_error = eta_hat_ - Eigen::Vector2d(true_eta_right, true_eta_left);
  return 0.5 * (error_.squaredNorm() + eta_error.cwiseAbs2().cwiseQuotient(config_.adaptation_gains).sum());
}

void TrackSlipObserver::Initialise(const TrackSlipInput& input) {
  initialised_ = true;
  last_input_ = input;
  pose_hat_ = {input.x_m, input.y_m, WrapAngle(input.theta_rad)};
  error_.setZero();
}

// Heading change over the step: the 2 pi branch of the measured change nearest to the one
// predicted by eta^, moved into the range reachable with eta in the box when a branch lies in it.
double TrackSlipObserver::TurnOverStep(const TrackSlipInput& input, double step_s, double v_right,
                                       double v_left) const {
  const double scale = step_s / config_.track_width_m;
  const double predicted = scale * (eta_hat_.x() * v_right - eta_hat_.y() * v_left);
  const double centre = 0.5 * (config_.eta_max + config_.eta_min);
  const double half = 0.5 * (config_.eta_max - config_.eta_min);
  const double lowest = scale * (centre * (v_right - v_left) - half * (std::abs(v_right) + std::abs(v_left)));
  const double highest = scale * (centre * (v_right - v_left) + half * (std::abs(v_right) + std::abs(v_left)));
  constexpr double kTurn = 2.0 * std::numbers::pi;
  double turn = predicted + WrapAngle(input.theta_rad - last_input_.theta_rad - predicted);
  if (turn > highest && turn - kTurn >= lowest) turn -= kTurn;
  if (turn < lowest && turn + kTurn <= highest) turn += kTurn;
  return turn;
}

// One exact step of z = (e, eta^): z' = A z + b (header comment), via exp([A h, b h; 0, 0]).
void TrackSlipObserver::Integrate(const TrackSlipInput& input, double step_s) {
  const double v_right = 0.5 * (last_input_.v_right_mps + input.v_right_mps);
  const double v_left = 0.5 * (last_input_.v_left_mps + input.v_left_mps);
  const double turn = TurnOverStep(input, step_s, v_right, v_left);
  const Eigen::Matrix<double, 3, 2> psi =
      MeanRegressor(last_input_.theta_rad, turn, v_right, v_left, config_.track_width_m);
  Matrix6d m = Matrix6d::Zero();
  m.block<3, 3>(0, 0) = -step_s * config_.injection_gains_per_s.asDiagonal().toDenseMatrix();
  m.block<3, 2>(0, 3) = -step_s * psi;
  m.block<2, 3>(3, 0) = step_s * config_.adaptation_gains.asDiagonal() * psi.transpose();
  m.block<3, 1>(0, 5) = Eigen::Vector3d(input.x_m - last_input_.x_m, input.y_m - last_input_.y_m, turn);
  Vector6d z;
  z << error_, eta_hat_, 1.0;
  const Vector6d next = Exponential(m) * z;
  if (!next.allFinite()) {
    throw std::invalid_argument("TrackSlipObserver::Update: the step from time_s " +
                                Format(last_input_.time_s) + " to " + Format(input.time_s) +
                                " overflowed (time_s, position or speed values out of range)");
  }
  error_ = {next[0], next[1], WrapAngle(next[2])};
  eta_hat_ = next.segment<2>(3).cwiseMax(config_.eta_min).cwiseMin(config_.eta_max);
  pose_hat_ = {input.x_m - error_.x(), input.y_m - error_.y(), WrapAngle(input.theta_rad - error_.z())};
  last_input_ = input;
}

}  // namespace rowloc::localization
