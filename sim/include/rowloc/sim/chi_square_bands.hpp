// Chi-square acceptance bands of the filter-consistency tests (Lindgren et al. 2002, Eqs. 42-44).
//
// - Per sample: a consistent filter's NEES e' P^-1 e (or NIS v' S^-1 v) of dimension n is
//   chi2(n); its central interval of probability p is [Q(n, (1-p)/2), Q(n, (1+p)/2)], Q the
//   chi-square quantile.
// - Time average (Lindgren et al. 2002, Eq. 43): eps_bar = (1/N) sum_k eps_k; N eps_bar ~ chi2(sum_k n_k),
//   so its band is [Q(D, (1-p)/2), Q(D, (1+p)/2)] / N with D = sum_k n_k (= N n for a fixed n).
//   The seed approximates Q by Wilson-Hilferty (Eq. 44); we use the exact quantile from
//   Boost.Math (for N = 1099, n = 2 both give 1.883-2.120, the paper's 1.8831-2.1204).
// - Whiteness (Lindgren et al. 2002, after Eq. 42): for lag l > 0 the normalized autocorrelation of a white
//   zero-mean sequence of K samples is approximately N(0, 1/K); the band is +-z / sqrt(K) with
//   z = Phi^-1((1+p)/2) (1.95996 for p = 0.95). For whitened innovations of length m pass
//   K m samples (metrics.hpp explains why).
#pragma once

#include <cstddef>

namespace rowloc::sim {

/// A closed interval [lower, upper].
struct ChiSquareBand {
  double lower = 0.0;
  double upper = 0.0;
  bool Contains(double x) const { return x >= lower && x <= upper; }
};

/// Central interval of probability `probability` of chi2(dof). Throws std::invalid_argument for
/// dof <= 0 or probability outside (0, 1).
ChiSquareBand ChiSquareInterval(double dof, double probability = 0.95);

/// Band of the time average of sample_count statistics with total_dof degrees of freedom in all
/// (chi2(total_dof) interval divided by sample_count). Throws std::invalid_argument for
/// sample_count == 0 or total_dof <= 0.
ChiSquareBand TimeAveragedBand(double total_dof, std::size_t sample_count, double probability = 0.95);

/// Half-width z / sqrt(K) of the whiteness band of a normalized autocorrelation over
/// sample_count = K samples. Throws std::invalid_argument for K == 0.
double WhitenessBandHalfWidth(std::size_t sample_count, double probability = 0.95);

}  // namespace rowloc::sim
