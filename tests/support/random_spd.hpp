// Random symmetric positive definite matrices for property tests.
#pragma once

#include <Eigen/Core>

#include <random>

namespace rowloc::test {

/// A A^T + ridge I with A an n x n matrix of standard normal entries: SPD for ridge > 0, with
/// eigenvalues bounded below by ridge, and exactly symmetric (a matrix product need not round
/// both triangles alike; a covariance is, and the Kalman update requires it).
inline Eigen::MatrixXd RandomSpd(Eigen::Index n, std::mt19937_64& rng, double ridge) {
  std::normal_distribution<double> normal;
  Eigen::MatrixXd a(n, n);
  for (Eigen::Index i = 0; i < a.size(); ++i) a(i) = normal(rng);
  const Eigen::MatrixXd product = a * a.transpose();
  return 0.5 * (product + product.transpose()) + ridge * Eigen::MatrixXd::Identity(n, n);
}

}  // namespace rowloc::test
