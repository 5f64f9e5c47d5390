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

namespace {

/// M H^T for a square M (n x n) and a sparse H (m x n): column i is sum_j H(i, j) M.col(j).
/// Plain loops on contiguous columns (column-major storage): for these sizes Eigen's expression
/// set-up per column costs more than the arithmetic, and the compiler vectorizes the inner loops.
Eigen::MatrixXd TimesTransposed(const Eigen::MatrixXd& m, const Eigen::MatrixXd& h) {
  const Eigen::Index n = m.rows();
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(n, h.rows());
  for (Eigen::Index i = 0; i < h.rows(); ++i) {
    double* target = out.col(i).data();
    for (Eigen::Index j = 0; j < h.cols(); ++j) {
      const double factor = h(i, j);
      if (factor == 0.0) continue;
      const double* source = m.col(j).data();
      for (Eigen::Index r = 0; r < n; ++r) target[r] += factor * source[r];
    }
  }
  return out;
}

/// p <- p - u v^T on the upper triangle (row <= col), then the lower triangle mirrored from it:
/// for a symmetric result, exactly symmetric, at half the cost.
void SubtractUpperRankUpdate(Eigen::MatrixXd& p, const Eigen::MatrixXd& u, const Eigen::MatrixXd& v) {
  const Eigen::Index n = p.rows();
  for (Eigen::Index col = 0; col < n; ++col) {
    double* target = p.col(col).data();
    for (Eigen::Index k = 0; k < u.cols(); ++k) {
      const double factor = v(col, k);
      const double* source = u.col(k).data();
      for (Eigen::Index r = 0; r <= col; ++r) target[r] -= factor * source[r];
    }
  }
  for (Eigen::Index col = 0; col < n; ++col) {
    for (Eigen::Index row = col + 1; row < n; ++row) p(row, col) = p(col, row);
  }
}

}  // namespace

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
  if (angle_index >= n) throw std::invalid_argument("Kalman update: angle_index outside the state");
  if (!innovation.allFinite() || !jacobian.allFinite() || !noise.allFinite()) {
    throw std::invalid_argument("Kalman update: non-finite innovation, Jacobian or noise");
  }
  UpdateOutcome outcome;
  outcome.innovation = innovation;
  // Small matrices (n <= ~25, m <= 4) and a sparse H: every product below is written as m column
  // operations (axpy / rank-1 updates on contiguous columns of the column-major P) so that it costs
  // O(nnz(H) n + m n^2) without Eigen's GEMM packing (docs/benchmarks.md, "Vehicle EKF").
  const Eigen::MatrixXd pht = TimesTransposed(covariance, jacobian);  // P H^T (n x m)
  outcome.innovation_covariance = noise;
  outcome.innovation_covariance.noalias() += jacobian * pht;          // m x m, tiny
  outcome.innovation_covariance = 0.5 * (outcome.innovation_covariance + outcome.innovation_covariance.transpose());
  const Eigen::LLT<Eigen::MatrixXd> s_factor(outcome.innovation_covariance);
  if (s_factor.info() != Eigen::Success) {
    outcome.nis = std::numeric_limits<double>::infinity();
    return outcome;  // S not positive definite (R must be): never apply such an update
  }
  outcome.nis = innovation.dot(s_factor.solve(innovation));
  if (!(outcome.nis <= gate_threshold)) return outcome;
  // K = P H^T S^-1, solved as (S^-1 (P H^T)^T)^T (S symmetric).
  const Eigen::MatrixXd gain = s_factor.solve(pht.transpose()).transpose();  // n x m
  state += gain * innovation;
  if (angle_index >= 0) state(angle_index) = WrapAngle(state(angle_index));
  // Joseph form in one pass: with U = P H^T and A = P - K U^T, A H^T = U - K (S - R), so
  //   (I - K H) P (I - K H)^T + K R K^T = A - (A H^T) K^T + K R K^T
  //                                     = P - K U^T - (U - K S) K^T = P - [K, U - K S] [U, K]^T
  // for any gain K (the Joseph form's property; with the exact K = U S^-1 the second block vanishes
  // and only its round-off remains). A rank-2m update of which only the upper triangle is computed.
  const Eigen::Index m2 = 2 * m;
  Eigen::MatrixXd left(n, m2), right(n, m2);
  left.leftCols(m) = gain;
  left.rightCols(m) = pht - gain * outcome.innovation_covariance;
  right.leftCols(m) = pht;
  right.rightCols(m) = gain;
  SubtractUpperRankUpdate(covariance, left, right);
  outcome.accepted = true;
  return outcome;
}

}  // namespace rowloc::localization
