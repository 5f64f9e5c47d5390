// The mean of a serially correlated sequence and its confidence interval by batch means, for the
// time-averaged NEES and NIS of a filter run (docs/validation.md, "Consistency").
//
// The chi-square band of a time average (chi_square_bands.hpp; Lindgren et al. 2002, Eq. 43) holds for
// independent samples. A filter's NEES is correlated over the filter's time constant: at 10 Hz a
// correlation time of 10-20 s leaves a few dozen independent samples in thousands, and that band
// is then far too narrow to test anything. Batch means (Law, Simulation Modeling and Analysis,
// 5th ed., §9.5.3; Schmeiser 1982): cut the N samples into B consecutive batches of m = N / B
// samples (the last N mod B dropped); for batches long compared with the correlation time the
// batch means Y_b are nearly independent and nearly normal, so
//   mean +- t(B - 1, (1 + p) / 2) s_Y / sqrt(B),   s_Y^2 = sum_b (Y_b - mean)^2 / (B - 1)
// covers the sequence's expected value with probability about p. The lag-1 autocorrelation of
// the batch means is reported: near 0 when the batches are long enough (large values: the
// interval is too narrow).
// Integrated autocorrelation time (Sokal 1997, §3): tau = 1 + 2 sum_{l >= 1} rho_l over the
// initial positive sequence (until the first rho_l <= 0, at most max_lag lags); N / tau is the
// effective number of independent samples.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

namespace rowloc::sim {

struct BatchMeansInterval {
  std::size_t batch_count = 0;   ///< B
  std::size_t batch_length = 0;  ///< m samples per batch
  double mean = 0.0;             ///< of the B m samples used
  double lower = 0.0;            ///< the interval of the expected value
  double upper = 0.0;
  double batch_lag1_autocorrelation = 0.0;  ///< of the batch means
  double probability = 0.95;
  bool Contains(double x) const { return x >= lower && x <= upper; }
};

/// The batch-means interval of the expected value of `values`; nullopt when there are fewer than
/// 2 samples per batch. Throws std::invalid_argument for batch_count < 2, a probability outside
/// (0, 1) or a non-finite value.
std::optional<BatchMeansInterval> BatchMeans(const std::vector<double>& values, std::size_t batch_count = 20,
                                             double probability = 0.95);

/// tau >= 1 in samples (1 for fewer than 3 samples or a constant sequence). Throws
/// std::invalid_argument for a non-finite value.
double IntegratedAutocorrelationTime(const std::vector<double>& values, std::size_t max_lag = 1000);

}  // namespace rowloc::sim
