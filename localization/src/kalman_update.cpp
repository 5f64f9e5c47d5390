#include "rowloc/localization/kalman_update.hpp"

#include "column_kernels.hpp"

#include <Eigen/Cholesky>

#include <boost/container/small_vector.hpp>
#include <boost/math/distributions/chi_squared.hpp>

#include <algorithm>
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

/// Largest state and measurement sizes served by stack temporaries (all shipped vehicles: n <= 23).
constexpr int kStackStates = 32;
constexpr int kStackMeasurements = 8;

/// The non-zero entries of each row of a Jacobian H (m x n), row by row: the measurement models'
/// H has a few non-zeros per row (3-8 of 10-30 states), so its products take O(nnz) each.
class SparseRows {
 public:
  explicit SparseRows(const MatrixRef& h)
      : start_(Slot(h.rows() + 1), boost::container::default_init),
        column_(Slot(h.size()), boost::container::default_init),
        value_(Slot(h.size()), boost::container::default_init) {
    Eigen::Index count = 0;
    for (Eigen::Index i = 0; i < h.rows(); ++i) {
      start_[Slot(i)] = count;
      const double* entry = h.data() + i;  // h(i, j) = entry[j * stride]
      for (Eigen::Index j = 0; j < h.cols(); ++j, entry += h.outerStride()) {
        if (*entry == 0.0) continue;
        column_[Slot(count)] = j;
        value_[Slot(count++)] = *entry;
      }
    }
    start_[Slot(h.rows())] = count;
  }
  /// h_i . v for a vector v of the state's size.
  double Dot(Eigen::Index i, const double* v) const {
    double sum = 0.0;
    for (Eigen::Index e = Begin(i); e < End(i); ++e) sum += value_[Slot(e)] * v[column_[Slot(e)]];
    return sum;
  }
  /// target = M h_i^T for a square column-major M (n x n): the columns of M at the non-zeros of
  /// row i, up to kMaxCombinedColumns of them per pass over target (column_kernels.hpp).
  void TimesTransposed(const Eigen::MatrixXd& m, Eigen::Index i, double* target) const {
    std::fill(target, target + m.rows(), 0.0);
    AddColumns(m, Begin(i), End(i), target);
  }

 private:
  static std::size_t Slot(Eigen::Index e) { return static_cast<std::size_t>(e); }
  Eigen::Index Begin(Eigen::Index i) const { return start_[Slot(i)]; }
  Eigen::Index End(Eigen::Index i) const { return start_[Slot(i) + 1]; }
  ROWLOC_VECTOR_CLONES
  void AddColumns(const Eigen::MatrixXd& m, Eigen::Index begin, Eigen::Index end, double* target) const;

  // Sized once (m x n entries at most): up to the stack sizes of KalmanUpdate nothing is allocated.
  boost::container::small_vector<Eigen::Index, kStackMeasurements + 1> start_;  ///< row i: [start_i, start_i+1)
  boost::container::small_vector<Eigen::Index, kStackStates * kStackMeasurements> column_;
  boost::container::small_vector<double, kStackStates * kStackMeasurements> value_;
};

void SparseRows::AddColumns(const Eigen::MatrixXd& m, Eigen::Index begin, Eigen::Index end, double* target) const {
  const double* sources[detail::kMaxCombinedColumns];
  for (Eigen::Index first = begin; first < end; first += detail::kMaxCombinedColumns) {
    const int count = static_cast<int>(std::min<Eigen::Index>(end - first, detail::kMaxCombinedColumns));
    for (int e = 0; e < count; ++e) sources[e] = m.col(column_[Slot(first + e)]).data();
    detail::CombineColumns<true>(sources, value_.data() + first, count, m.rows(), target);
  }
}

/// M H^T (n x m): column i is M h_i^T.
template <typename Tall>
Tall TimesTransposed(const Eigen::MatrixXd& m, const SparseRows& h, Eigen::Index rows) {
  Tall out(m.rows(), rows);
  for (Eigen::Index i = 0; i < rows; ++i) h.TimesTransposed(m, i, out.col(i).data());
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
/// (docs/notes/2026-12-benchmarks-history.md, "Vehicle EKF (issue 4)").
template <typename Tall, typename Square>
bool GateJointly(const Eigen::MatrixXd& covariance, const VectorRef& innovation, const MatrixRef& jacobian,
                 const MatrixRef& noise, double gate_threshold, JointStatistics<Tall, Square>& joint,
                 UpdateOutcome& outcome) {
  outcome.innovation = innovation;
  joint.pht = TimesTransposed<Tall>(covariance, SparseRows(jacobian), jacobian.rows());
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

/// y += a x over n entries.
void Axpy(double a, const double* __restrict__ x, double* __restrict__ y, Eigen::Index n) {
  for (Eigen::Index r = 0; r < n; ++r) y[r] += a * x[r];
}

/// The vectors of one scalar correction from u = P h^T and s = h u + r > 0: the gain k = u / s (one
/// division, not n: any gain is fine for the Joseph form) and v = u - (s / 2) k.
void ScalarGain(const double* __restrict__ u, double s, Eigen::Index n, double* __restrict__ k,
                double* __restrict__ v) {
  const double inverse = 1.0 / s, half = 0.5 * s;
  for (Eigen::Index r = 0; r < n; ++r) {
    k[r] = u[r] * inverse;
    v[r] = u[r] - half * k[r];
  }
}

/// p -= sum over the Count correction columns e of k_e v_e^T + v_e k_e^T, entry (r, c) summed in a
/// register in the order of e; k and v hold Count columns of length n (leading dimension n). Entry
/// (c, r) takes the same products and addends in commuted order, and IEEE products and sums commute:
/// a symmetric P stays exactly symmetric without a mirroring pass (its strided stores would cost as
/// much as the update). That needs every product rounded on its own: no FMA contraction
/// (cmake/RowlocOptions.cmake). Count is a compile-time constant, so the sum unrolls and the loop
/// over the contiguous rows vectorizes. Each Count is its own cloned function: its restrict
/// parameters spare the loop the run-time aliasing checks an inlined copy would get.
template <int Count>
ROWLOC_VECTOR_CLONES void SubtractSymmetricCorrectionsOf(double* __restrict__ p, const double* __restrict__ k,
                                                         const double* __restrict__ v, Eigen::Index n) {
  if (n < detail::kLanes) {
    for (Eigen::Index c = 0; c < n; ++c) {
      for (Eigen::Index r = 0; r < n; ++r) {
        double sum = k[r] * v[c] + v[r] * k[c];
        for (int e = 1; e < Count; ++e) sum += k[e * n + r] * v[e * n + c] + v[e * n + r] * k[e * n + c];
        p[c * n + r] -= sum;
      }
    }
    return;
  }
  using detail::Double4, detail::Load4;
  for (Eigen::Index c = 0; c < n; ++c) {
    Double4 kc[Count], vc[Count];
    for (int e = 0; e < Count; ++e) {
      kc[e] = detail::Broadcast4(k[e * n + c]);
      vc[e] = detail::Broadcast4(v[e * n + c]);
    }
    double* __restrict__ column = p + c * n;
    detail::ForEachRowBlock(n, column, [&](Eigen::Index r) {  // the scalar loop's operations, lane-wise
      Double4 sum = Load4(k + r) * vc[0] + Load4(v + r) * kc[0];
      for (int e = 1; e < Count; ++e) sum += Load4(k + e * n + r) * vc[e] + Load4(v + e * n + r) * kc[e];
      return Load4(column + r) - sum;
    });
  }
}

/// SubtractSymmetricCorrectionsOf for any count >= 1: one pass over P per kMaxCombinedColumns
/// corrections (each pass keeps P exactly symmetric).
void SubtractSymmetricCorrections(double* p, const double* k, const double* v, Eigen::Index n, Eigen::Index count) {
  for (Eigen::Index first = 0; first < count; first += detail::kMaxCombinedColumns) {
    const double* ks = k + first * n;
    const double* vs = v + first * n;
    switch (std::min<Eigen::Index>(count - first, detail::kMaxCombinedColumns)) {
      case 1: SubtractSymmetricCorrectionsOf<1>(p, ks, vs, n); break;
      case 2: SubtractSymmetricCorrectionsOf<2>(p, ks, vs, n); break;
      case 3: SubtractSymmetricCorrectionsOf<3>(p, ks, vs, n); break;
      case 4: SubtractSymmetricCorrectionsOf<4>(p, ks, vs, n); break;
      case 5: SubtractSymmetricCorrectionsOf<5>(p, ks, vs, n); break;
      case 6: SubtractSymmetricCorrectionsOf<6>(p, ks, vs, n); break;
      case 7: SubtractSymmetricCorrectionsOf<7>(p, ks, vs, n); break;
      default: SubtractSymmetricCorrectionsOf<detail::kMaxCombinedColumns>(p, ks, vs, n); break;
    }
  }
}

/// target = M h^T for the first row h of H: SparseRows::TimesTransposed (the same operations in the
/// same order) without building its tables, which cost as much as the product for one row.
ROWLOC_VECTOR_CLONES
void TimesTransposedFirstRow(const Eigen::MatrixXd& m, const MatrixRef& h, double* __restrict__ target) {
  std::fill(target, target + m.rows(), 0.0);
  const double* sources[detail::kMaxCombinedColumns];
  double scales[detail::kMaxCombinedColumns];
  int count = 0;
  const double* entry = h.data();  // h(0, j) = entry[j * stride]
  for (Eigen::Index j = 0; j < h.cols(); ++j, entry += h.outerStride()) {
    if (*entry == 0.0) continue;
    sources[count] = m.col(j).data();
    scales[count++] = *entry;
    if (count == detail::kMaxCombinedColumns) {
      detail::CombineColumns<true>(sources, scales, count, m.rows(), target);
      count = 0;
    }
  }
  if (count > 0) detail::CombineColumns<true>(sources, scales, count, m.rows(), target);
}

/// u = P h^T for the one-row sparse H.
template <typename Vector>
Vector SparseColumn(const Eigen::MatrixXd& covariance, const MatrixRef& jacobian) {
  Vector u(covariance.rows());
  TimesTransposedFirstRow(covariance, jacobian, u.data());
  return u;
}

/// One scalar correction with u = P h^T and s = h u + r > 0: k = u / s, x <- x + k y and the Joseph
/// form (I - k h) P (I - k h)^T + k r k^T = P - k u^T - u k^T + s k k^T = P - k v^T - v k^T with
/// v = u - (s / 2) k, for any k. P must be symmetric (KalmanUpdate's precondition); it stays exactly
/// symmetric (SubtractSymmetricCorrections).
template <typename Vector>
void ApplyScalarCorrection(Eigen::VectorXd& state, Eigen::MatrixXd& covariance, const Vector& u, double s, double y) {
  const Eigen::Index n = state.size();
  Vector gain(n), v(n);
  ScalarGain(u.data(), s, n, gain.data(), v.data());
  Axpy(y, gain.data(), state.data(), n);
  SubtractSymmetricCorrections(covariance.data(), gain.data(), v.data(), n, 1);
}

/// The update of one scalar measurement (m = 1): S, the NIS and the gain are scalars, so there is
/// nothing to factorize. Vector: an n-vector type.
template <typename Vector>
UpdateOutcome ScalarUpdateWith(Eigen::VectorXd& state, Eigen::MatrixXd& covariance, const VectorRef& innovation,
                               const MatrixRef& jacobian, double noise, double gate_threshold, int angle_index) {
  UpdateOutcome outcome;
  outcome.innovation = innovation;
  const Vector u = SparseColumn<Vector>(covariance, jacobian);
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

/// The update of m measurements with a diagonal R: m sequential scalar corrections at one
/// linearization point (sequential Kalman filtering: Simon, Optimal State Estimation, 2006, §6.1),
/// equal to the joint update for a linearized measurement with independent components. Correction i
/// has u_i = P_(i-1) h_i^T, s_i = h_i u_i + R_ii, k_i = u_i / s_i and the innovation
/// y_i - h_i (x_(i-1) - x_0); its Joseph form is P_i = P_(i-1) - k_i v_i^T - v_i k_i^T with
/// v_i = u_i - (s_i / 2) k_i (ApplyScalarCorrection). All corrections are computed before P changes:
/// with U = P H^T (sparse H), P_(i-1) = P - sum_(j<i) (k_j v_j^T + v_j k_j^T) gives exactly
///   u_i = U_i - sum_(j<i) (k_j (v_j . h_i) + v_j (k_j . h_i)),
/// and then they are applied to P in one pass (SubtractSymmetricCorrections). The s_i are the
/// pivots of the LDL^T factorization of S = H P H^T + R, so S is positive definite iff every
/// s_i > 0, and the joint NIS y^T S^-1 y is sum_i y_i'^2 / s_i (the chain rule of the Gaussian
/// likelihood): the gate needs no factorization, and a gated update leaves x and P untouched.
/// Tall: n x m; Square: m x m; Vector: n.
template <typename Tall, typename Square, typename Vector>
UpdateOutcome SequentialUpdateWith(Eigen::VectorXd& state, Eigen::MatrixXd& covariance,
                                   const VectorRef& innovation, const MatrixRef& jacobian,
                                   const MatrixRef& noise, double gate_threshold, int angle_index) {
  const Eigen::Index n = state.size();
  const Eigen::Index m = innovation.size();
  const SparseRows h(jacobian);
  UpdateOutcome outcome;
  outcome.innovation = innovation;
  Tall u = TimesTransposed<Tall>(covariance, h, m);  // U = P H^T, then column i becomes u_i
  Square s(m, m);  // S = H P H^T + R (R diagonal), computed on the upper triangle: exactly symmetric
  for (Eigen::Index j = 0; j < m; ++j) {
    for (Eigen::Index i = 0; i <= j; ++i) s(i, j) = s(j, i) = h.Dot(i, u.col(j).data()) + noise(i, j);
  }
  outcome.innovation_covariance = s;
  Tall gain(n, m), half(n, m);     // k_i, v_i
  Vector shift = Vector::Zero(n);  // x_(i-1) - x_0
  double nis = 0.0;
  for (Eigen::Index i = 0; i < m; ++i) {
    double* u_i = u.col(i).data();
    for (Eigen::Index j = 0; j < i; ++j) {
      const double* k_j = gain.col(j).data();
      const double* v_j = half.col(j).data();
      Axpy(-h.Dot(i, v_j), k_j, u_i, n);
      Axpy(-h.Dot(i, k_j), v_j, u_i, n);
    }
    const double s_i = h.Dot(i, u_i) + noise(i, i);
    if (!(s_i > 0.0)) {
      outcome.nis = std::numeric_limits<double>::infinity();
      return outcome;  // S not positive definite: never apply such an update
    }
    const double y_i = innovation(i) - h.Dot(i, shift.data());
    nis += y_i * (y_i / s_i);
    ScalarGain(u_i, s_i, n, gain.col(i).data(), half.col(i).data());
    Axpy(y_i, gain.col(i).data(), shift.data(), n);
  }
  outcome.nis = nis;
  if (!(nis <= gate_threshold)) return outcome;
  state += shift;
  if (angle_index >= 0) state(angle_index) = WrapAngle(state(angle_index));
  SubtractSymmetricCorrections(covariance.data(), gain.data(), half.data(), n, m);
  outcome.accepted = true;
  return outcome;
}

/// No NaN or infinity among the entries: x * 0 is 0 for a finite x and NaN otherwise, and a sum
/// of zeros is exactly 0, so the test is exact; over contiguous storage Eigen vectorizes the sum
/// (Eigen's allFinite walks a Ref's strides one coefficient at a time, about 12 instructions per
/// entry).
template <typename Ref>
bool AllFinite(const Ref& m) {
  if (m.outerStride() != m.innerSize()) return m.allFinite();
  return (Eigen::Map<const Eigen::ArrayXd>(m.data(), m.size()) * 0.0).sum() == 0.0;
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
  if (!AllFinite(innovation) || !AllFinite(jacobian) || !AllFinite(noise)) {
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
  if (IsPositiveDiagonal(noise)) {  // independent components: sequential corrections
    if (n <= kStackStates && m <= kStackMeasurements) {
      using Tall = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kStackStates, kStackMeasurements>;
      using Square = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kStackMeasurements, kStackMeasurements>;
      using Vector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kStackStates, 1>;
      return SequentialUpdateWith<Tall, Square, Vector>(state, covariance, innovation, jacobian, noise,
                                                        gate_threshold, angle_index);
    }
    return SequentialUpdateWith<Eigen::MatrixXd, Eigen::MatrixXd, Eigen::VectorXd>(
        state, covariance, innovation, jacobian, noise, gate_threshold, angle_index);
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
