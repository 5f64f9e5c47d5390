// Property tests of the Joseph-form Kalman update with chi-square gating (kalman_update.hpp).
#include "rowloc/localization/kalman_update.hpp"

#include "random_spd.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>

namespace rowloc::localization {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Eigen::MatrixXd RandomMatrix(Eigen::Index rows, Eigen::Index cols, std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  Eigen::MatrixXd a(rows, cols);
  for (Eigen::Index i = 0; i < a.size(); ++i) a(i) = normal(rng);
  return a;
}

bool BitIdentical(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() && (a.array() == b.array()).all();
}

double RelativeError(const Eigen::MatrixXd& actual, const Eigen::MatrixXd& expected) {
  return (actual - expected).norm() / std::max(expected.norm(), 1e-300);
}

// A random problem of state size n and measurement size m.
struct Problem {
  Eigen::VectorXd x;
  Eigen::MatrixXd p, h, r;
  Eigen::VectorXd y;
};

Problem RandomProblem(Eigen::Index n, Eigen::Index m, std::mt19937_64& rng) {
  Problem pr;
  pr.x = RandomMatrix(n, 1, rng);
  pr.p = test::RandomSpd(n, rng, 0.5) / static_cast<double>(n);
  pr.h = RandomMatrix(m, n, rng);
  pr.r = test::RandomSpd(m, rng, 0.5) / static_cast<double>(m);
  pr.y = RandomMatrix(m, 1, rng);
  return pr;
}

TEST(KalmanUpdate, EqualsTheTextbookJosephUpdate) {
  std::mt19937_64 rng(20240601);
  for (Eigen::Index n = 3; n <= 21; ++n) {
    for (Eigen::Index m = 1; m <= 4; ++m) {
      const Problem pr = RandomProblem(n, m, rng);
      // Naive textbook formulas with an explicit inverse.
      const Eigen::MatrixXd s = pr.h * pr.p * pr.h.transpose() + pr.r;
      const Eigen::MatrixXd k = pr.p * pr.h.transpose() * s.inverse();
      const Eigen::VectorXd x_expected = pr.x + k * pr.y;
      const Eigen::MatrixXd i_kh = Eigen::MatrixXd::Identity(n, n) - k * pr.h;
      const Eigen::MatrixXd p_expected = i_kh * pr.p * i_kh.transpose() + k * pr.r * k.transpose();
      const double nis_expected = pr.y.dot(s.inverse() * pr.y);

      Eigen::VectorXd x = pr.x;
      Eigen::MatrixXd p = pr.p;
      const UpdateOutcome out = KalmanUpdate(x, p, pr.y, pr.h, pr.r, kInf, -1);
      ASSERT_TRUE(out.accepted) << "n " << n << " m " << m;
      EXPECT_LT(RelativeError(x, x_expected), 1e-12) << "n " << n << " m " << m;
      EXPECT_LT(RelativeError(p, p_expected), 1e-12) << "n " << n << " m " << m;
      EXPECT_LT(RelativeError(out.innovation_covariance, s), 1e-12) << "n " << n << " m " << m;
      EXPECT_NEAR(out.nis, nis_expected, 1e-12 * nis_expected) << "n " << n << " m " << m;
      EXPECT_TRUE(BitIdentical(out.innovation, pr.y));
    }
  }
}

// A random problem with a diagonal R (variances from 1e-4 to 10).
Problem RandomDiagonalProblem(Eigen::Index n, Eigen::Index m, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> log_scale(-4.0, 1.0);
  Problem pr = RandomProblem(n, m, rng);
  pr.r = Eigen::MatrixXd::Zero(m, m);
  for (Eigen::Index i = 0; i < m; ++i) pr.r(i, i) = std::pow(10.0, log_scale(rng));
  return pr;
}

// A diagonal R takes the sequential path (m scalar corrections at one linearization point, applied
// to P in one pass per 8 of them): the same result as the joint textbook update. n = 40 and m > 8
// are beyond the stack temporaries; m = 9, 10 take two passes over P.
TEST(KalmanUpdate, DiagonalNoiseEqualsTheTextbookJosephUpdate) {
  std::mt19937_64 rng(20261201);
  for (const Eigen::Index n : {3, 9, 14, 23, 40}) {
    for (Eigen::Index m = 2; m <= 10; ++m) {
      const Problem pr = RandomDiagonalProblem(n, m, rng);
      const Eigen::MatrixXd s = pr.h * pr.p * pr.h.transpose() + pr.r;
      const Eigen::MatrixXd k = pr.p * pr.h.transpose() * s.inverse();
      const Eigen::MatrixXd i_kh = Eigen::MatrixXd::Identity(n, n) - k * pr.h;
      const Eigen::MatrixXd p_expected = i_kh * pr.p * i_kh.transpose() + k * pr.r * k.transpose();
      Eigen::VectorXd x = pr.x;
      Eigen::MatrixXd p = pr.p;
      const UpdateOutcome out = KalmanUpdate(x, p, pr.y, pr.h, pr.r, kInf, -1);
      ASSERT_TRUE(out.accepted) << "n " << n << " m " << m;
      EXPECT_LT(RelativeError(x, pr.x + k * pr.y), 1e-10) << "n " << n << " m " << m;
      EXPECT_LT(RelativeError(p, p_expected), 1e-10) << "n " << n << " m " << m;
      EXPECT_TRUE(BitIdentical(p, p.transpose())) << "n " << n << " m " << m;
      EXPECT_NEAR(out.nis, pr.y.dot(s.inverse() * pr.y), 1e-10 * out.nis) << "n " << n << " m " << m;
    }
  }
}

TEST(KalmanUpdate, PosteriorIsSymmetricPositiveDefiniteWithNoLargerTrace) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> log_scale(-6.0, 2.0);
  for (int trial = 0; trial < 300; ++trial) {
    const Eigen::Index n = 3 + trial % 19;
    const Eigen::Index m = 1 + trial % 4;
    Problem pr = RandomProblem(n, m, rng);
    pr.r *= std::pow(10.0, log_scale(rng));  // from a very precise to a very poor sensor
    Eigen::VectorXd x = pr.x;
    Eigen::MatrixXd p = pr.p;
    ASSERT_TRUE(KalmanUpdate(x, p, pr.y, pr.h, pr.r, kInf, -1).accepted);
    EXPECT_TRUE(BitIdentical(p, p.transpose())) << "trial " << trial;
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(p);
    EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0) << "trial " << trial;
    EXPECT_LE(p.trace(), pr.p.trace() * (1.0 + 1e-12)) << "trial " << trial;
    // Information only increases: P+ <= P- (P- - P+ positive semidefinite).
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> gain_eig(pr.p - p);
    EXPECT_GT(gain_eig.eigenvalues().minCoeff(), -1e-12 * pr.p.norm()) << "trial " << trial;
  }
}

TEST(KalmanUpdate, ManySequentialUpdatesKeepPositiveDefinite) {
  std::mt19937_64 rng(99);
  Problem pr = RandomProblem(12, 2, rng);
  Eigen::VectorXd x = pr.x;
  Eigen::MatrixXd p = pr.p;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::MatrixXd h = RandomMatrix(2, 12, rng);
    const Eigen::MatrixXd r = 1e-8 * Eigen::MatrixXd::Identity(2, 2);
    ASSERT_TRUE(KalmanUpdate(x, p, RandomMatrix(2, 1, rng) * 1e-4, h, r, kInf, -1).accepted);
  }
  EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(p).info(), Eigen::Success);
  EXPECT_TRUE(BitIdentical(p, p.transpose()));
}

TEST(KalmanUpdate, GatedMeasurementLeavesStateAndCovarianceUntouched) {
  std::mt19937_64 rng(3);
  for (Eigen::Index m = 1; m <= 4; ++m) {
    Problem pr = RandomProblem(9, m, rng);
    const Eigen::MatrixXd s = pr.h * pr.p * pr.h.transpose() + pr.r;
    const double nis = pr.y.dot(s.inverse() * pr.y);
    Eigen::VectorXd x = pr.x;
    Eigen::MatrixXd p = pr.p;
    const UpdateOutcome out = KalmanUpdate(x, p, pr.y, pr.h, pr.r, 0.999 * nis, 2);
    EXPECT_FALSE(out.accepted);
    EXPECT_NEAR(out.nis, nis, 1e-12 * nis);
    EXPECT_TRUE(BitIdentical(x, pr.x));
    EXPECT_TRUE(BitIdentical(p, pr.p));
    EXPECT_LT(RelativeError(out.innovation_covariance, s), 1e-12);
    // Just above the NIS: accepted, with the same NIS.
    const UpdateOutcome in = KalmanUpdate(x, p, pr.y, pr.h, pr.r, 1.001 * nis, 2);
    EXPECT_TRUE(in.accepted);
    EXPECT_NEAR(in.nis, nis, 1e-12 * nis);
    EXPECT_FALSE(BitIdentical(p, pr.p));
  }
}

// The sequential path gates on the joint NIS (the sum of the sequential y_i^2 / s_i) before it
// changes anything.
TEST(KalmanUpdate, DiagonalNoiseIsGatedOnTheJointNis) {
  std::mt19937_64 rng(11);
  for (Eigen::Index m = 2; m <= 10; ++m) {
    const Problem pr = RandomDiagonalProblem(14, m, rng);
    const Eigen::MatrixXd s = pr.h * pr.p * pr.h.transpose() + pr.r;
    const double nis = pr.y.dot(s.inverse() * pr.y);
    Eigen::VectorXd x = pr.x;
    Eigen::MatrixXd p = pr.p;
    const UpdateOutcome out = KalmanUpdate(x, p, pr.y, pr.h, pr.r, 0.999 * nis, 2);
    EXPECT_FALSE(out.accepted) << "m " << m;
    EXPECT_NEAR(out.nis, nis, 1e-10 * nis) << "m " << m;
    EXPECT_TRUE(BitIdentical(x, pr.x)) << "m " << m;
    EXPECT_TRUE(BitIdentical(p, pr.p)) << "m " << m;
    EXPECT_LT(RelativeError(out.innovation_covariance, s), 1e-12) << "m " << m;
    EXPECT_TRUE(BitIdentical(out.innovation_covariance, out.innovation_covariance.transpose())) << "m " << m;
    const UpdateOutcome in = KalmanUpdate(x, p, pr.y, pr.h, pr.r, 1.001 * nis, 2);
    EXPECT_TRUE(in.accepted) << "m " << m;
    EXPECT_FALSE(BitIdentical(p, pr.p)) << "m " << m;
  }
}

TEST(KalmanUpdate, HugeInnovationIsGatedAtTheChiSquareQuantile) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(3);
  Eigen::MatrixXd p = Eigen::MatrixXd::Identity(3, 3);
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(2, 3);
  h(0, 0) = h(1, 1) = 1.0;
  const Eigen::MatrixXd r = Eigen::MatrixXd::Identity(2, 2);  // S = 2 I
  const Eigen::Vector2d y(6.0, 0.0);                           // NIS = 18
  const UpdateOutcome out = KalmanUpdate(x, p, y, h, r, ChiSquareGate(2, 0.9999), -1);
  EXPECT_DOUBLE_EQ(out.nis, 18.0);
  EXPECT_TRUE(out.accepted);  // Q(2, 0.9999) = 18.42
  x.setZero();
  p.setIdentity();
  const UpdateOutcome rejected = KalmanUpdate(x, p, Eigen::Vector2d(7.0, 0.0), h, r, ChiSquareGate(2, 0.9999), -1);
  EXPECT_DOUBLE_EQ(rejected.nis, 24.5);
  EXPECT_FALSE(rejected.accepted);
}

TEST(KalmanUpdate, ScalarUpdateHasTheClosedForm) {
  Eigen::VectorXd x(2);
  x << 1.0, 2.0;
  Eigen::MatrixXd p(2, 2);
  p << 4.0, 1.0, 1.0, 2.0;
  Eigen::MatrixXd h(1, 2);
  h << 1.0, 0.0;
  const Eigen::MatrixXd r = Eigen::MatrixXd::Constant(1, 1, 1.0);
  const UpdateOutcome out = KalmanUpdate(x, p, Eigen::VectorXd::Constant(1, 2.5), h, r, kInf, -1);
  ASSERT_TRUE(out.accepted);
  // S = 5, K = (0.8, 0.2), x = (3, 2.5), P = P - K S K^T.
  EXPECT_DOUBLE_EQ(out.innovation_covariance(0, 0), 5.0);
  EXPECT_DOUBLE_EQ(out.nis, 1.25);
  EXPECT_NEAR(x(0), 3.0, 1e-15);
  EXPECT_NEAR(x(1), 2.5, 1e-15);
  EXPECT_NEAR(p(0, 0), 0.8, 1e-15);
  EXPECT_NEAR(p(0, 1), 0.2, 1e-15);
  EXPECT_NEAR(p(1, 1), 1.8, 1e-15);
}

TEST(KalmanUpdate, WrapsTheHeadingAfterTheCorrection) {
  std::mt19937_64 rng(5);
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(1, 4);
  h(0, 2) = 1.0;
  const Eigen::MatrixXd r = Eigen::MatrixXd::Constant(1, 1, 0.01);
  for (const double start : {3.1, -3.1}) {
    Eigen::VectorXd x = Eigen::VectorXd::Zero(4);
    x(2) = start;
    Eigen::MatrixXd p = test::RandomSpd(4, rng, 0.5);
    const double k = p(2, 2) / (p(2, 2) + 0.01);
    const double innovation = start > 0 ? 0.3 : -0.3;  // pushes the heading across +-pi
    const Eigen::VectorXd unwrapped = x + p.col(2) / (p(2, 2) + 0.01) * innovation;
    KalmanUpdate(x, p, Eigen::VectorXd::Constant(1, innovation), h, r, kInf, 2);
    EXPECT_GT(x(2), -kPi);
    EXPECT_LE(x(2), kPi);
    EXPECT_NEAR(x(2), start + k * innovation - (start > 0 ? 2 * kPi : -2 * kPi), 1e-12);
    for (int i : {0, 1, 3}) EXPECT_NEAR(x(i), unwrapped(i), 1e-12) << i;  // other states not wrapped
  }
  // angle_index < 0: nothing is wrapped.
  Eigen::VectorXd x = Eigen::VectorXd::Zero(4);
  x(2) = 3.1;
  Eigen::MatrixXd p = Eigen::MatrixXd::Identity(4, 4);
  KalmanUpdate(x, p, Eigen::VectorXd::Constant(1, 1.0), h, r, kInf, -1);
  EXPECT_GT(x(2), kPi);
}

TEST(KalmanUpdate, RejectsMismatchedSizes) {
  std::mt19937_64 rng(1);
  const Problem pr = RandomProblem(5, 2, rng);
  auto call = [&](Eigen::VectorXd x, Eigen::MatrixXd p, const Eigen::VectorXd& y, const Eigen::MatrixXd& h,
                  const Eigen::MatrixXd& r) { KalmanUpdate(x, p, y, h, r, kInf, -1); };
  EXPECT_NO_THROW(call(pr.x, pr.p, pr.y, pr.h, pr.r));
  EXPECT_THROW(call(pr.x.head(4), pr.p, pr.y, pr.h, pr.r), std::invalid_argument);          // state
  EXPECT_THROW(call(pr.x, pr.p.topLeftCorner(4, 5), pr.y, pr.h, pr.r), std::invalid_argument);  // P rows
  EXPECT_THROW(call(pr.x, pr.p.topLeftCorner(5, 4), pr.y, pr.h, pr.r), std::invalid_argument);  // P cols
  EXPECT_THROW(call(pr.x, pr.p, pr.y.head(1), pr.h, pr.r), std::invalid_argument);          // innovation
  EXPECT_THROW(call(pr.x, pr.p, pr.y, pr.h.topRows(1), pr.r), std::invalid_argument);      // H rows
  EXPECT_THROW(call(pr.x, pr.p, pr.y, pr.h.leftCols(4), pr.r), std::invalid_argument);     // H cols
  EXPECT_THROW(call(pr.x, pr.p, pr.y, pr.h, pr.r.topLeftCorner(1, 1)), std::invalid_argument);  // R
  EXPECT_THROW(call(pr.x, pr.p, pr.y, pr.h, pr.r.topRows(1)), std::invalid_argument);
  EXPECT_THROW(call(pr.x, pr.p, Eigen::VectorXd(0), Eigen::MatrixXd(0, 5), Eigen::MatrixXd(0, 0)),
               std::invalid_argument);  // empty measurement
}

TEST(KalmanUpdate, RejectsNonFiniteInputs) {
  std::mt19937_64 rng(2);
  const Problem pr = RandomProblem(5, 2, rng);
  for (const double bad : {kNaN, kInf, -kInf}) {
    Eigen::VectorXd x = pr.x;
    Eigen::MatrixXd p = pr.p;
    Eigen::VectorXd y = pr.y;
    y(1) = bad;
    EXPECT_THROW(KalmanUpdate(x, p, y, pr.h, pr.r, kInf, -1), std::invalid_argument);
    Eigen::MatrixXd h = pr.h;
    h(1, 3) = bad;
    EXPECT_THROW(KalmanUpdate(x, p, pr.y, h, pr.r, kInf, -1), std::invalid_argument);
    Eigen::MatrixXd r = pr.r;
    r(0, 0) = bad;
    EXPECT_THROW(KalmanUpdate(x, p, pr.y, pr.h, r, kInf, -1), std::invalid_argument);
    EXPECT_TRUE(BitIdentical(x, pr.x));
    EXPECT_TRUE(BitIdentical(p, pr.p));
  }
}

// H viewed in a larger buffer (outer stride 3 for 2 rows): a bad entry of H is found, one in the
// padding row (not part of H) is not.
TEST(KalmanUpdate, NonFiniteCheckFollowsTheJacobiansStrides) {
  std::mt19937_64 rng(4);
  const Problem pr = RandomProblem(5, 2, rng);
  using StridedMap = Eigen::Map<const Eigen::MatrixXd, Eigen::Aligned16, Eigen::OuterStride<>>;
  Eigen::MatrixXd buffer = Eigen::MatrixXd::Zero(3, 5);
  buffer.topRows(2) = pr.h;
  for (const double bad : {kNaN, kInf}) {
    buffer(2, 4) = bad;  // padding
    Eigen::VectorXd x = pr.x;
    Eigen::MatrixXd p = pr.p;
    EXPECT_TRUE(KalmanUpdate(x, p, pr.y, StridedMap(buffer.data(), 2, 5, Eigen::OuterStride<>(3)), pr.r, kInf, -1)
                    .accepted);
    buffer(2, 4) = 0.0;
    buffer(1, 4) = bad;  // in H
    x = pr.x;
    p = pr.p;
    EXPECT_THROW(KalmanUpdate(x, p, pr.y, StridedMap(buffer.data(), 2, 5, Eigen::OuterStride<>(3)), pr.r, kInf, -1),
                 std::invalid_argument);
    buffer(1, 4) = pr.h(1, 4);
  }
}

TEST(KalmanUpdate, IndefiniteInnovationCovarianceIsNeverApplied) {
  Eigen::VectorXd x = Eigen::VectorXd::Ones(3);
  Eigen::MatrixXd p = Eigen::MatrixXd::Identity(3, 3);
  const Eigen::MatrixXd h = Eigen::MatrixXd::Identity(1, 3);
  const Eigen::MatrixXd r = Eigen::MatrixXd::Constant(1, 1, -2.0);  // S = -1
  const UpdateOutcome out = KalmanUpdate(x, p, Eigen::VectorXd::Constant(1, 0.1), h, r, kInf, -1);
  EXPECT_FALSE(out.accepted);
  EXPECT_TRUE(std::isinf(out.nis));
  EXPECT_TRUE(BitIdentical(x, Eigen::VectorXd::Ones(3)));
  EXPECT_TRUE(BitIdentical(p, Eigen::MatrixXd::Identity(3, 3)));
}

TEST(ChiSquareGate, KnownQuantiles) {
  EXPECT_NEAR(ChiSquareGate(2, 0.95), 5.991, 1e-3);
  EXPECT_NEAR(ChiSquareGate(2, 0.95), -2.0 * std::log(0.05), 1e-12);  // closed form for dof 2
  EXPECT_NEAR(ChiSquareGate(3, 0.9999), 21.108, 1e-3);
  EXPECT_NEAR(ChiSquareGate(1, 0.95), 3.841, 1e-3);
  EXPECT_NEAR(ChiSquareGate(4, 0.99), 13.277, 1e-3);
  EXPECT_LT(ChiSquareGate(2, 0.9), ChiSquareGate(2, 0.99));  // increasing in p
  EXPECT_LT(ChiSquareGate(2, 0.99), ChiSquareGate(3, 0.99));  // and in dof
}

TEST(ChiSquareGate, RejectsInvalidArguments) {
  EXPECT_THROW(ChiSquareGate(0, 0.95), std::invalid_argument);
  EXPECT_THROW(ChiSquareGate(-1, 0.95), std::invalid_argument);
  EXPECT_THROW(ChiSquareGate(2, 0.0), std::invalid_argument);
  EXPECT_THROW(ChiSquareGate(2, 1.0), std::invalid_argument);
  EXPECT_THROW(ChiSquareGate(2, -0.5), std::invalid_argument);
  EXPECT_THROW(ChiSquareGate(2, 1.5), std::invalid_argument);
  EXPECT_THROW(ChiSquareGate(2, kNaN), std::invalid_argument);
}

TEST(WrapAngle, MapsIntoHalfOpenInterval) {
  EXPECT_EQ(WrapAngle(0.0), 0.0);
  EXPECT_EQ(WrapAngle(1.0), 1.0);
  EXPECT_EQ(WrapAngle(-1.0), -1.0);
  EXPECT_EQ(WrapAngle(kPi), kPi);    // pi stays pi
  EXPECT_EQ(WrapAngle(-kPi), kPi);   // -pi is not in the interval
  EXPECT_NEAR(WrapAngle(3 * kPi), kPi, 1e-12);
  EXPECT_NEAR(WrapAngle(-3 * kPi), kPi, 1e-12);
  EXPECT_NEAR(WrapAngle(2 * kPi), 0.0, 1e-15);
  EXPECT_NEAR(WrapAngle(kPi + 0.5), -kPi + 0.5, 1e-12);
  EXPECT_NEAR(WrapAngle(-kPi - 0.5), kPi - 0.5, 1e-12);
  EXPECT_NEAR(WrapAngle(1000.0), 1000.0 - 159 * 2 * kPi, 1e-9);
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> angle(-1e6, 1e6);
  for (int i = 0; i < 10000; ++i) {
    const double a = angle(rng);
    const double w = WrapAngle(a);
    ASSERT_GT(w, -kPi) << a;
    ASSERT_LE(w, kPi) << a;
    // Same direction: a - w is a multiple of 2 pi.
    EXPECT_NEAR(std::sin(w), std::sin(a), 1e-9) << a;
    EXPECT_NEAR(std::cos(w), std::cos(a), 1e-9) << a;
  }
}

}  // namespace
}  // namespace rowloc::localization
