// Tests of the cut statuses, degenerate inputs, the special cases (n = 1, one-sided slabs, the
// unchanged region) and the stable sigma across alpha == alpha_hat (docs/ellipsoid.md).
#include "rowloc/geometry/ellipsoid_cuts.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>

namespace rowloc::geometry {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

Ellipsoid<Eigen::Dynamic> UnitBall(int n) {
  return Ellipsoid<Eigen::Dynamic>(Eigen::VectorXd::Zero(n), Eigen::MatrixXd::Identity(n, n));
}
Eigen::VectorXd E1(int n) { return Eigen::VectorXd::Unit(n, 0); }

/// On the unit ball with g = e1 the depths are alpha = -beta_hi and alpha_hat = beta_lo.
CutResult<Eigen::Dynamic> SlabOnUnitBall(int n, double alpha, double alpha_hat) {
  return ParallelCut(UnitBall(n), E1(n), alpha_hat, -alpha);
}

Ellipsoid<2> TestEllipse() {
  Eigen::Matrix2d shape;
  shape << 4.0, 1.2, 1.2, 0.8;
  return Ellipsoid<2>(Eigen::Vector2d(3.0, -1.0), shape);
}

template <int N>
void ExpectSameEllipsoid(const Ellipsoid<N>& a, const Ellipsoid<N>& b, double tolerance) {
  EXPECT_LE((a.center() - b.center()).norm(), tolerance * (1.0 + b.center().norm()));
  EXPECT_LE((a.shape() - b.shape()).norm(), tolerance * b.shape().norm());
}

TEST(EllipsoidCutsTest, ToStringNamesEveryStatus) {
  EXPECT_EQ(std::string(ToString(CutStatus::kUpdated)), "updated");
  EXPECT_EQ(std::string(ToString(CutStatus::kUnchanged)), "unchanged");
  EXPECT_EQ(std::string(ToString(CutStatus::kEmpty)), "empty");
  EXPECT_EQ(std::string(ToString(CutStatus::kInvalidInput)), "invalid input");
}

TEST(EllipsoidCutsTest, CentralCutMatchesClassicParameters) {
  for (const int n : {2, 3, 12}) {
    const auto r = CentralCut(UnitBall(n), E1(n));
    ASSERT_EQ(r.status, CutStatus::kUpdated);
    EXPECT_EQ(r.alpha, 0.0);
    EXPECT_TRUE(std::isnan(r.alpha_hat));
    const double nd = n;
    EXPECT_NEAR(r.ellipsoid.center()(0), -1.0 / (nd + 1.0), 1e-15);
    const double delta = nd * nd / (nd * nd - 1.0);
    EXPECT_NEAR(r.ellipsoid.shape()(0, 0), delta * (1.0 - 2.0 / (nd + 1.0)), 1e-14);
    EXPECT_NEAR(r.ellipsoid.shape()(n - 1, n - 1), delta, 1e-14);
  }
  // Equal to a deep cut through the centre, on a general ellipse with |g| != 1.
  const auto e = TestEllipse();
  const Eigen::Vector2d g(0.3, -2.0);
  const auto central = CentralCut(e, g);
  const auto deep = DeepCut(e, g, g.dot(e.center()));
  ASSERT_EQ(central.status, CutStatus::kUpdated);
  ASSERT_EQ(deep.status, CutStatus::kUpdated);
  ExpectSameEllipsoid(central.ellipsoid, deep.ellipsoid, 1e-14);
}

TEST(EllipsoidCutsTest, DeepCutAtOrBelowMinusOneOverNIsUnchanged) {
  for (const int n : {2, 3, 12}) {
    const double nd = n;
    for (const double alpha : {-1.0 / nd, -0.5, -0.99, -1.0, -3.0}) {
      const auto r = DeepCut(UnitBall(n), E1(n), -alpha);
      EXPECT_EQ(r.status, CutStatus::kUnchanged) << "n = " << n << ", alpha = " << alpha;
      EXPECT_EQ(r.alpha, alpha);
      EXPECT_EQ(r.ellipsoid.shape(), Eigen::MatrixXd::Identity(n, n));
    }
    const auto shallow = DeepCut(UnitBall(n), E1(n), 1.0 / nd - 1e-3);
    ASSERT_EQ(shallow.status, CutStatus::kUpdated) << n;
    EXPECT_LT(shallow.ellipsoid.LogVolume(), UnitBall(n).LogVolume());
  }
}

TEST(EllipsoidCutsTest, DepthBeyondOneIsEmptyNeverClipped) {
  // Donati 2021 clips alpha > 1 to 1 (an erratum): that would return a single point. It is kEmpty.
  const auto e = TestEllipse();
  const Eigen::Vector2d g(1.5, 0.5);
  const double s = std::sqrt(g.dot(e.shape() * g));
  const double gc = g.dot(e.center());
  for (const double alpha : {1.0 + 1e-9, 1.5, 40.0}) {
    const auto deep = DeepCut(e, g, gc - alpha * s);
    EXPECT_EQ(deep.status, CutStatus::kEmpty) << alpha;
    EXPECT_NEAR(deep.alpha, alpha, 1e-12);
    EXPECT_EQ(deep.ellipsoid.shape(), e.shape());
    // Upper plane below E, lower plane above E: each side alone empties the slab.
    EXPECT_EQ(ParallelCut(e, g, gc - 3.0 * s, gc - alpha * s).status, CutStatus::kEmpty) << alpha;
    EXPECT_EQ(ParallelCut(e, g, gc + alpha * s, gc + 3.0 * s).status, CutStatus::kEmpty) << alpha;
  }
  EXPECT_EQ(DeepCut(e, g, gc - (1.0 - 1e-6) * s).status, CutStatus::kUpdated);
  // Exactly 1 (exact arithmetic on the unit ball): the plane touches E at one point only.
  EXPECT_EQ(DeepCut(UnitBall(3), E1(3), -1.0).status, CutStatus::kEmpty);
  EXPECT_EQ(ParallelCut(UnitBall(3), E1(3), 1.0, 2.0).status, CutStatus::kEmpty);
}

TEST(EllipsoidCutsTest, EmptyAndDegenerateSlabs) {
  const auto e = TestEllipse();
  const Eigen::Vector2d g(1.0, 1.0);
  const double gc = g.dot(e.center());
  EXPECT_EQ(ParallelCut(e, g, gc + 0.1, gc - 0.1).status, CutStatus::kEmpty);      // beta_lo > beta_hi
  EXPECT_EQ(ParallelCut(e, g, gc + 100.0, gc + 50.0).status, CutStatus::kEmpty);   // reversed, outside
  EXPECT_EQ(ParallelCut(e, g, gc + 100.0, gc + 200.0).status, CutStatus::kEmpty);  // both planes above E
  EXPECT_EQ(ParallelCut(e, g, gc - 200.0, gc - 100.0).status, CutStatus::kEmpty);  // both planes below E
  EXPECT_EQ(ParallelCut(e, g, gc - 200.0, gc + 200.0).status, CutStatus::kUnchanged);  // E inside the slab
  // A slab of zero width inside E has no full-dimensional bounding ellipsoid: invalid input.
  const auto flat = ParallelCut(e, g, gc + 0.2, gc + 0.2);
  EXPECT_EQ(flat.status, CutStatus::kInvalidInput);
  EXPECT_EQ(flat.ellipsoid.shape(), e.shape());
  // ... but a zero-width slab outside E is simply empty.
  EXPECT_EQ(ParallelCut(e, g, gc + 100.0, gc + 100.0).status, CutStatus::kEmpty);
}

TEST(EllipsoidCutsTest, ProductOfNegativeDepthsAtLeastOneOverNIsUnchanged) {
  for (const int n : {2, 3, 12}) {
    const double t = 1.0 / std::sqrt(static_cast<double>(n));
    EXPECT_EQ(SlabOnUnitBall(n, -t * (1.0 + 1e-12), -t * (1.0 + 1e-12)).status, CutStatus::kUnchanged) << n;
    EXPECT_EQ(SlabOnUnitBall(n, -0.99, -1.0 / (0.99 * n) - 1e-12).status, CutStatus::kUnchanged) << n;
    EXPECT_EQ(SlabOnUnitBall(n, -t + 1e-6, -t + 1e-6).status, CutStatus::kUpdated) << n;
  }
}

TEST(EllipsoidCutsTest, InvalidNormalsAndOffsets) {
  const auto e = TestEllipse();
  const Eigen::Vector2d g(1.0, 2.0);
  for (const Eigen::Vector2d& bad : {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(kNaN, 1.0),
                                     Eigen::Vector2d(1.0, kInf), Eigen::Vector2d(-kInf, 0.0)}) {
    EXPECT_EQ(CentralCut(e, bad).status, CutStatus::kInvalidInput);
    EXPECT_EQ(DeepCut(e, bad, 1.0).status, CutStatus::kInvalidInput);
    const auto r = ParallelCut(e, bad, -1.0, 1.0);
    EXPECT_EQ(r.status, CutStatus::kInvalidInput);
    EXPECT_TRUE(std::isnan(r.alpha));
    EXPECT_EQ(r.ellipsoid.center(), e.center());
  }
  for (const double bad : {kNaN, kInf, -kInf}) {
    EXPECT_EQ(DeepCut(e, g, bad).status, CutStatus::kInvalidInput);
    EXPECT_EQ(ParallelCut(e, g, bad, 1.0).status, CutStatus::kInvalidInput);
    EXPECT_EQ(ParallelCut(e, g, 0.0, bad).status, CutStatus::kInvalidInput);
  }
  // Dynamic size: a normal of the wrong dimension.
  const auto ball = UnitBall(3);
  EXPECT_EQ(CentralCut(ball, Eigen::VectorXd::Ones(2)).status, CutStatus::kInvalidInput);
  EXPECT_EQ(DeepCut(ball, Eigen::VectorXd::Ones(4), 0.0).status, CutStatus::kInvalidInput);
  EXPECT_EQ(ParallelCut(ball, Eigen::VectorXd(0), -1.0, 1.0).status, CutStatus::kInvalidInput);
}

TEST(EllipsoidCutsTest, TinyAndHugeNormalsAreNormalized) {
  const auto e = TestEllipse();
  const Eigen::Vector2d g(0.6, -0.8);
  const double gc = g.dot(e.center());
  const auto reference = ParallelCut(e, g, gc - 0.3, gc + 0.5);
  ASSERT_EQ(reference.status, CutStatus::kUpdated);
  for (const double k : {1e-200, 1e200}) {
    const auto scaled = ParallelCut(e, Eigen::Vector2d(k * g), k * (gc - 0.3), k * (gc + 0.5));
    ASSERT_EQ(scaled.status, CutStatus::kUpdated) << k;
    ExpectSameEllipsoid(scaled.ellipsoid, reference.ellipsoid, 1e-12);
  }
}

TEST(EllipsoidCutsTest, OneSideOutsideReducesToDeepCut) {
  const auto e = TestEllipse();
  const Eigen::Vector2d g(-0.7, 2.2);
  const double s = std::sqrt(g.dot(e.shape() * g));
  const double gc = g.dot(e.center());
  for (const double outside : {1.0, 1.5, 30.0}) {
    // Lower plane below E: the upper deep cut.
    const double beta_hi = gc - 0.3 * s;
    const auto slab = ParallelCut(e, g, gc - outside * s, beta_hi);
    const auto deep = DeepCut(e, g, beta_hi);
    ASSERT_EQ(slab.status, CutStatus::kUpdated);
    EXPECT_NEAR(slab.alpha_hat, -outside, 1e-12);  // reported as given, not clamped
    ExpectSameEllipsoid(slab.ellipsoid, deep.ellipsoid, 1e-13);
    // Upper plane above E: the lower deep cut, -g^T x <= -beta_lo.
    const double beta_lo = gc + 0.2 * s;
    const auto slab2 = ParallelCut(e, g, beta_lo, gc + outside * s);
    const auto deep2 = DeepCut(e, Eigen::Vector2d(-g), -beta_lo);
    ASSERT_EQ(slab2.status, CutStatus::kUpdated);
    ExpectSameEllipsoid(slab2.ellipsoid, deep2.ellipsoid, 1e-13);
  }
}

TEST(EllipsoidCutsTest, OneDimensionalCutsAreIntervalIntersections) {
  // E = [-1, 5]: centre 2, P = 9.
  const Ellipsoid<1> e(Eigen::Matrix<double, 1, 1>(2.0), Eigen::Matrix<double, 1, 1>(9.0));
  const auto expect_interval = [](const CutResult<1>& r, double lo, double hi) {
    ASSERT_EQ(r.status, CutStatus::kUpdated);
    EXPECT_NEAR(r.ellipsoid.center()(0), 0.5 * (lo + hi), 1e-14);
    EXPECT_NEAR(r.ellipsoid.shape()(0, 0), 0.25 * (hi - lo) * (hi - lo), 1e-14);
  };
  using V = Ellipsoid<1>::Vector;
  expect_interval(ParallelCut(e, V(1.0), 0.0, 10.0), 0.0, 5.0);
  expect_interval(ParallelCut(e, V(2.0), 1.0, 4.0), 0.5, 2.0);  // 1 <= 2x <= 4
  expect_interval(DeepCut(e, V(-2.0), -2.0), 1.0, 5.0);          // -2x <= -2
  expect_interval(CentralCut(e, V(1.0)), -1.0, 2.0);
  expect_interval(CentralCut(e, V(-0.1)), 2.0, 5.0);
  EXPECT_EQ(ParallelCut(e, V(1.0), -3.0, 7.0).status, CutStatus::kUnchanged);
  EXPECT_EQ(ParallelCut(e, V(1.0), -1.0, 5.0).status, CutStatus::kUnchanged);
  EXPECT_EQ(DeepCut(e, V(1.0), 5.0).status, CutStatus::kUnchanged);
  EXPECT_EQ(ParallelCut(e, V(1.0), 6.0, 8.0).status, CutStatus::kEmpty);
  EXPECT_EQ(DeepCut(e, V(1.0), -1.0).status, CutStatus::kEmpty);  // touches at one point
}

// A slab of half-width h (in units of E) leaves a thin axis of relative size ~h; the update
// P - sigma w w^T then cancels to ~eps / (1 - sigma) ~ eps / ((n - 1) h^2) relative accuracy along
// that axis (docs/ellipsoid.md): tight containment to 1e-9 down to h = 1e-3, PD and 1e-3 at 1e-6.
TEST(EllipsoidCutsTest, ThinSlabStaysPositiveDefinite) {
  for (const int n : {2, 3, 12}) {
    for (const auto& [half_width, tolerance] : {std::pair{1e-2, 1e-9}, std::pair{1e-3, 1e-9}, std::pair{1e-6, 1e-3}}) {
      const auto r = SlabOnUnitBall(n, -0.3 - half_width, 0.3 - half_width);
      ASSERT_EQ(r.status, CutStatus::kUpdated) << n << " " << half_width;
      EXPECT_GT(r.ellipsoid.cholesky_factor().diagonal().minCoeff(), 0.0);
      // The rims of the slab (u1 = 0.3 -+ h, |u| = 1) are inside.
      for (const double height : {0.3 - half_width, 0.3 + half_width}) {
        Eigen::VectorXd rim = Eigen::VectorXd::Zero(n);
        rim(0) = height;
        rim(n - 1) = std::sqrt(1.0 - height * height);
        EXPECT_TRUE(r.ellipsoid.Contains(rim, tolerance))
            << n << " " << half_width << " " << r.ellipsoid.MahalanobisSquared(rim) - 1.0;
      }
    }
  }
}

// The published sigma is 0/0 at alpha == alpha_hat; the rationalized form must be exact there,
// agree with the published form elsewhere and be continuous across the diagonal.
TEST(EllipsoidCutsTest, StableSigmaAgreesWithSpecFormAndCentredLimit) {
  for (const int n : {2, 3, 12}) {
    const double nd = n;
    for (double a = -1.0; a < 1.0; a += 0.0625) {
      for (double ah = -1.0; ah < 1.0; ah += 0.0625) {
        if (a + ah >= 0.0 || a * ah >= 1.0 / nd) continue;
        const CutParameters p = ParallelCutParameters(a, ah, n);
        ASSERT_TRUE(std::isfinite(p.tau) && std::isfinite(p.sigma) && std::isfinite(p.delta));
        if (std::abs(a - ah) > 1e-2) {
          const double rho = std::sqrt(4.0 * (1 - a * a) * (1 - ah * ah) + nd * nd * std::pow(ah * ah - a * a, 2));
          const double spec_sigma = (nd + 2.0 * (1.0 - a * ah - rho / 2.0) / ((a - ah) * (a - ah))) / (nd + 1.0);
          EXPECT_NEAR(p.sigma, spec_sigma, 1e-10) << n << " " << a << " " << ah;
        }
      }
    }
    for (const double t : {1e-3, 0.1, 0.25, 1.0 / std::sqrt(nd) - 1e-3}) {
      const CutParameters p = ParallelCutParameters(-t, -t, n);
      EXPECT_NEAR(p.sigma, (1.0 - nd * t * t) / (1.0 - t * t), 1e-14);
      EXPECT_EQ(p.tau, 0.0);
      EXPECT_NEAR(p.delta, nd * (1.0 - t * t) / (nd - 1.0), 1e-14);
    }
  }
  // Outside the domain every parameter is NaN (a clear error, not garbage).
  for (const auto& [a, ah] : {std::pair{1.0, -0.5}, std::pair{0.3, 0.3}, std::pair{-0.9, -0.9}, std::pair{kNaN, 0.0}}) {
    EXPECT_TRUE(std::isnan(ParallelCutParameters(a, ah, 2).sigma)) << a << " " << ah;
  }
  EXPECT_TRUE(std::isnan(ParallelCutParameters(-0.1, -0.1, 0).delta));
}

TEST(EllipsoidCutsTest, ContinuousAcrossAlphaEqualsAlphaHat) {
  for (const int n : {2, 3, 12}) {
    for (const double t : {0.05, 0.2, 0.5, 0.9}) {
      const auto centred = SlabOnUnitBall(n, -t, -t);
      if (t * t >= 1.0 / n) {
        EXPECT_EQ(centred.status, CutStatus::kUnchanged);
        continue;
      }
      ASSERT_EQ(centred.status, CutStatus::kUpdated);
      EXPECT_NEAR(centred.ellipsoid.center().norm(), 0.0, 1e-15);
      for (const double offset : {-1e-9, 1e-9}) {
        const auto near = SlabOnUnitBall(n, -t, -t + offset);
        ASSERT_EQ(near.status, CutStatus::kUpdated);
        ExpectSameEllipsoid(near.ellipsoid, centred.ellipsoid, 1e-7);
        const auto near2 = SlabOnUnitBall(n, -t + offset, -t);
        ExpectSameEllipsoid(near2.ellipsoid, centred.ellipsoid, 1e-7);
      }
    }
  }
}

TEST(EllipsoidCutsTest, NoNaNOnAFineGridOfDepths) {
  for (const int n : {2, 3, 12}) {
    const auto ball = UnitBall(n);
    const double log_volume = ball.LogVolume();
    int updated = 0;
    for (int i = -260; i <= 260; ++i) {
      for (int j = -260; j <= 260; ++j) {
        const double a = i * 0.005;
        const double ah = j * 0.005;
        const auto r = SlabOnUnitBall(n, a, ah);
        const double ca = std::max(a, -1.0);
        const double cah = std::max(ah, -1.0);
        CutStatus expected = CutStatus::kUpdated;
        if (a >= 1.0 || ah >= 1.0 || ca + cah > 0.0) {
          expected = CutStatus::kEmpty;
        } else if (i == -j) {
          expected = CutStatus::kInvalidInput;  // zero width
        } else if (ca * cah >= 1.0 / n) {
          expected = CutStatus::kUnchanged;
        }
        ASSERT_EQ(r.status, expected) << "n=" << n << " alpha=" << a << " alpha_hat=" << ah;
        if (r.status != CutStatus::kUpdated) continue;
        ++updated;
        ASSERT_TRUE(r.ellipsoid.center().allFinite() && r.ellipsoid.shape().allFinite())
            << "n=" << n << " alpha=" << a << " alpha_hat=" << ah;
        ASSERT_LE(r.ellipsoid.LogVolume(), log_volume + 1e-12) << "alpha=" << a << " alpha_hat=" << ah;
      }
    }
    EXPECT_GT(updated, 50000) << n;
  }
}

}  // namespace
}  // namespace rowloc::geometry
