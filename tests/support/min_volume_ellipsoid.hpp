// Test-only brute-force reference: the minimum-volume ellipsoid containing a slab of the unit ball,
//   K = { u in R^n : |u| <= 1, lo <= u1 <= hi },   -1 <= lo < hi <= 1,
// found by numerical search, independently of the closed-form cut formulas (docs/ellipsoid.md).
//
// Every cut reduces to this case: map E to the unit ball (u = L^-1 (x - c)) and the cut normal to e1.
// K is a body of revolution about e1 and its minimum-volume (Löwner) ellipsoid is unique, hence also
// of revolution: (u1 - t)^2 / a^2 + |u_perp|^2 / b^2 <= 1. With p = 1/a, m = t/a, q = 1/b^2 it
// contains K iff, for every u1 in [lo, hi] (the cross-section of K at u1 is a disc of radius
// sqrt(1 - u1^2)),
//   G(u1) = 1 - (p u1 - m)^2 - q (1 - u1^2) >= 0.
// G is a quadratic in u1, so its minimum over [lo, hi] is exact (endpoints or vertex): no sampling.
// The constraints are jointly convex in (p, m, q), so the largest feasible q, q*(p, m) (found by
// bisection: G decreases in q), is concave, and the objective
//   log(vol / vol(unit ball)) = log a + (n - 1) log b = -log p - (n - 1)/2 log q*(p, m)
// is jointly convex in (p, m): nested golden-section searches (outer p, inner m) find its minimum.
// Bounds: a >= (hi - lo)/2 (length of K along e1), a <= n (hi - lo)/2 (the Löwner ellipsoid shrunk
// by 1/n about its centre lies in K), and |p u1 - m| <= 1 at u1 = lo, hi.
//
// Also samplers for containment tests: uniform points of the unit ball, uniform points of K, and
// points on the boundary of K (its rims and spherical zone, where containment is tight).
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>

namespace rowloc::test {

/// (u1 - center)^2 / axial^2 + |u_perp|^2 / radial^2 <= 1 in the normalized frame.
struct RevolutionEllipsoid {
  double center = 0.0;  ///< t, along e1
  double axial = 1.0;   ///< a, semi-axis along e1
  double radial = 1.0;  ///< b, semi-axis across e1
  double log_volume_ratio = 0.0;  ///< log(vol / vol(unit ball)) = log a + (n - 1) log b
};

namespace min_volume_detail {

/// Minimum over [lo, hi] of G(u1) = 1 - (p u1 - m)^2 - q (1 - u1^2) = k2 u1^2 + 2 p m u1 + k0.
inline double MinContainmentMargin(double p, double m, double q, double lo, double hi) {
  const auto g = [&](double u1) { return 1.0 - (p * u1 - m) * (p * u1 - m) - q * (1.0 - u1 * u1); };
  double smallest = std::min(g(lo), g(hi));
  const double k2 = q - p * p;
  if (k2 > 0.0) {
    const double vertex = -p * m / k2;  // dG/du1 = 2 k2 u1 + 2 p m = 0
    if (vertex > lo && vertex < hi) smallest = std::min(smallest, g(vertex));
  }
  return smallest;
}

/// The largest q with G >= 0 on [lo, hi] (0 when even q = 0 is infeasible).
inline double LargestRadialCurvature(double p, double m, double lo, double hi) {
  if (MinContainmentMargin(p, m, 0.0, lo, hi) < 0.0) return 0.0;
  // Any interior u1 bounds q: q <= (1 - (p u1 - m)^2) / (1 - u1^2); take the middle of [lo, hi].
  const double mid = 0.5 * (lo + hi);
  double infeasible = (1.0 - (p * mid - m) * (p * mid - m)) / (1.0 - mid * mid) * (1.0 + 1e-12) + 1e-300;
  double feasible = 0.0;
  for (int i = 0; i < 200 && infeasible - feasible > 1e-16 * infeasible; ++i) {
    const double q = 0.5 * (feasible + infeasible);
    (MinContainmentMargin(p, m, q, lo, hi) >= 0.0 ? feasible : infeasible) = q;
  }
  return feasible;
}

/// Golden-section minimum of a unimodal f on [left, right]; returns the argument.
inline double GoldenSectionArgMin(const std::function<double(double)>& f, double left, double right) {
  const double inv_phi = (std::sqrt(5.0) - 1.0) / 2.0;
  double x1 = right - inv_phi * (right - left);
  double x2 = left + inv_phi * (right - left);
  double f1 = f(x1);
  double f2 = f(x2);
  for (int i = 0; i < 200 && right - left > 1e-15 * (1.0 + std::abs(left) + std::abs(right)); ++i) {
    if (f1 <= f2) {
      right = x2;
      x2 = x1;
      f2 = f1;
      x1 = right - inv_phi * (right - left);
      f1 = f(x1);
    } else {
      left = x1;
      x1 = x2;
      f1 = f2;
      x2 = left + inv_phi * (right - left);
      f2 = f(x2);
    }
  }
  return f1 <= f2 ? x1 : x2;
}

}  // namespace min_volume_detail

/// Minimum-volume ellipsoid containing { |u| <= 1, lo <= u1 <= hi } in R^n (n >= 2).
inline RevolutionEllipsoid MinVolumeEllipsoidOfBallSlab(int n, double lo, double hi) {
  using namespace min_volume_detail;
  const double width = hi - lo;
  const auto log_ratio = [&](double p, double m) {
    const double q = LargestRadialCurvature(p, m, lo, hi);
    if (!(q > 0.0)) return std::numeric_limits<double>::infinity();
    return -std::log(p) - 0.5 * (n - 1) * std::log(q);
  };
  // For a given p, the m with |p u1 - m| <= 1 at both ends: [p hi - 1, p lo + 1].
  const auto best_m = [&](double p) {
    return GoldenSectionArgMin([&](double m) { return log_ratio(p, m); }, p * hi - 1.0, p * lo + 1.0);
  };
  const double p_min = 1.0 / (n * width);  // a <= n width / 2, with a factor 2 of margin
  const double p_max = 2.0 / width;        // a >= width / 2
  const double p = GoldenSectionArgMin([&](double pp) { return log_ratio(pp, best_m(pp)); }, p_min, p_max);
  const double m = best_m(p);
  const double q = LargestRadialCurvature(p, m, lo, hi);
  return RevolutionEllipsoid{m / p, 1.0 / p, 1.0 / std::sqrt(q), log_ratio(p, m)};
}

/// A point uniformly distributed in the unit ball of R^n (Gaussian direction, radius U^(1/n)).
inline Eigen::VectorXd SampleUnitBall(Eigen::Index n, std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform;
  Eigen::VectorXd direction(n);
  for (Eigen::Index i = 0; i < n; ++i) direction(i) = normal(rng);
  return direction.normalized() * std::pow(uniform(rng), 1.0 / static_cast<double>(n));
}

/// A point uniformly distributed in K = { |u| <= 1, lo <= e^T u <= hi } (e a unit vector, n >= 2,
/// -1 <= lo < hi <= 1): the height h = e^T u from its marginal density, proportional to
/// (1 - h^2)^((n-1)/2) (rejection from the uniform law on [lo, hi]), then a point uniform in the
/// (n-1)-ball of radius sqrt(1 - h^2) orthogonal to e. Exact even when K is a tiny part of the ball,
/// where rejecting unit-ball samples would almost never accept.
inline Eigen::VectorXd SampleBallSlab(const Eigen::VectorXd& e, double lo, double hi, std::mt19937_64& rng) {
  const double exponent = 0.5 * static_cast<double>(e.size() - 1);
  const double closest_to_zero = std::clamp(0.0, lo, hi);
  const double peak_density = std::pow(1.0 - closest_to_zero * closest_to_zero, exponent);
  std::uniform_real_distribution<double> height_law(lo, hi);
  std::uniform_real_distribution<double> uniform;
  double height = height_law(rng);
  while (uniform(rng) * peak_density > std::pow(1.0 - height * height, exponent)) height = height_law(rng);
  std::normal_distribution<double> normal;
  Eigen::VectorXd perpendicular(e.size());
  for (Eigen::Index i = 0; i < e.size(); ++i) perpendicular(i) = normal(rng);
  perpendicular = (perpendicular - perpendicular.dot(e) * e).normalized();
  const double radius = std::sqrt(1.0 - height * height) * std::pow(uniform(rng), 1.0 / static_cast<double>(e.size() - 1));
  return height * e + radius * perpendicular;
}

/// A random point on the boundary of K = { |u| <= 1, lo <= e^T u <= hi } (e a unit vector, n >= 2):
/// on the rim e^T u = lo or e^T u = hi with |u| = 1, or on the sphere |u| = 1 between them.
inline Eigen::VectorXd SampleBallSlabBoundary(const Eigen::VectorXd& e, double lo, double hi,
                                              std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  std::uniform_int_distribution<int> which(0, 2);
  std::uniform_real_distribution<double> uniform(lo, hi);
  Eigen::VectorXd perpendicular(e.size());
  for (Eigen::Index i = 0; i < e.size(); ++i) perpendicular(i) = normal(rng);
  perpendicular = (perpendicular - perpendicular.dot(e) * e).normalized();
  const int kind = which(rng);
  // Along e: a rim height, or (zone) a height drawn uniformly: not uniform on the zone, which the
  // containment check does not need.
  const double height = kind == 0 ? lo : (kind == 1 ? hi : uniform(rng));
  return height * e + std::sqrt(std::max(0.0, 1.0 - height * height)) * perpendicular;
}

}  // namespace rowloc::test
