#include "rowloc/localization/kalman_update.hpp"

#include "column_kernels.hpp"

#include <Eigen/Cholesky>

#include <boost/math/distributions/chi_squared.hpp>

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rowloc::localization {

double WrapAngle(double angle_rad) {
  if (angle_rad > -std::numbers::pi && angle_rad <= std::numbers::pi) return angle_rad;  // the usual case
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

/// target += M h_row^T for a square M (n x n) and row `row` of a sparse H: the columns of M at the
/// non-zero entries of that row, up to kMaxCombinedColumns of them in one pass over target.
ROWLOC_VECTOR_CLONES
void AddSparseColumn(const Eigen::MatrixXd& m, const MatrixRef& h, Eigen::Index row, double* target) {
  const double* sources[detail::kMaxCombinedColumns];
  double scales[detail::kMaxCombinedColumns];
  int count = 0;
  for (Eigen::Index j = 0; j < h.cols(); ++j) {
    const double factor = h(row, j);
    if (factor == 0.0) continue;
    sources[count] = m.col(j).data();
    scales[count] = factor;
    if (++count == detail::kMaxCombinedColumns) {
      detail::CombineColumns<true>(sources, scales, count, m.rows(), target);
      count = 0;
    }
  }
  if (count > 0) detail::CombineColumns<true>(sources, scales, count, m.rows(), target);
}

/// M H^T (n x m): column i is M h_i^T.
template <typename Tall>
Tall TimesTransposed(const Eigen::MatrixXd& m, const MatrixRef& h) {
  Tall out = Tall::Zero(m.rows(), h.rows());
  for (Eigen::Index i = 0; i < h.rows(); ++i) AddSparseColumn(m, h, i, out.col(i).data());
  return out;
}

/// The strictly lower triangle of p set from the upper one: p exactly symmetric.
void MirrorUpperTriangle(Eigen::MatrixXd& p) {
  const Eigen::Index n = p.rows();
  for (Eigen::Index col = 0; col < n; ++col) {
    double* target = p.col(col).data();
    for (Eigen::Index row = col + 1; row < n; ++row) target[row] = p(col, row);
  }
}

/// p <- p - u v^T on the upper triangle (row <= col), then the lower triangle mirrored from it:
/// for a symmetric result, exactly symmetric, at half the cost.
template <typename Wide>
void SubtractUpperRankUpdate(Eigen::MatrixXd& p, const Wide& u, const Wide& v) {
  const Eigen::Index n = p.rows();
  for (Eigen::Index col = 0; col < n; ++col) {
    double* target = p.col(col).data();
    for (Eigen::Index k = 0; k < u.cols(); ++k) {
      const double factor = v(col, k);
      const double* source = u.col(k).data();
      for (Eigen::Index r = 0; r <= col; ++r) target[r] -= factor * source[r];
    }
  }
  MirrorUpperTriangle(p);
}

/// The joint statistics of an m-dimensional update: U = P H^T (n x m), S = H P H^T + R (made
/// exactly symmetric) and its Cholesky factor.
template <typename Tall, typename Square>
struct JointStatistics {
  Tall pht;
  Square s;
  Eigen::LLT<Square> s_factor;
};

/// Computes `joint` and writes the innovation, S and the NIS y^T S^-1 y to outcome. False when the
/// update must not be applied: S not positive definite (R must be; NIS = +inf) or the NIS above the
/// gate. Small matrices (n <= ~25, m <= 8) and a sparse H: P H^T is m column operations on
/// contiguous columns of the column-major P, O(nnz(H) n), without Eigen's GEMM packing
/// (docs/benchmarks.md, "Vehicle EKF").
template <typename Tall, typename Square>
bool GateJointly(const Eigen::MatrixXd& covariance, const VectorRef& innovation, const MatrixRef& jacobian,
                 const MatrixRef& noise, double gate_threshold, JointStatistics<Tall, Square>& joint,
                 UpdateOutcome& outcome) {
  outcome.innovation = innovation;
  joint.pht = TimesTransposed<Tall>(covariance, jacobian);
  joint.s = noise;
  joint.s.noalias() += jacobian.lazyProduct(joint.pht);  // m x m, tiny
  joint.s = (0.5 * (joint.s + joint.s.transpose())).eval();
  outcome.innovation_covariance = joint.s;
  joint.s_factor.compute(joint.s);
  if (joint.s_factor.info() != Eigen::Success) {
    outcome.nis = std::numeric_limits<double>::infinity();
    return false;  // S not positive definite: never apply such an update
  }
  outcome.nis = innovation.dot(joint.s_factor.solve(innovation));
  return outcome.nis <= gate_threshold;
}

/// The update with temporaries of type Tall (n x m), Wide (n x 2m) and Square (m x m): bounded
/// fixed-capacity (stack) matrices for the usual sizes, dynamic ones beyond them.
template <typename Tall, typename Wide, typename Square>
UpdateOutcome UpdateWith(Eigen::VectorXd& state, Eigen::MatrixXd& covariance, const VectorRef& innovation,
                         const MatrixRef& jacobian, const MatrixRef& noise, double gate_threshold,
                         int angle_index) {
  const Eigen::Index n = state.size();
  const Eigen::Index m = innovation.size();
  UpdateOutcome outcome;
  JointStatistics<Tall, Square> joint;
  if (!GateJointly(covariance, innovation, jacobian, noise, gate_threshold, joint, outcome)) return outcome;
  const Tall& pht = joint.pht;
  // K = P H^T S^-1, solved as (S^-1 (P H^T)^T)^T (S symmetric). The products below are rank-m
  // column operations (O(m n^2), upper triangle only).
  const Tall gain = joint.s_factor.solve(pht.transpose()).transpose();  // n x m
  state.noalias() += gain.lazyProduct(innovation);
  if (angle_index >= 0) state(angle_index) = WrapAngle(state(angle_index));
  // Joseph form in one pass: with U = P H^T and A = P - K U^T, A H^T = U - K (S - R), so
  //   (I - K H) P (I - K H)^T + K R K^T = A - (A H^T) K^T + K R K^T
  //                                     = P - K U^T - (U - K S) K^T = P - [K, U - K S] [U, K]^T
  // for any gain K (the Joseph form's property; with the exact K = U S^-1 the second block vanishes
  // and only its round-off remains). A rank-2m update of which only the upper triangle is computed.
  const Eigen::Index m2 = 2 * m;
  Wide left(n, m2), right(n, m2);
  left.leftCols(m) = gain;
  left.rightCols(m) = pht - gain.lazyProduct(joint.s);
  right.leftCols(m) = pht;
  right.rightCols(m) = gain;
  SubtractUpperRankUpdate(covariance, left, right);
  outcome.accepted = true;
  return outcome;
}

/// u = P h^T for row `row` of the sparse H.
template <typename Vector>
Vector SparseColumn(const Eigen::MatrixXd& covariance, const MatrixRef& jacobian, Eigen::Index row) {
  Vector u = Vector::Zero(covariance.rows());
  AddSparseColumn(covariance, jacobian, row, u.data());
  return u;
}

/// P <- P - g g^T - (k w^T + w k^T) on every entry of the n x n column-major p. Entry (r, c) is
/// g_r g_c + (k_r w_c + w_r k_c), the same products and addends as entry (c, r) in commuted order,
/// and IEEE products and sums commute: a symmetric P stays exactly symmetric without a mirroring
/// pass (its strided stores cost as much as the update). That needs every product rounded on its
/// own: no FMA contraction (cmake/RowlocOptions.cmake). Contiguous columns: the loop vectorizes.
ROWLOC_VECTOR_CLONES
void SubtractSymmetricRankThree(double* __restrict__ p, const double* __restrict__ g, const double* __restrict__ k,
                                const double* __restrict__ w, Eigen::Index n) {
  for (Eigen::Index c = 0; c < n; ++c) {
    const double gc = g[c], kc = k[c], wc = w[c];
    double* __restrict__ column = p + c * n;
    for (Eigen::Index r = 0; r < n; ++r) column[r] -= g[r] * gc + (k[r] * wc + w[r] * kc);
  }
}

/// One scalar correction with u = P h^T and s = h u + r > 0: k = u / s, x <- x + k y and the Joseph
/// form P - k u^T - w k^T with w = u - k s (zero up to round-off), which is the symmetric
/// P - s k k^T - (k w^T + w k^T) = P - g g^T - (k w^T + w k^T) with g = sqrt(s) k. P must be
/// symmetric (KalmanUpdate's precondition); it stays exactly symmetric.
template <typename Vector>
void ApplyScalarCorrection(Eigen::VectorXd& state, Eigen::MatrixXd& covariance, const Vector& u, double s, double y) {
  const Vector gain = u * (1.0 / s);  // one division, not n (any gain is fine: the Joseph form)
  state.noalias() += y * gain;
  const Vector w = u - s * gain;
  const Vector root = std::sqrt(s) * gain;
  SubtractSymmetricRankThree(covariance.data(), root.data(), gain.data(), w.data(), state.size());
}

/// The update of one scalar measurement (m = 1): S, the NIS and the gain are scalars, so there is
/// nothing to factorize. Vector: an n-vector type.
template <typename Vector>
UpdateOutcome ScalarUpdateWith(Eigen::VectorXd& state, Eigen::MatrixXd& covariance, const VectorRef& innovation,
                               const MatrixRef& jacobian, double noise, double gate_threshold, int angle_index) {
  UpdateOutcome outcome;
  outcome.innovation = innovation;
  const Vector u = SparseColumn<Vector>(covariance, jacobian, 0);
  const double s = jacobian.row(0).dot(u) + noise;
  outcome.innovation_covariance = Eigen::MatrixXd::Constant(1, 1, s);
  if (!(s > 0.0)) {
    outcome.nis = std::numeric_limits<double>::infinity();
    return outcome;  // S not positive: never apply such an update
  }
  const double y = innovation(0);
  outcome.nis = y * y / s;
  if (!(outcome.nis <= gate_threshold)) return outcome;
  ApplyScalarCorrection(state, covariance, u, s, y);
  if (angle_index >= 0) state(angle_index) = WrapAngle(state(angle_index));
  outcome.accepted = true;
  return outcome;
}

/// The update of m > 1 measurements with a diagonal R (every R_ii > 0): gated on the joint NIS
/// (S = H P H^T + R, m x m, Cholesky), then applied as m sequential scalar corrections at the same
/// linearization point, the i-th with the innovation y_i - h_i (x - x_0) left after the first i - 1.
/// For a linearized measurement with independent components this equals the joint update
/// (sequential Kalman filtering: Simon, Optimal State Estimation, 2006, §6.1) and costs m scalar
/// O(n^2) updates, with no m x m solves and no rank-2m temporaries. Tall: n x m; Square: m x m;
/// Vector: n.
template <typename Tall, typename Square, typename Vector>
UpdateOutcome SequentialUpdateWith(Eigen::VectorXd& state, Eigen::MatrixXd& covariance,
                                   const VectorRef& innovation, const MatrixRef& jacobian,
                                   const MatrixRef& noise, double gate_threshold, int angle_index) {
  UpdateOutcome outcome;
  JointStatistics<Tall, Square> joint;
  if (!GateJointly(covariance, innovation, jacobian, noise, gate_threshold, joint, outcome)) return outcome;
  const Tall& pht = joint.pht;
  const Vector start = state;  // the linearization point (not wrapped between the corrections)
  for (Eigen::Index i = 0; i < innovation.size(); ++i) {
    const Vector u = i == 0 ? Vector(pht.col(0)) : SparseColumn<Vector>(covariance, jacobian, i);
    const double s_i = jacobian.row(i).dot(u) + noise(i, i);  // >= R_ii > 0
    const double y_i = innovation(i) - jacobian.row(i).dot(state - start);
    ApplyScalarCorrection(state, covariance, u, s_i, y_i);
  }
  if (angle_index >= 0) state(angle_index) = WrapAngle(state(angle_index));
  outcome.accepted = true;
  return outcome;
}

/// R diagonal with a positive diagonal: its components are independent measurements.
bool IsPositiveDiagonal(const MatrixRef& noise) {
  for (Eigen::Index c = 0; c < noise.cols(); ++c) {
    for (Eigen::Index r = 0; r < noise.rows(); ++r) {
      if (r == c ? !(noise(r, c) > 0.0) : noise(r, c) != 0.0) return false;
    }
  }
  return true;
}

/// Largest state and measurement sizes served by stack temporaries (all shipped vehicles: n <= 23).
constexpr int kStackStates = 32;
constexpr int kStackMeasurements = 8;

}  // namespace

UpdateOutcome KalmanUpdate(Eigen::VectorXd& state, Eigen::MatrixXd& covariance,
                           const VectorRef& innovation, const MatrixRef& jacobian,
                           const MatrixRef& noise, double gate_threshold, int angle_index) {
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
  if (m == 1) {
    if (n <= kStackStates) {
      return ScalarUpdateWith<Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kStackStates, 1>>(
          state, covariance, innovation, jacobian, noise(0, 0), gate_threshold, angle_index);
    }
    return ScalarUpdateWith<Eigen::VectorXd>(state, covariance, innovation, jacobian, noise(0, 0), gate_threshold,
                                             angle_index);
  }
  if (n <= kStackStates && m <= kStackMeasurements && IsPositiveDiagonal(noise)) {
    using Tall = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kStackStates, kStackMeasurements>;
    using Square = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kStackMeasurements, kStackMeasurements>;
    using Vector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kStackStates, 1>;
    return SequentialUpdateWith<Tall, Square, Vector>(state, covariance, innovation, jacobian, noise, gate_threshold,
                                                      angle_index);
  }
  if (n <= kStackStates && m <= kStackMeasurements) {
    using Tall = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kStackStates, kStackMeasurements>;
    using Wide = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kStackStates, 2 * kStackMeasurements>;
    using Square = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kStackMeasurements, kStackMeasurements>;
    return UpdateWith<Tall, Wide, Square>(state, covariance, innovation, jacobian, noise, gate_threshold, angle_index);
  }
  return UpdateWith<Eigen::MatrixXd, Eigen::MatrixXd, Eigen::MatrixXd>(state, covariance, innovation, jacobian, noise,
                                                                       gate_threshold, angle_index);
}

}  // namespace rowloc::localization
