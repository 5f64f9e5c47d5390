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
  squared_innovations_[next_] = innovation_m * innovation_m;
  other_variances_[next_] = other_variance_m2;
  next_ = (next_ + 1) % window_;
  count_ = std::min(count_ + 1, window_);
  if (count_ >= min_samples_) Estimate();
  return true;
}

double RangeNoiseEstimator::Median(const std::vector<double>& values) {
  scratch_.assign(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(count_));
  const auto middle = scratch_.begin() + static_cast<std::ptrdiff_t>(count_ / 2);
  std::nth_element(scratch_.begin(), middle, scratch_.end());
  if (count_ % 2 == 1) return *middle;
  return 0.5 * (*middle + *std::max_element(scratch_.begin(), middle));
}

void RangeNoiseEstimator::Estimate() {
  const double variance = Median(squared_innovations_) / kChiSquare1Median - Median(other_variances_);
  const double floor = configured_sigma_m_ * configured_sigma_m_, cap = max_sigma_m_ * max_sigma_m_;
  sigma_m_ = std::sqrt(std::clamp(variance, floor, cap));
}

}  // namespace rowloc::localization
