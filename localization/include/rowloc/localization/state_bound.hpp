// A state that crossed a limit of its domain, moved back onto the limit by the covariance-weighted
// projection (Simon and Chia, "Kalman filtering with state equality constraints", IEEE Trans.
// Aerospace and Electronic Systems 38(1), 2002, eq. (15) with W = P^-1; Simon, Optimal State
// Estimation, 2006, §7.5):
//   x' = argmin (x' - x)^T P^-1 (x' - x)  subject to  x'_i = b
//      = x + P e_i (b - x_i) / P_ii,
// the estimate an update with an exact measurement of state i at b would give. The states
// correlated with i move with it; a clamp of x_i alone would leave them where the crossing put
// them. P is left unchanged: a domain limit is an inequality, active only until the next update.
#pragma once

#include <Eigen/Core>

namespace rowloc::localization {

/// Moves x(index) to bound and the other states by P(:, index) (bound - x(index)) / P(index,
/// index). With P(index, index) <= 0 (a known state) only x(index) moves. Throws
/// std::invalid_argument for sizes that do not match, an index out of range or a non-finite bound.
void ProjectOntoBound(Eigen::VectorXd& x, const Eigen::MatrixXd& p, int index, double bound);

}  // namespace rowloc::localization
