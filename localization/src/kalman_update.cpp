#include "rowloc/localization/kalman_update.hpp"

#include <Eigen/Cholesky>

#include <boost/math/distributions/chi_squared.hpp>

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rowloc::localization {

double WrapAngle(double angle_rad) {
  double wrapped = std::remainder(angle_rad, 2.0 * std::numbers::pi);  // in [-pi, pi]
  if (wrapped <= -std::numbers::pi) wrapped += 2.0 * std::numbers::pi;
  return wrapped;
}

double ChiSquareGate(int dof, double probability) {
  if (dof < 1) throw std::invalid_argument("chi-square gate: dof must be >= 1");
  if (!(probability > 0.0 && probability < 1.0)) {
    throw std::invalid_argument("chi-square gate: probability must be in (0, 1)");
  }
  return boost::math::quantile(boost::math::chi_squared(dof), probability);
}

UpdateOutcome KalmanUpdate(Eigen::VectorXd& state, Eigen::MatrixXd& covariance,
                           const Eigen::VectorXd& innovation, const Eigen::MatrixXd& jacobian,
                           const Eigen::MatrixXd& noise, double gate_threshold, int angle_index) {
  const Eigen::Index n = state.size();
  const Eigen::Index m = innovation.size();
  if (covariance.rows() != n || covariance.cols() != n || jacobian.rows() != m || jacobian.cols() != n ||
      noise.rows() != m || noise.cols() != m || m == 0) {
    throw std::invalid_argument("Kalman update: mismatched sizes (state " + std::to_string(n) +
                                ", innovation " + std::to_string(m) + ")");
  }
  if (!innovation.allFinite() || !jacobian.allFinite() || !noise.allFinite()) {
    throw std::invalid_argument("Kalman update: non-finite innovation, Jacobian or noise");
  }
  UpdateOutcome outcome;
  outcome.innovation = innovation;
  const Eigen::MatrixXd hp = jacobian * covariance;  // H P (m x n)
  outcome.innovation_covariance = hp * jacobian.transpose() + noise;
  outcome.innovation_covariance = 0.5 * (outcome.innovation_covariance + outcome.innovation_covariance.transpose());
  const Eigen::LLT<Eigen::MatrixXd> s_factor(outcome.innovation_covariance);
  if (s_factor.info() != Eigen::Success) {
    outcome.nis = std::numeric_limits<double>::infinity();
    return outcome;  // S not positive definite (R must be): never apply such an update
  }
  outcome.nis = innovation.dot(s_factor.solve(innovation));
  if (!(outcome.nis <= gate_threshold)) return outcome;
  // K = P H^T S^-1 = (S^-1 H P)^T since P and S are symmetric.
  const Eigen::MatrixXd gain = s_factor.solve(hp).transpose();  // n x m
  state.noalias() += gain * innovation;
  if (angle_index >= 0) state(angle_index) = WrapAngle(state(angle_index));
  Eigen::MatrixXd joseph = covariance;
  joseph.noalias() -= gain * hp;                                 // A = (I - K H) P
  const Eigen::MatrixXd a_ht = joseph * jacobian.transpose();   // A H^T (n x m)
  joseph.noalias() -= a_ht * gain.transpose();                  // A (I - K H)^T
  joseph.noalias() += gain * noise * gain.transpose();
  covariance = 0.5 * (joseph + joseph.transpose());
  outcome.accepted = true;
  return outcome;
}

}  // namespace rowloc::localization
