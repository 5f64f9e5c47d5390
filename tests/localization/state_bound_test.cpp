// ProjectOntoBound (state_bound.hpp): the covariance-weighted projection of a state onto a domain
// limit, checked by its defining properties on random symmetric positive definite covariances.
#include "rowloc/localization/state_bound.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include <limits>
#include <random>
#include <stdexcept>

namespace rowloc::localization {
namespace {

Eigen::MatrixXd RandomCovariance(int n, std::mt19937& rng) {
  std::normal_distribution<double> normal;
  Eigen::MatrixXd a(n, n);
  for (int i = 0; i < n * n; ++i) a.data()[i] = normal(rng);
  return a * a.transpose() + 0.1 * Eigen::MatrixXd::Identity(n, n);
}

Eigen::VectorXd RandomVector(int n, std::mt19937& rng) {
  std::normal_distribution<double> normal;
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v(i) = normal(rng);
  return v;
}

// The result lies on the bound and is the minimiser of (x' - x)^T P^-1 (x' - x) on it: its
// gradient P^-1 (x' - x) is normal to the constraint (zero in every other component).
TEST(ProjectOntoBound, LandsOnTheBoundAtTheMostProbablePoint) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 2 + trial % 9;
    const Eigen::MatrixXd p = RandomCovariance(n, rng);
    const Eigen::VectorXd x = RandomVector(n, rng);
    const int index = trial % n;
    const double bound = x(index) - 0.5 - trial % 3;
    Eigen::VectorXd projected = x;
    ProjectOntoBound(projected, p, index, bound);
    EXPECT_EQ(projected(index), bound);
    const Eigen::VectorXd gradient = p.ldlt().solve(projected - x);
    for (int j = 0; j < n; ++j) {
      if (j == index) continue;
      EXPECT_NEAR(gradient(j), 0.0, 1e-9 * (1.0 + gradient.norm())) << trial << " " << j;
    }
    // Any other point on the bound is less probable (the Mahalanobis distance grows).
    Eigen::VectorXd other = projected;
    other((index + 1) % n) += 0.01;
    EXPECT_GT((other - x).dot(p.ldlt().solve(other - x)), (projected - x).dot(p.ldlt().solve(projected - x)));
  }
}

TEST(ProjectOntoBound, MovesOnlyTheCorrelatedStates) {
  Eigen::MatrixXd p = Eigen::MatrixXd::Identity(3, 3);
  p(0, 1) = p(1, 0) = 0.5;  // state 2 is uncorrelated with state 0
  Eigen::VectorXd x(3);
  x << -0.2, 1.0, 7.0;
  ProjectOntoBound(x, p, 0, 0.0);
  EXPECT_EQ(x(0), 0.0);
  EXPECT_DOUBLE_EQ(x(1), 1.0 + 0.5 * 0.2);  // P(1, 0) / P(0, 0) times the step 0.2
  EXPECT_EQ(x(2), 7.0);
}

TEST(ProjectOntoBound, AKnownStateIsClampedAloneAndAStateOnItsBoundIsLeft) {
  Eigen::MatrixXd p = Eigen::MatrixXd::Identity(2, 2);
  p(0, 0) = 0.0;
  Eigen::VectorXd x(2);
  x << -1.0, 3.0;
  ProjectOntoBound(x, p, 0, 0.0);
  EXPECT_EQ(x, Eigen::Vector2d(0.0, 3.0));
  const Eigen::VectorXd before = x;
  ProjectOntoBound(x, Eigen::MatrixXd::Identity(2, 2), 0, 0.0);
  EXPECT_EQ(x, before);
}

TEST(ProjectOntoBound, RejectsBadArguments) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(2);
  const Eigen::MatrixXd p = Eigen::MatrixXd::Identity(2, 2);
  EXPECT_THROW(ProjectOntoBound(x, Eigen::MatrixXd::Identity(3, 3), 0, 1.0), std::invalid_argument);
  EXPECT_THROW(ProjectOntoBound(x, p, 2, 1.0), std::invalid_argument);
  EXPECT_THROW(ProjectOntoBound(x, p, -1, 1.0), std::invalid_argument);
  EXPECT_THROW(ProjectOntoBound(x, p, 0, std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
  EXPECT_EQ(x, Eigen::Vector2d::Zero());
}

}  // namespace
}  // namespace rowloc::localization
