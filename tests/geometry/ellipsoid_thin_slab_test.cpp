// Parallel cuts at their numerical edges (docs/ellipsoid.md, "Thin slabs"): slabs from 1 down to
// 1e-12 of the ellipsoid's extent along the normal, in 2, 3 and 12 dimensions, and planes tangent to
// the ellipsoid within rounding.
//
// Properties: the rims of E ∩ slab (where E+ of a thin slab touches) lie in E+ to 1e-9 at every
// width; 1 - sigma is computed without cancellation; E+ is flagged precision_limited only where
// double precision cannot hold the minimum and is then still a containing ellipsoid; a plane
// tangent to E within rounding is kEmpty, a cap of depth 1 - 1e-6 still a cut.
#include "rowloc/geometry/ellipsoid_cuts.hpp"

#include <Eigen/Householder>
#include <Eigen/QR>
#include <gtest/gtest.h>

#include "random_spd.hpp"

#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace rowloc::geometry {
namespace {

const std::vector<double> kWidths = {1.0, 0.3, 1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7,
                                     1e-8, 1.4e-8, 1e-9, 1e-10, 1e-11, 1e-12};

/// A random ellipsoid away from the origin and a random normal of arbitrary length.
template <int N>
std::pair<Ellipsoid<N>, typename Ellipsoid<N>::Vector> RandomProblem(int n, std::mt19937_64& rng) {
  using Vector = typename Ellipsoid<N>::Vector;
  std::normal_distribution<double> normal;
  Vector center(n);
  Vector g(n);
  for (int i = 0; i < n; ++i) {
    center(i) = 10.0 * normal(rng);
    g(i) = 2.5 * normal(rng);
  }
  return {Ellipsoid<N>(center, test::RandomSpd(n, rng, 0.1)), g};
}

/// Points of the rims of E ∩ slab, the circles |u_perp| = sqrt(1 - u1^2) at u1 = lo and u1 = hi of
/// the normalized frame (u = L^-1 (x - c), normal e = L^T g / s), mapped back to x.
template <int N>
std::vector<typename Ellipsoid<N>::Vector> RimPoints(const Ellipsoid<N>& e, const typename Ellipsoid<N>::Vector& g,
                                                     double lo, double hi, std::mt19937_64& rng) {
  using Vector = typename Ellipsoid<N>::Vector;
  const Eigen::Index n = e.dimension();
  const Eigen::MatrixXd l = e.cholesky_factor();
  Eigen::VectorXd normal = l.transpose() * g;
  normal.normalize();
  // An orthonormal basis whose first column is the normal.
  Eigen::MatrixXd seed = Eigen::MatrixXd::Identity(n, n);
  seed.col(0) = normal;
  const Eigen::MatrixXd basis = Eigen::HouseholderQR<Eigen::MatrixXd>(seed).householderQ();
  std::normal_distribution<double> gauss;
  std::vector<Vector> points;
  for (const double u1 : {std::max(lo, -1.0), std::min(hi, 1.0)}) {  // a plane outside E: its pole
    for (int k = 0; k < 200; ++k) {
      Eigen::VectorXd perp = Eigen::VectorXd::Zero(n);
      for (Eigen::Index i = 1; i < n; ++i) perp(i) = gauss(rng);
      perp *= std::sqrt(std::max(0.0, 1.0 - u1 * u1)) / perp.norm();
      Eigen::VectorXd u = basis * perp + u1 * basis.col(0) * (basis.col(0).dot(normal) > 0 ? 1.0 : -1.0);
      points.push_back(e.center() + l * u);
    }
  }
  return points;
}

template <int N>
void CheckThinSlabs(int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> centre_of_slab(-0.8, 0.8);
  for (int trial = 0; trial < 4; ++trial) {
    const auto [e, g] = RandomProblem<N>(n, rng);
    const double s = std::sqrt(g.dot(e.shape() * g));
    const double gc = g.dot(e.center());
    const double m = centre_of_slab(rng);
    for (const double width : kWidths) {
      const double lo = m - width / 2.0;  // normalized depths along the normal
      const double hi = m + width / 2.0;
      const std::string what = "n=" + std::to_string(n) + " trial=" + std::to_string(trial) +
                               " centre=" + std::to_string(m) + " width=" + std::to_string(width);
      const CutResult<N> cut = ParallelCut(e, g, gc + lo * s, gc + hi * s);
      if (-hi * lo >= 1.0 / n) continue;  // alpha alpha_hat >= 1/n: E itself is the minimum
      ASSERT_EQ(cut.status, CutStatus::kUpdated) << what;
      EXPECT_LT(cut.ellipsoid.LogVolume(), e.LogVolume()) << what;
      // The representable limit: above it the minimum itself, below it a containing ellipsoid.
      if (width >= 1e-3) {
        EXPECT_FALSE(cut.precision_limited) << what;
      }
      if (width <= 1e-10) {
        EXPECT_TRUE(cut.precision_limited) << what;
      }
      double worst = 0.0;
      for (const auto& x : RimPoints(e, g, lo, hi, rng)) worst = std::max(worst, cut.ellipsoid.MahalanobisSquared(x));
      EXPECT_LE(worst, 1.0 + 1e-9) << what;
      if (!cut.precision_limited && width <= 1e-2) {
        // Not (much) larger than the minimum: a thin slab's E+ touches its rims; the rounding
        // margin may widen the thin axis by up to 0.1 % before the result is flagged.
        EXPECT_GT(worst, 1.0 - 1e-3) << what;
      }
    }
  }
}

TEST(EllipsoidThinSlab, RimsStayInsideAtEveryWidth2D) { CheckThinSlabs<2>(2, 21); }
TEST(EllipsoidThinSlab, RimsStayInsideAtEveryWidth3D) { CheckThinSlabs<3>(3, 31); }
TEST(EllipsoidThinSlab, RimsStayInsideAtEveryWidth12DDynamic) { CheckThinSlabs<Eigen::Dynamic>(12, 121); }

TEST(EllipsoidThinSlab, OneMinusSigmaHasNoCancellation) {
  for (const int n : {2, 3, 12}) {
    const double nd = n;
    // Centred slab a = ah = -t: 1 - sigma = (n - 1) t^2 / (1 - t^2) exactly.
    for (const double t : {1e-12, 1e-9, 1e-6, 1e-3, 0.1}) {
      const CutParameters p = ParallelCutParameters(-t, -t, n);
      const double expected = (nd - 1.0) * t * t / ((1.0 - t) * (1.0 + t));
      EXPECT_NEAR(p.one_minus_sigma / expected, 1.0, 1e-13) << n << " " << t;
    }
    // Where 1 - sigma is not small, it equals 1 - sigma.
    for (double a = -1.0; a < 1.0; a += 0.0625) {
      for (double ah = -1.0; ah < 1.0; ah += 0.0625) {
        if (a + ah >= 0.0 || a * ah >= 1.0 / nd) continue;
        const CutParameters p = ParallelCutParameters(a, ah, n);
        EXPECT_NEAR(p.one_minus_sigma, 1.0 - p.sigma, 1e-13 * (1.0 + std::abs(p.sigma))) << n << " " << a << " " << ah;
      }
    }
    // Off-centre thin slab: against a long-double evaluation of the published form.
    for (const double width : {1e-4, 1e-7, 1e-10}) {
      const double m = 0.37;
      const CutParameters p = ParallelCutParameters(-(m + width / 2), m - width / 2, n);
      const long double a = -(m + width / 2), ah = m - width / 2, nl = n;
      const long double rho = std::sqrt(4.0L * (1 - a * a) * (1 - ah * ah) + nl * nl * std::pow(ah * ah - a * a, 2.0L));
      const long double d = 1.0L - a * ah + rho / 2.0L;
      const long double sigma = (nl + 2.0L * (1.0L - nl * nl * (a + ah) * (a + ah) / 4.0L) / d) / (nl + 1.0L);
      const long double reference = 1.0L - sigma;  // ~1e-19 relative rounding in long double
      if (width >= 1e-7) {
        EXPECT_NEAR(p.one_minus_sigma / static_cast<double>(reference), 1.0, 1e-4) << n << " " << width;
      }
      EXPECT_GT(p.one_minus_sigma, 0.0);
    }
  }
}

TEST(EllipsoidThinSlab, PlaneTangentWithinRoundingIsEmpty) {
  std::mt19937_64 rng(7);
  for (const int n : {2, 3, 12}) {
    for (int trial = 0; trial < 20; ++trial) {
      const auto [e, g] = RandomProblem<Eigen::Dynamic>(n, rng);
      const double s = std::sqrt(g.dot(e.shape() * g));
      const double gc = g.dot(e.center());
      // g^T x <= gc - s: the plane touches E at one point (depth 1, within the rounding of gc, s).
      for (const double ulp : {-4.0, -1.0, 0.0, 1.0, 4.0}) {
        const double beta = (gc - s) * (1.0 + ulp * std::numeric_limits<double>::epsilon());
        EXPECT_EQ(DeepCut(e, g, beta).status, CutStatus::kEmpty) << n << " " << trial << " " << ulp;
        EXPECT_EQ(ParallelCut(e, g, gc - 2.0 * s, beta).status, CutStatus::kEmpty) << n << " " << ulp;
        const double beta_lo = (gc + s) * (1.0 + ulp * std::numeric_limits<double>::epsilon());
        EXPECT_EQ(ParallelCut(e, g, beta_lo, gc + 2.0 * s).status, CutStatus::kEmpty) << n << " " << ulp;
      }
      // A genuine cap (depth 1 - 1e-6) is still a cut, and contains its apex.
      const CutResult<Eigen::Dynamic> cap = DeepCut(e, g, gc - (1.0 - 1e-6) * s);
      ASSERT_EQ(cap.status, CutStatus::kUpdated) << n;
      const Eigen::VectorXd apex = e.center() - e.shape() * g / s;
      EXPECT_LE(cap.ellipsoid.MahalanobisSquared(apex), 1.0 + 1e-6) << n;
    }
  }
}

}  // namespace
}  // namespace rowloc::geometry
