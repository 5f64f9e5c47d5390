// Tests of the Ellipsoid value type (docs/ellipsoid.md): validation, FromCovariance, Mahalanobis distance,
// volume, projection (principal submatrix, not the Schur-complement slice of Donati 2021).
#include "rowloc/geometry/ellipsoid.hpp"

#include "min_volume_ellipsoid.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "random_spd.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

namespace rowloc::geometry {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

/// A random symmetric positive definite matrix with strong correlations.
Eigen::MatrixXd RandomSpd(Eigen::Index n, std::mt19937_64& rng) {
  return test::RandomSpd(n, rng, 0.05);
}

TEST(EllipsoidTest, StoresCenterAndShapeAndFactor) {
  const Eigen::Vector2d center(1.0, -2.0);
  Eigen::Matrix2d shape;
  shape << 4.0, 1.0, 1.0, 2.0;
  const Ellipsoid<2> e(center, shape);
  EXPECT_EQ(e.center(), center);
  EXPECT_EQ(e.shape(), shape);
  EXPECT_EQ(e.dimension(), 2);
  const Eigen::Matrix2d l = e.cholesky_factor();
  EXPECT_DOUBLE_EQ(l(0, 1), 0.0);
  EXPECT_TRUE((l * l.transpose()).isApprox(shape, 1e-14));
}

TEST(EllipsoidTest, RejectsNonFiniteEntries) {
  const Eigen::Matrix2d identity = Eigen::Matrix2d::Identity();
  EXPECT_THROW(Ellipsoid<2>(Eigen::Vector2d(kNaN, 0.0), identity), std::invalid_argument);
  EXPECT_THROW(Ellipsoid<2>(Eigen::Vector2d(0.0, kInf), identity), std::invalid_argument);
  Eigen::Matrix2d shape = identity;
  shape(1, 1) = kNaN;
  EXPECT_THROW(Ellipsoid<2>(Eigen::Vector2d::Zero(), shape), std::invalid_argument);
  shape(1, 1) = kInf;
  EXPECT_THROW(Ellipsoid<2>(Eigen::Vector2d::Zero(), shape), std::invalid_argument);
}

TEST(EllipsoidTest, RejectsNonSymmetricShape) {
  Eigen::Matrix2d shape;
  shape << 2.0, 0.5, 0.4, 2.0;
  EXPECT_THROW(Ellipsoid<2>(Eigen::Vector2d::Zero(), shape), std::invalid_argument);
}

TEST(EllipsoidTest, AcceptsRoundingLevelAsymmetryAndSymmetrizes) {
  Eigen::Matrix2d shape;
  shape << 2.0, 0.5 + 1e-13, 0.5, 2.0;
  const Ellipsoid<2> e(Eigen::Vector2d::Zero(), shape);
  EXPECT_EQ(e.shape()(0, 1), e.shape()(1, 0));
}

TEST(EllipsoidTest, RejectsShapeThatIsNotPositiveDefinite) {
  Eigen::Matrix2d indefinite;
  indefinite << 1.0, 2.0, 2.0, 1.0;
  EXPECT_THROW(Ellipsoid<2>(Eigen::Vector2d::Zero(), indefinite), std::invalid_argument);
  EXPECT_THROW(Ellipsoid<2>(Eigen::Vector2d::Zero(), Eigen::Matrix2d::Zero()), std::invalid_argument);
  EXPECT_THROW(Ellipsoid<2>(Eigen::Vector2d::Zero(), -Eigen::Matrix2d::Identity()), std::invalid_argument);
  Eigen::Matrix2d singular;
  singular << 1.0, 1.0, 1.0, 1.0;
  EXPECT_THROW(Ellipsoid<2>(Eigen::Vector2d::Zero(), singular), std::invalid_argument);
}

TEST(EllipsoidTest, DynamicSizeRejectsMismatchAndEmpty) {
  EXPECT_THROW(Ellipsoid<Eigen::Dynamic>(Eigen::VectorXd::Zero(3), Eigen::MatrixXd::Identity(2, 2)),
               std::invalid_argument);
  EXPECT_THROW(Ellipsoid<Eigen::Dynamic>(Eigen::VectorXd::Zero(2), Eigen::MatrixXd::Identity(2, 3)),
               std::invalid_argument);
  EXPECT_THROW(Ellipsoid<Eigen::Dynamic>(Eigen::VectorXd(0), Eigen::MatrixXd(0, 0)), std::invalid_argument);
  const Ellipsoid<Eigen::Dynamic> e(Eigen::VectorXd::Zero(3), Eigen::MatrixXd::Identity(3, 3));
  EXPECT_THROW(static_cast<void>(e.MahalanobisSquared(Eigen::VectorXd::Zero(2))), std::invalid_argument);
  EXPECT_THROW(static_cast<void>(e.Contains(Eigen::VectorXd::Zero(4))), std::invalid_argument);
}

TEST(EllipsoidTest, FromCovarianceScalesByKSquared) {
  Eigen::Matrix3d covariance;
  covariance << 0.04, 0.01, 0.0, 0.01, 0.09, -0.02, 0.0, -0.02, 0.25;
  const Eigen::Vector3d mean(1.0, 2.0, 3.0);
  const auto e = Ellipsoid<3>::FromCovariance(mean, covariance, 3.0);
  EXPECT_EQ(e.center(), mean);
  EXPECT_TRUE(e.shape().isApprox(9.0 * covariance, 1e-15));
  // A point k sigma away along a principal axis of an axis-aligned covariance is on the boundary.
  const auto axis = Ellipsoid<2>::FromCovariance(Eigen::Vector2d::Zero(), Eigen::Vector2d(4.0, 1.0).asDiagonal(), 2.0);
  EXPECT_NEAR(axis.MahalanobisSquared(Eigen::Vector2d(2.0 * 2.0, 0.0)), 1.0, 1e-15);
  for (const double bad_k : {0.0, -1.0, kNaN, kInf}) {
    EXPECT_THROW(Ellipsoid<3>::FromCovariance(mean, covariance, bad_k), std::invalid_argument) << bad_k;
  }
  EXPECT_THROW(Ellipsoid<3>::FromCovariance(mean, -covariance, 1.0), std::invalid_argument);
}

TEST(EllipsoidTest, MahalanobisAndContainsOnKnownPoints) {
  // Axis-aligned: semi-axes 2 (x) and 1 (y) around (1, 2).
  const Ellipsoid<2> e(Eigen::Vector2d(1.0, 2.0), Eigen::Vector2d(4.0, 1.0).asDiagonal());
  EXPECT_DOUBLE_EQ(e.MahalanobisSquared(Eigen::Vector2d(1.0, 2.0)), 0.0);
  EXPECT_DOUBLE_EQ(e.MahalanobisSquared(Eigen::Vector2d(3.0, 2.0)), 1.0);
  EXPECT_DOUBLE_EQ(e.MahalanobisSquared(Eigen::Vector2d(1.0, 2.5)), 0.25);
  EXPECT_DOUBLE_EQ(e.MahalanobisSquared(Eigen::Vector2d(4.0, 2.0)), 2.25);
  EXPECT_TRUE(e.Contains(Eigen::Vector2d(3.0, 2.0)));
  EXPECT_TRUE(e.Contains(Eigen::Vector2d(1.0 + 2.0 * std::sqrt(0.5), 2.0 + std::sqrt(0.5))));
  EXPECT_FALSE(e.Contains(Eigen::Vector2d(3.0 + 1e-6, 2.0)));
  EXPECT_TRUE(e.Contains(Eigen::Vector2d(3.0 + 1e-6, 2.0), 1e-5));
  EXPECT_FALSE(e.Contains(Eigen::Vector2d(kNaN, 2.0)));
  // Rotated: P = R diag(9, 1) R^T; the point 3 along the rotated major axis is on the boundary.
  const double angle = 0.7;
  const Eigen::Matrix2d rotation = Eigen::Rotation2Dd(angle).toRotationMatrix();
  const Ellipsoid<2> rotated(Eigen::Vector2d::Zero(),
                             rotation * Eigen::Vector2d(9.0, 1.0).asDiagonal() * rotation.transpose());
  EXPECT_NEAR(rotated.MahalanobisSquared(3.0 * rotation.col(0)), 1.0, 1e-14);
  EXPECT_NEAR(rotated.MahalanobisSquared(0.5 * rotation.col(1)), 0.25, 1e-14);
}

TEST(EllipsoidTest, LogVolumeOfBallsMatchesClosedForm) {
  for (const int n : {1, 2, 3, 4, 7, 12}) {
    const double radius = 1.7;
    const Ellipsoid<Eigen::Dynamic> ball(Eigen::VectorXd::Ones(n),
                                         radius * radius * Eigen::MatrixXd::Identity(n, n));
    const double half_n = 0.5 * n;
    const double expected = half_n * std::log(std::numbers::pi) - std::lgamma(half_n + 1.0) + n * std::log(radius);
    EXPECT_NEAR(ball.LogVolume(), expected, 1e-12) << "n = " << n;
  }
  EXPECT_NEAR(Ellipsoid<2>(Eigen::Vector2d::Zero(), Eigen::Matrix2d::Identity()).LogVolume(),
              std::log(std::numbers::pi), 1e-15);
  EXPECT_NEAR(Ellipsoid<3>(Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity()).LogVolume(),
              std::log(4.0 / 3.0 * std::numbers::pi), 1e-15);
}

TEST(EllipsoidTest, LogVolumeIsHalfLogDeterminantPlusUnitBall) {
  std::mt19937_64 rng(7);
  const Eigen::MatrixXd shape = RandomSpd(5, rng);
  const Ellipsoid<Eigen::Dynamic> e(Eigen::VectorXd::Zero(5), shape);
  const Ellipsoid<Eigen::Dynamic> unit(Eigen::VectorXd::Zero(5), Eigen::MatrixXd::Identity(5, 5));
  EXPECT_NEAR(e.LogVolume() - unit.LogVolume(), 0.5 * std::log(shape.determinant()), 1e-12);
}

TEST(EllipsoidTest, ProjectIsThePrincipalSubmatrix) {
  std::mt19937_64 rng(11);
  const Eigen::Matrix<double, 12, 12> shape = RandomSpd(12, rng);
  Eigen::Matrix<double, 12, 1> center;
  for (int i = 0; i < 12; ++i) center(i) = 0.5 * i;
  const Ellipsoid<12> e(center, shape);

  const Ellipsoid<2> position = e.Project(std::array<int, 2>{0, 1});
  EXPECT_EQ(position.center(), center.head<2>());
  EXPECT_EQ(position.shape(), (shape.topLeftCorner<2, 2>()));
  const Ellipsoid<2> explicit_size = e.Project<2>({0, 1});
  EXPECT_EQ(explicit_size.shape(), position.shape());

  const Ellipsoid<Eigen::Dynamic> picked = e.Project(std::vector<int>{7, 2, 10});
  ASSERT_EQ(picked.dimension(), 3);
  const std::vector<int> index{7, 2, 10};
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(picked.center()(i), center(index[i]));
    for (int j = 0; j < 3; ++j) EXPECT_EQ(picked.shape()(i, j), shape(index[i], index[j]));
  }
}

TEST(EllipsoidTest, ProjectRejectsBadCoordinates) {
  const Ellipsoid<3> e(Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity());
  EXPECT_THROW(static_cast<void>(e.Project(std::vector<int>{})), std::invalid_argument);
  EXPECT_THROW(static_cast<void>(e.Project(std::vector<int>{0, 3})), std::invalid_argument);
  EXPECT_THROW(static_cast<void>(e.Project(std::vector<int>{-1})), std::invalid_argument);
  EXPECT_THROW(static_cast<void>(e.Project(std::vector<int>{1, 1})), std::invalid_argument);
  EXPECT_THROW(static_cast<void>(e.Project(std::array<int, 2>{2, 2})), std::invalid_argument);
  EXPECT_THROW(static_cast<void>(e.Project(std::array<int, 1>{5})), std::invalid_argument);
}

// The projection must contain the projection of every point of E and be tight: the point of E
// that maximizes y^T x (y in the subspace) projects onto its boundary. The Schur complement
// (the slice through the centre, Donati 2021's erratum) fails to contain the projected points.
TEST(EllipsoidTest, ProjectionContainsProjectedPointsAndSchurSliceDoesNot) {
  std::mt19937_64 rng(2024);
  const int n = 12;
  const Eigen::MatrixXd shape = RandomSpd(n, rng);
  const Eigen::VectorXd center = Eigen::VectorXd::LinSpaced(n, -1.0, 1.0);
  const Ellipsoid<Eigen::Dynamic> e(center, shape);
  const std::vector<int> kept{0, 1};
  const Ellipsoid<Eigen::Dynamic> projection = e.Project(kept);

  const Eigen::MatrixXd p_kk = shape.topLeftCorner(2, 2);
  const Eigen::MatrixXd p_kr = shape.topRightCorner(2, n - 2);
  const Eigen::MatrixXd p_rr = shape.bottomRightCorner(n - 2, n - 2);
  const Eigen::MatrixXd schur = p_kk - p_kr * p_rr.ldlt().solve(p_kr.transpose());
  const Ellipsoid<Eigen::Dynamic> slice(center.head(2), schur);

  int outside_slice = 0;
  const int samples = 20000;
  for (int k = 0; k < samples; ++k) {
    const Eigen::VectorXd x = center + e.cholesky_factor() * test::SampleUnitBall(n, rng);
    ASSERT_TRUE(e.Contains(x, 1e-12));
    ASSERT_TRUE(projection.Contains(x.head(2), 1e-12)) << "sample " << k;
    if (!slice.Contains(x.head(2), 1e-12)) ++outside_slice;
  }
  EXPECT_GT(outside_slice, samples / 10) << "the Schur-complement slice should miss many projections";

  // Tightness: for y in the plane, x* = c + P y / sqrt(y^T P y) is on the boundary of E and its
  // projection is on the boundary of the projection.
  for (int k = 0; k < 32; ++k) {
    const double angle = 2.0 * std::numbers::pi * k / 32.0;
    Eigen::VectorXd y = Eigen::VectorXd::Zero(n);
    y.head(2) << std::cos(angle), std::sin(angle);
    const Eigen::VectorXd extreme = center + shape * y / std::sqrt(y.dot(shape * y));
    EXPECT_NEAR(e.MahalanobisSquared(extreme), 1.0, 1e-10);
    EXPECT_NEAR(projection.MahalanobisSquared(extreme.head(2)), 1.0, 1e-10);
  }
}

}  // namespace
}  // namespace rowloc::geometry
