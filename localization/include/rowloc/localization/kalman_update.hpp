// One Kalman measurement update in Joseph form with chi-square gating (docs/localization-filter.md: sequential
// updates per sensor, Joseph-form covariance update, P kept symmetric positive definite,
// chi-square gating of outliers, NIS for every update).
//
// Given the innovation y = z - h(x), its Jacobian H and the measurement noise R:
//   S   = H P H^T + R,           NIS = y^T S^-1 y   (chi-square with m = dim(y) degrees of freedom)
//   rejected when NIS > gate (the state and P are then unchanged), else
//   K   = P H^T S^-1,            x  <- x + K y
//   P   <- (I - K H) P (I - K H)^T + K R K^T           (Joseph, Bucy & Joseph 1968; Bar-Shalom,
//                                                       Li & Kirubarajan 2001, eq. 5.2.3-18)
// computed with U = P H^T (skipping the zeros of the sparse H) as the identical
//   P <- P - K U^T - (U - K S) K^T          (valid for any gain K, like the product form)
// on the upper triangle only, mirrored to the lower: O(nnz(H) n + m n^2) instead of O(n^3), and P
// exactly symmetric. Two cheaper paths give the same result: a scalar measurement (m = 1) needs no
// factorization; m > 1 components with a diagonal R are m scalar corrections at the same
// linearization point (sequential Kalman filtering, Simon, Optimal State Estimation, 2006, §6.1),
// correction i with
//   u = P_(i-1) h_i^T, s = h_i u + R_ii, k = u / s,   P_i = P_(i-1) - k v^T - v k^T,
// v = u - (s / 2) k: the same Joseph identity for m = 1 (P - k u^T - u k^T + s k k^T). The s_i are
// the pivots of the LDL^T factorization of S, so the joint NIS is sum_i y_i'^2 / s_i (y_i' the
// innovation left after the first i - 1 corrections) and the gate needs no factorization; all
// corrections are computed from U = P H^T before P changes and then applied in one pass over P.
// Every entry of these corrections is computed alike for (r, c) and (c, r), so these paths need a
// symmetric P and keep it exactly symmetric without a mirroring pass (the filter's P always is:
// PredictStep and SetPose keep it so). The heading (state index angle_index) is wrapped to
// (-pi, pi] after the correction.
#pragma once

#include <Eigen/Core>

namespace rowloc::localization {

/// Arguments of KalmanUpdate: dynamic, fixed or bounded-size vectors and matrices bind without a
/// copy; Aligned16 (Eigen allocates them so) keeps Eigen's aligned vector loads in the inner loops
/// (an unaligned Ref made the 2-D update 15-20 % slower). Expressions, maps and blocks, which are
/// not aligned by type, are copied into the Ref first.
using VectorRef = Eigen::Ref<const Eigen::VectorXd, Eigen::Aligned16>;
using MatrixRef = Eigen::Ref<const Eigen::MatrixXd, Eigen::Aligned16, Eigen::OuterStride<>>;

struct UpdateOutcome {
  Eigen::VectorXd innovation;             ///< y = z - h(x) (angles wrapped by the caller)
  Eigen::MatrixXd innovation_covariance;  ///< S
  double nis = 0.0;                       ///< y^T S^-1 y
  bool accepted = false;                  ///< false: gated out (or S not positive definite)
};

/// Applies the update to (state, covariance) unless gated. covariance must be symmetric (an exactly
/// symmetric one stays exactly symmetric; the scalar and diagonal-noise paths do not symmetrize an
/// asymmetric one). gate_threshold is the NIS above which the measurement is rejected (+infinity:
/// never). angle_index < 0: no angle state to wrap.
/// Throws std::invalid_argument on mismatched sizes, angle_index >= state size or non-finite inputs
/// (innovation, H, R).
UpdateOutcome KalmanUpdate(Eigen::VectorXd& state, Eigen::MatrixXd& covariance, const VectorRef& innovation,
                           const MatrixRef& jacobian, const MatrixRef& noise, double gate_threshold, int angle_index);

/// The chi-square quantile Q(dof, probability) (Boost.Math), the gate for that probability.
/// Throws std::invalid_argument for dof < 1 or probability outside (0, 1).
double ChiSquareGate(int dof, double probability);

/// Wraps an angle to (-pi, pi].
double WrapAngle(double angle_rad);

}  // namespace rowloc::localization
