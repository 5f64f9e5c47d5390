// Minimality of the cuts (docs/ellipsoid.md): in 2-D and 3-D (and 12-D) the closed-form E+ equals the
// minimum-volume ellipsoid of E ∩ cut found by an independent brute-force search
// (tests/support/min_volume_ellipsoid.hpp), which is itself first checked on known answers.
#include "rowloc/geometry/ellipsoid_cuts.hpp"

#include "min_volume_ellipsoid.hpp"

#include <gtest/gtest.h>

#include "random_spd.hpp"

#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace rowloc::geometry {
namespace {

TEST(MinVolumeReferenceTest, CentralCutKnownAnswer) {
  // Half ball: t = -1/(n+1), a = n/(n+1), b^2 = n^2/(n^2-1) (Khachiyan / Shor).
  for (const int n : {2, 3, 5, 12}) {
    const double nd = n;
    const auto r = test::MinVolumeEllipsoidOfBallSlab(n, -1.0, 0.0);
    EXPECT_NEAR(r.center, -1.0 / (nd + 1.0), 1e-7) << n;
    EXPECT_NEAR(r.axial, nd / (nd + 1.0), 1e-7) << n;
    EXPECT_NEAR(r.radial * r.radial, nd * nd / (nd * nd - 1.0), 1e-7) << n;
    EXPECT_NEAR(r.log_volume_ratio, std::log(nd / (nd + 1.0)) + 0.5 * (nd - 1.0) * std::log(nd * nd / (nd * nd - 1.0)), 1e-10);
  }
}

TEST(MinVolumeReferenceTest, SymmetricSlabKnownAnswers) {
  for (const int n : {2, 3, 12}) {
    const double nd = n;
    // |u1| <= t with t^2 >= 1/n: the ball itself.
    const double wide = 1.05 / std::sqrt(nd);
    const auto ball = test::MinVolumeEllipsoidOfBallSlab(n, -wide, wide);
    EXPECT_NEAR(ball.log_volume_ratio, 0.0, 1e-10) << n;
    EXPECT_NEAR(ball.axial, 1.0, 1e-6) << n;
    // |u1| <= t with t^2 < 1/n: through the four rims with a = sqrt(n) t, b^2 = n (1 - t^2)/(n - 1).
    const double t = 0.5 / std::sqrt(nd);
    const auto slab = test::MinVolumeEllipsoidOfBallSlab(n, -t, t);
    EXPECT_NEAR(slab.center, 0.0, 1e-8) << n;
    EXPECT_NEAR(slab.axial, std::sqrt(nd) * t, 1e-7) << n;
    EXPECT_NEAR(slab.radial * slab.radial, nd * (1.0 - t * t) / (nd - 1.0), 1e-7) << n;
  }
}

Eigen::MatrixXd RandomSpd(Eigen::Index n, std::mt19937_64& rng) {
  return test::RandomSpd(n, rng, 0.1);
}

/// Depth pairs (alpha, alpha_hat); alpha_hat = -1 is a deep cut, (0, -1) the central cut.
const std::vector<std::pair<double, double>> kDepths = {
    {0.0, -1.0},  {0.45, -1.0}, {-0.2, -1.0}, {0.95, -1.0}, {-0.25, -0.25}, {-0.05, -0.05},
    {0.2, -0.6},  {-0.7, 0.1},  {0.5, -0.55}, {-0.1, -0.5}, {0.3, -0.95},   {-0.9, -0.3},
    {-0.4, -0.1}, {0.7, -0.75}, {-0.3, 0.29}, {-2.0, 0.4},
};

/// The brute-force ellipsoid, mapped back from the normalized frame: c + t w and
/// b^2 P + (a^2 - b^2) w w^T with w = P g / s (u1 = e^T u, e = L^T g / s).
struct Expected {
  Eigen::VectorXd center;
  Eigen::MatrixXd shape;
  double log_volume;
};
Expected BruteForce(const Ellipsoid<Eigen::Dynamic>& e, const Eigen::VectorXd& g, double alpha, double alpha_hat) {
  const int n = static_cast<int>(e.dimension());
  const double s = std::sqrt(g.dot(e.shape() * g));
  const Eigen::VectorXd w = e.shape() * g / s;
  const auto r = test::MinVolumeEllipsoidOfBallSlab(n, std::max(alpha_hat, -1.0), std::min(-alpha, 1.0));
  const double a2 = r.axial * r.axial;
  const double b2 = r.radial * r.radial;
  return {e.center() + r.center * w, b2 * e.shape() + (a2 - b2) * w * w.transpose(),
          e.LogVolume() + r.log_volume_ratio};
}

void CheckMinimality(int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  for (const auto& [alpha, alpha_hat] : kDepths) {
    const std::string what = "n=" + std::to_string(n) + " alpha=" + std::to_string(alpha) +
                             " alpha_hat=" + std::to_string(alpha_hat);
    Eigen::VectorXd center(n);
    for (int i = 0; i < n; ++i) center(i) = 5.0 * normal(rng);
    const Ellipsoid<Eigen::Dynamic> e(center, RandomSpd(n, rng));
    // |g| != 1 and g^T P g != 1: dividing the update by s instead of s^2 would change it.
    Eigen::VectorXd g(n);
    do {
      for (int i = 0; i < n; ++i) g(i) = 3.0 * normal(rng);
    } while (std::abs(g.norm() - 1.0) < 0.1 || std::abs(g.dot(e.shape() * g) - 1.0) < 0.1);
    const double s = std::sqrt(g.dot(e.shape() * g));
    const double gc = g.dot(center);
    const auto r = alpha_hat == -1.0 ? DeepCut(e, g, gc - alpha * s)
                                     : ParallelCut(e, g, gc + alpha_hat * s, gc - alpha * s);
    const Expected expected = BruteForce(e, g, alpha, alpha_hat);
    if (r.status == CutStatus::kUnchanged) {
      EXPECT_NEAR(expected.log_volume, e.LogVolume(), 1e-9) << what << ": brute force found a smaller one";
      continue;
    }
    ASSERT_EQ(r.status, CutStatus::kUpdated) << what;
    // Relative volume within 1e-6; centre within 1e-6 of E's size (Mahalanobis in E).
    EXPECT_NEAR(r.ellipsoid.LogVolume(), expected.log_volume, 1e-6) << what;
    const double center_error =
        e.cholesky_factor().triangularView<Eigen::Lower>().solve(expected.center - r.ellipsoid.center()).norm();
    EXPECT_LT(center_error, 1e-6) << what;
    EXPECT_LT((r.ellipsoid.shape() - expected.shape).norm(), 1e-6 * e.shape().norm()) << what;
  }
}

TEST(EllipsoidMinimalityTest, CutsAreMinimumVolume2D) { CheckMinimality(2, 1); }
TEST(EllipsoidMinimalityTest, CutsAreMinimumVolume3D) { CheckMinimality(3, 2); }
TEST(EllipsoidMinimalityTest, CutsAreMinimumVolume12D) { CheckMinimality(12, 3); }

TEST(EllipsoidMinimalityTest, FixedSizeCutsMatchDynamicOnes) {
  std::mt19937_64 rng(9);
  const Eigen::Matrix3d shape = RandomSpd(3, rng);
  const Eigen::Vector3d center(1.0, -2.0, 0.5);
  const Eigen::Vector3d g(0.4, 2.0, -1.1);
  const auto fixed = ParallelCut(Ellipsoid<3>(center, shape), g, -1.0, 0.8);
  const auto dynamic = ParallelCut(Ellipsoid<Eigen::Dynamic>(center, shape), Eigen::VectorXd(g), -1.0, 0.8);
  ASSERT_EQ(fixed.status, CutStatus::kUpdated);
  ASSERT_EQ(dynamic.status, CutStatus::kUpdated);
  EXPECT_TRUE(fixed.ellipsoid.shape().isApprox(dynamic.ellipsoid.shape(), 1e-14));
  EXPECT_TRUE(fixed.ellipsoid.center().isApprox(dynamic.ellipsoid.center(), 1e-14));
}

// The shape update of Donati 2021 (divided by s instead of s^2, an erratum) is not the minimum.
TEST(EllipsoidMinimalityTest, ErroneousSDivisionIsNotMinimal) {
  std::mt19937_64 rng(4);
  const int n = 3;
  const Ellipsoid<Eigen::Dynamic> e(Eigen::VectorXd::Zero(n), RandomSpd(n, rng));
  const Eigen::VectorXd g = Eigen::Vector3d(0.1, 0.2, -0.15);
  const double s = std::sqrt(g.dot(e.shape() * g));
  ASSERT_LT(s, 0.9);
  const auto r = ParallelCut(e, g, -0.3 * s, 0.5 * s);
  ASSERT_EQ(r.status, CutStatus::kUpdated);
  const Expected expected = BruteForce(e, g, -0.5, -0.3);
  EXPECT_NEAR(r.ellipsoid.LogVolume(), expected.log_volume, 1e-6);
  const CutParameters p = ParallelCutParameters(-0.5, -0.3, n);
  const Eigen::VectorXd p_g = e.shape() * g;
  const Eigen::MatrixXd wrong = p.delta * (e.shape() - p.sigma * p_g * p_g.transpose() / s);
  const Ellipsoid<Eigen::Dynamic> wrong_e(r.ellipsoid.center(), wrong);
  EXPECT_GT(wrong_e.LogVolume() - expected.log_volume, 1e-2);
}

}  // namespace
}  // namespace rowloc::geometry
