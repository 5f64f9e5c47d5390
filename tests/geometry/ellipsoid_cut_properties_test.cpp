// Property tests of every cut in 2-D, 3-D and 12-D (fixed and dynamic size), docs/ellipsoid.md:
// points of E ∩ cut lie in E+, vol(E+) <= vol(E), invariance to scaling g and to affine changes of
// coordinates, and the s-versus-s^2 erratum of the shape update (Donati 2021's, not copied).
#include "rowloc/geometry/ellipsoid_cuts.hpp"

#include "min_volume_ellipsoid.hpp"

#include <Eigen/LU>
#include <gtest/gtest.h>

#include "random_spd.hpp"

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace rowloc::geometry {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

enum class Kind { kCentral, kDeep, kParallel };

/// A cut given by its depths in units of E (alpha_hat = -inf: no lower plane).
struct CutCase {
  Kind kind;
  double alpha;
  double alpha_hat;
};

// Central, deep (through, before and behind the centre, near the far edge) and parallel cuts
// (centred, off-centre, crossing the centre, thin, one side outside E).
const std::vector<CutCase> kCases = {
    {Kind::kCentral, 0.0, -kInf},      {Kind::kDeep, 0.4, -kInf},       {Kind::kDeep, -0.05, -kInf},
    {Kind::kDeep, 0.9, -kInf},         {Kind::kParallel, -0.2, -0.2},   {Kind::kParallel, 0.2, -0.6},
    {Kind::kParallel, -0.7, 0.1},      {Kind::kParallel, -0.05, -0.05}, {Kind::kParallel, 0.5, -0.55},
    {Kind::kParallel, -1.5, 0.3},      {Kind::kParallel, 0.35, -3.0},   {Kind::kParallel, -0.02, -0.9},
};

std::string Describe(int n, const CutCase& c) {
  return "n=" + std::to_string(n) + " kind=" + std::to_string(static_cast<int>(c.kind)) +
         " alpha=" + std::to_string(c.alpha) + " alpha_hat=" + std::to_string(c.alpha_hat);
}

Eigen::MatrixXd RandomSpd(Eigen::Index n, std::mt19937_64& rng) {
  return test::RandomSpd(n, rng, 0.1);
}

/// A random ellipsoid and a random normal with |g| != 1 and g^T P g != 1 (so that dividing the
/// shape update by s instead of s^2 changes the result).
template <int N>
std::pair<Ellipsoid<N>, typename Ellipsoid<N>::Vector> RandomProblem(int n, std::mt19937_64& rng) {
  using Vector = typename Ellipsoid<N>::Vector;
  std::normal_distribution<double> normal;
  Vector center(n);
  for (int i = 0; i < n; ++i) center(i) = 10.0 * normal(rng);
  const Ellipsoid<N> e(center, RandomSpd(n, rng));
  Vector g(n);
  do {
    for (int i = 0; i < n; ++i) g(i) = 2.5 * normal(rng);
  } while (std::abs(g.norm() - 1.0) < 0.1 || std::abs(g.dot(e.shape() * g) - 1.0) < 0.1);
  return {e, g};
}

struct Planes {
  double beta_lo;  ///< -inf when there is no lower plane
  double beta_hi;
};

template <int N>
Planes PlanesOf(const Ellipsoid<N>& e, const typename Ellipsoid<N>::Vector& g, const CutCase& c) {
  const double s = std::sqrt(g.dot(e.shape() * g));
  const double gc = g.dot(e.center());
  return {c.kind == Kind::kParallel ? gc + c.alpha_hat * s : -kInf, gc - c.alpha * s};
}

template <int N>
CutResult<N> Apply(const Ellipsoid<N>& e, const typename Ellipsoid<N>::Vector& g, const CutCase& c) {
  const Planes planes = PlanesOf(e, g, c);
  switch (c.kind) {
    case Kind::kCentral:
      return CentralCut(e, g);
    case Kind::kDeep:
      return DeepCut(e, g, planes.beta_hi);
    case Kind::kParallel:
      return ParallelCut(e, g, planes.beta_lo, planes.beta_hi);
  }
  return CentralCut(e, g);
}

/// 10^4 points uniform in E ∩ cut and 2000 points on its boundary lie in the result; its volume
/// is not larger (strictly smaller when updated).
template <int N>
void CheckContainmentAndVolume(int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  for (const CutCase& c : kCases) {
    const auto [e, g] = RandomProblem<N>(n, rng);
    const CutResult<N> r = Apply(e, g, c);
    ASSERT_TRUE(r.status == CutStatus::kUpdated || r.status == CutStatus::kUnchanged) << Describe(n, c);
    EXPECT_LE(r.ellipsoid.LogVolume(), e.LogVolume() + 1e-12) << Describe(n, c);
    if (r.status == CutStatus::kUpdated) {
      EXPECT_LT(r.ellipsoid.LogVolume(), e.LogVolume()) << Describe(n, c);
    }

    // Uniform in E ∩ cut: uniform in the normalized slab K (u1 along e = L^T g / s), mapped by
    // x = c + L u, and checked against the cut itself (which validates the sampler).
    const Planes planes = PlanesOf(e, g, c);
    const Eigen::MatrixXd l = e.cholesky_factor();
    const Eigen::VectorXd center = e.center();
    const double s = std::sqrt(g.dot(e.shape() * g));
    const Eigen::VectorXd unit_normal = l.transpose() * g / s;
    const double lo = std::max(-1.0, (planes.beta_lo - g.dot(center)) / s);
    const double hi = std::min(1.0, (planes.beta_hi - g.dot(center)) / s);
    const double slack = 1e-9 * s;
    for (int k = 0; k < 10000; ++k) {
      const Eigen::VectorXd x = center + l * test::SampleBallSlab(unit_normal, lo, hi, rng);
      ASSERT_TRUE(e.Contains(x, 1e-9));
      ASSERT_TRUE(g.dot(x) <= planes.beta_hi + slack && g.dot(x) >= planes.beta_lo - slack);
      ASSERT_TRUE(r.ellipsoid.Contains(x, 1e-9)) << Describe(n, c) << " sample " << k;
    }
    // Boundary of E ∩ cut (rims and spherical zone), where containment is tight.
    for (int k = 0; k < 2000; ++k) {
      const Eigen::VectorXd x = center + l * test::SampleBallSlabBoundary(unit_normal, lo, hi, rng);
      ASSERT_TRUE(r.ellipsoid.Contains(x, 1e-9)) << Describe(n, c) << " boundary point " << k;
    }
  }
}

TEST(EllipsoidCutPropertiesTest, ContainsIntersectionAndShrinks2D) { CheckContainmentAndVolume<2>(2, 101); }
TEST(EllipsoidCutPropertiesTest, ContainsIntersectionAndShrinks3D) { CheckContainmentAndVolume<3>(3, 202); }
TEST(EllipsoidCutPropertiesTest, ContainsIntersectionAndShrinks12D) { CheckContainmentAndVolume<12>(12, 303); }
TEST(EllipsoidCutPropertiesTest, ContainsIntersectionAndShrinksDynamic12D) {
  CheckContainmentAndVolume<Eigen::Dynamic>(12, 404);
}

template <int N>
void ExpectSameEllipsoid(const Ellipsoid<N>& a, const Ellipsoid<N>& b, double tolerance, const std::string& what) {
  EXPECT_LE((a.center() - b.center()).norm(), tolerance * (1.0 + b.center().norm())) << what;
  EXPECT_LE((a.shape() - b.shape()).norm(), tolerance * b.shape().norm()) << what;
}

template <int N>
void CheckScalingInvariance(int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  for (const CutCase& c : kCases) {
    const auto [e, g] = RandomProblem<N>(n, rng);
    const CutResult<N> reference = Apply(e, g, c);
    const Planes planes = PlanesOf(e, g, c);
    for (const double k : {1e-9, 0.37, 3.0, 2.5e7}) {
      const typename Ellipsoid<N>::Vector kg = k * g;
      CutResult<N> scaled = CentralCut(e, kg);
      if (c.kind == Kind::kDeep) scaled = DeepCut(e, kg, k * planes.beta_hi);
      if (c.kind == Kind::kParallel) scaled = ParallelCut(e, kg, k * planes.beta_lo, k * planes.beta_hi);
      ASSERT_EQ(scaled.status, reference.status) << Describe(n, c) << " k=" << k;
      ExpectSameEllipsoid(scaled.ellipsoid, reference.ellipsoid, 1e-11, Describe(n, c));
      EXPECT_NEAR(scaled.alpha, reference.alpha, 1e-11);
    }
  }
}

TEST(EllipsoidCutPropertiesTest, InvariantToScalingTheNormal) {
  CheckScalingInvariance<2>(2, 11);
  CheckScalingInvariance<3>(3, 12);
  CheckScalingInvariance<12>(12, 13);
}

/// x -> y = A x + b maps E(c, P) to E(A c + b, A P A^T) and {g^T x <= beta} to
/// {(A^-T g)^T y <= beta + (A^-T g)^T b}: cutting then mapping equals mapping then cutting.
template <int N>
void CheckAffineInvariance(int n, std::uint64_t seed) {
  using Vector = typename Ellipsoid<N>::Vector;
  using Matrix = typename Ellipsoid<N>::Matrix;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  for (const CutCase& c : kCases) {
    const auto [e, g] = RandomProblem<N>(n, rng);
    Matrix a(n, n);
    Vector b(n);
    for (int i = 0; i < n; ++i) {
      b(i) = 5.0 * normal(rng);
      for (int j = 0; j < n; ++j) a(i, j) = normal(rng) + (i == j ? 3.0 : 0.0);
    }
    const Ellipsoid<N> mapped_e(a * e.center() + b, a * e.shape() * a.transpose());
    const Vector mapped_g = a.transpose().partialPivLu().solve(g);
    const Planes planes = PlanesOf(e, g, c);
    const double shift = mapped_g.dot(b);
    CutResult<N> cut_then_map = Apply(e, g, c);
    CutResult<N> map_then_cut = CentralCut(mapped_e, mapped_g);
    if (c.kind == Kind::kDeep) map_then_cut = DeepCut(mapped_e, mapped_g, planes.beta_hi + shift);
    if (c.kind == Kind::kParallel) {
      map_then_cut = ParallelCut(mapped_e, mapped_g, planes.beta_lo + shift, planes.beta_hi + shift);
    }
    ASSERT_EQ(map_then_cut.status, cut_then_map.status) << Describe(n, c);
    const Ellipsoid<N> expected(a * cut_then_map.ellipsoid.center() + b,
                                a * cut_then_map.ellipsoid.shape() * a.transpose());
    ExpectSameEllipsoid(map_then_cut.ellipsoid, expected, 1e-9, Describe(n, c));
  }
}

TEST(EllipsoidCutPropertiesTest, CommutesWithAffineChangeOfCoordinates) {
  CheckAffineInvariance<2>(2, 21);
  CheckAffineInvariance<3>(3, 22);
  CheckAffineInvariance<12>(12, 23);
  CheckAffineInvariance<Eigen::Dynamic>(7, 24);
}

// Donati 2021 eq. (3.12) divides (P g)(P g)^T by s = sqrt(g^T P g) instead of s^2 (an erratum). With
// g^T P g = 4 the erroneous ellipse is not even positive definite; with g^T P g = 1/4 it is too
// large (not minimal); ours contains the half-ellipse and has the known minimum volume.
TEST(EllipsoidCutPropertiesTest, ShapeUpdateDividesBySSquaredNotS) {
  Eigen::Matrix2d shape;
  shape << 3.0, 1.0, 1.0, 2.0;
  const Ellipsoid<2> e(Eigen::Vector2d(1.0, 2.0), shape);
  const Eigen::Vector2d direction(0.6, 0.8);
  const double unit_s2 = direction.dot(shape * direction);
  std::mt19937_64 rng(5);
  for (const double target_s2 : {4.0, 0.25}) {
    const Eigen::Vector2d g = direction * std::sqrt(target_s2 / unit_s2);
    const double s = std::sqrt(g.dot(shape * g));
    ASSERT_NEAR(s * s, target_s2, 1e-12);
    const auto r = CentralCut(e, g);
    ASSERT_EQ(r.status, CutStatus::kUpdated);
    // Central cut in 2-D: vol(E+)/vol(E) = delta sqrt(1 - sigma) = (4/3) sqrt(1/3).
    EXPECT_NEAR(r.ellipsoid.LogVolume() - e.LogVolume(), std::log(4.0 / 3.0 * std::sqrt(1.0 / 3.0)), 1e-12);
    const Eigen::Vector2d p_g = shape * g;
    const Eigen::Matrix2d wrong = 4.0 / 3.0 * (shape - 2.0 / 3.0 * p_g * p_g.transpose() / s);
    const Eigen::Matrix2d right = 4.0 / 3.0 * (shape - 2.0 / 3.0 * p_g * p_g.transpose() / (s * s));
    EXPECT_TRUE(r.ellipsoid.shape().isApprox(right, 1e-13));
    const Eigen::LLT<Eigen::Matrix2d> wrong_llt(wrong);
    if (target_s2 > 1.0) {
      EXPECT_NE(wrong_llt.info(), Eigen::Success) << "the erratum gives an indefinite 'ellipse' here";
    } else {
      ASSERT_EQ(wrong_llt.info(), Eigen::Success);
      const Ellipsoid<2> wrong_e(r.ellipsoid.center(), wrong);
      EXPECT_GT(wrong_e.LogVolume() - r.ellipsoid.LogVolume(), 0.1) << "the erratum is not minimal";
    }
    for (int k = 0; k < 10000; ++k) {
      const Eigen::Vector2d x = e.center() + e.cholesky_factor() * test::SampleUnitBall(2, rng);
      if (g.dot(x - e.center()) <= 0.0) {
        ASSERT_TRUE(r.ellipsoid.Contains(x, 1e-9));
      }
    }
  }
}

}  // namespace
}  // namespace rowloc::geometry
