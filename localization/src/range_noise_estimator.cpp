#include "rowloc/localization/range_noise_estimator.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rowloc::localization {

RangeNoiseEstimator::RangeNoiseEstimator(double configured_sigma_m, double max_sigma_m, std::size_t window,
                                         std::size_t min_samples)
    : configured_sigma_m_(configured_sigma_m),
      max_sigma_m_(max_sigma_m),
      window_(window),
      min_samples_(min_samples),
      sigma_m_(max_sigma_m) {
  if (!(std::isfinite(configured_sigma_m) && configured_sigma_m > 0.0)) {
    throw std::invalid_argument("RangeNoiseEstimator: the configured range sigma must be finite and > 0");
  }
  if (!(std::isfinite(max_sigma_m) && max_sigma_m >= configured_sigma_m)) {
    throw std::invalid_argument("RangeNoiseEstimator: the largest range sigma must be finite and >= the configured one");
  }
  if (min_samples < 1 || window < min_samples) {
    throw std::invalid_argument("RangeNoiseEstimator: need window >= min_samples >= 1");
  }
  squared_innovations_.assign(window, 0.0);
  other_variances_.assign(window, 0.0);
  sorted_squared_innovations_.reserve(window);
  sorted_other_variances_.reserve(window);
}

RangeNoiseEstimator RangeNoiseEstimator::Fixed(double sigma_m) {
  RangeNoiseEstimator fixed(sigma_m, sigma_m, 1, 1);
  fixed.fixed_ = true;
  return fixed;
}

bool RangeNoiseEstimator::Observe(double innovation_m, double other_variance_m2) {
  if (fixed_) return false;
  if (!std::isfinite(innovation_m) || !std::isfinite(other_variance_m2) || other_variance_m2 < 0.0) return false;
  if (std::abs(innovation_m) > kOtherSurfaceSigmas * max_sigma_m_) return false;
  const double squared = innovation_m * innovation_m;
  if (count_ == window_) {  // the oldest leaves the window
    EraseOne(sorted_squared_innovations_, squared_innovations_[next_]);
    EraseOne(sorted_other_variances_, other_variances_[next_]);
  }
  squared_innovations_[next_] = squared;
  other_variances_[next_] = other_variance_m2;
  InsertSorted(sorted_squared_innovations_, squared);
  InsertSorted(sorted_other_variances_, other_variance_m2);
  next_ = (next_ + 1) % window_;
  count_ = std::min(count_ + 1, window_);
  if (count_ >= min_samples_) Estimate();
  return true;
}

void RangeNoiseEstimator::InsertSorted(std::vector<double>& sorted, double value) {
  sorted.insert(std::upper_bound(sorted.begin(), sorted.end(), value), value);
}

void RangeNoiseEstimator::EraseOne(std::vector<double>& sorted, double value) {
  const auto it = std::lower_bound(sorted.begin(), sorted.end(), value);
  if (it != sorted.end() && *it == value) sorted.erase(it);
}

double RangeNoiseEstimator::Median(const std::vector<double>& sorted) {
  const std::size_t n = sorted.size();
  if (n % 2 == 1) return sorted[n / 2];
  return 0.5 * (sorted[n / 2] + sorted[n / 2 - 1]);
}

void RangeNoiseEstimator::Estimate() {
  const double variance = Median(sorted_squared_innovations_) / kChiSquare1Median - Median(sorted_other_variances_);
  const double floor = configured_sigma_m_ * configured_sigma_m_, cap = max_sigma_m_ * max_sigma_m_;
  sigma_m_ = std::sqrt(std::clamp(variance, floor, cap));
}

}  // namespace rowloc::localization
