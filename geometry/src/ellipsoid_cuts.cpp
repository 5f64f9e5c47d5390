// Cut parameters tau, sigma, delta of the ellipsoid cuts (formulas and their derivation in
// ellipsoid_cuts.hpp and docs/ellipsoid.md).
#include "rowloc/geometry/ellipsoid_cuts.hpp"

#include <cmath>
#include <limits>

namespace rowloc::geometry {

const char* ToString(CutStatus status) {
  switch (status) {
    case CutStatus::kUpdated:
      return "updated";
    case CutStatus::kUnchanged:
      return "unchanged";
    case CutStatus::kEmpty:
      return "empty";
    case CutStatus::kInvalidInput:
      return "invalid input";
  }
  return "unknown";
}

CutParameters ParallelCutParameters(double alpha, double alpha_hat, Eigen::Index n) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  const double a = alpha;
  const double ah = alpha_hat;
  const double nd = static_cast<double>(n);
  const bool in_domain = n >= 1 && a >= -1.0 && a < 1.0 && ah >= -1.0 && ah < 1.0 && a + ah < 0.0 &&
                         a * ah < 1.0 / nd;
  if (!in_domain) return {kNaN, kNaN, kNaN, kNaN};
  if (n == 1) {
    // The interval [ah, -a] of the unit interval: centre (ah - a) / 2, half-width -(a + ah) / 2.
    return {(a - ah) / 2.0, 0.0, (a + ah) * (a + ah) / 4.0, 1.0};
  }
  // 1 - x^2 as (1 - x)(1 + x) and ah^2 - a^2 as (ah - a)(ah + a): no cancellation near |x| = 1.
  const double one_minus_a2 = (1.0 - a) * (1.0 + a);
  const double one_minus_ah2 = (1.0 - ah) * (1.0 + ah);
  const double difference_of_squares = (ah - a) * (ah + a);
  const double rho = std::sqrt(4.0 * one_minus_a2 * one_minus_ah2 +
                               nd * nd * difference_of_squares * difference_of_squares);
  // The published sigma = (n + 2 (1 - a ah - rho/2) / (a - ah)^2) / (n + 1), multiplied above and
  // below by (1 - a ah + rho/2) > 0: (1 - a ah)^2 - rho^2/4 = (a - ah)^2 [1 - n^2 (a + ah)^2 / 4].
  const double sum = a + ah;
  const double numerator = 1.0 - nd * nd * sum * sum / 4.0;
  const double denominator = 1.0 - a * ah + rho / 2.0;
  const double sigma = (nd + 2.0 * numerator / denominator) / (nd + 1.0);
  const double tau = sigma * (a - ah) / 2.0;
  const double delta =
      nd * nd / (nd * nd - 1.0) * (1.0 - (a * a + ah * ah - rho / nd) / 2.0);
  // 1 - sigma = (D - 2 numerator) / ((n + 1) D), where D - 2 numerator = rho/2 - (1 + a ah) +
  // n^2 sum^2 / 2 cancels for thin slabs. With E = 1 + a ah + rho/2 and
  // rho^2/4 - (1 + a ah)^2 = sum^2 [n^2 (ah - a)^2 / 4 - 1]:
  //   D - 2 numerator = sum^2 (n^2 (E/2 + (ah - a)^2 / 4) - 1) / E,
  // whose factor n^2 (E/2 + (ah - a)^2/4) - 1 tends to n^2 - 1 for a thin slab (no cancellation).
  const double e_plus = 1.0 + a * ah + rho / 2.0;
  const double difference = ah - a;
  const double one_minus_sigma =
      sum * sum * (nd * nd * (e_plus / 2.0 + difference * difference / 4.0) - 1.0) /
      (e_plus * denominator * (nd + 1.0));
  return {tau, sigma, delta, one_minus_sigma};
}

}  // namespace rowloc::geometry
