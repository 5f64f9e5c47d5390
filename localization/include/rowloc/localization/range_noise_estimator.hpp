// The range noise of the map-aided echoes, estimated online from their innovations (issue 28: the
// canopy's leaf roughness is not known in advance, and a range sigma of millimetres against leaves
// a few centimetres rough made the filter certain of wrong positions).
//
// Innovation-based adaptive estimation (Mehra 1972; Mohamed & Schwarz 1999: R = E[nu nu^T] -
// H P H^T), made robust with medians: an echo's innovation nu = d_m - r(x^-) has variance S =
// sigma_r^2 + S_rest, S_rest = H P H^T + the map's and the heading's terms (map_aided_ranging.hpp),
// and nu^2 / S is chi-square with one degree of freedom when the model is right. Over the last
// `window` echoes
//   sigma_r^2 = median(nu^2) / m_1 - median(S_rest),
// m_1 = 0.45494 the median of that chi-square; exact when S_rest is the same for all, low when it
// varies widely (by a third at sigma_r = 5 mm against S_rest spread over 0 to (1 cm)^2). The exact
// form (the v with median_i nu_i^2 / (v + S_rest,i) = m_1) was measured too, over 12 seeds of the
// gappy + leafy vineyard: the lane lost on 2 (none with this form), NEES median 320 (132). Echoes
// off leaves are correlated from one to the next (several echoes see the same leaves), which this
// estimate of one echo's variance does not describe. The result is clamped to
// [sigma_0^2, sigma_max^2]: sigma_0 the configured range sigma (the floor: the sensor's own noise)
// and sigma_max the cap, which is also the sigma used until `min_samples` echoes are counted (the
// roughest canopy is assumed until the echoes say otherwise: the first echoes after a GNSS
// initialisation, weighted at 3 mm against 3 cm of leaves, made the filter certain of an along-row
// position half a metre off). Medians, not means: a fifth of a gappy row's echoes come from another
// surface than the predicted one (through a gap, past a row's end); an innovation beyond
// kOtherSurfaceSigmas sigma_max is not roughness and is not counted at all.
#pragma once

#include <cstddef>
#include <vector>

namespace rowloc::localization {

class RangeNoiseEstimator {
 public:
  /// An innovation beyond this many sigma_max comes from another surface (not counted).
  static constexpr double kOtherSurfaceSigmas = 5.0;
  /// Median of the chi-square distribution with one degree of freedom.
  static constexpr double kChiSquare1Median = 0.454936423119572;

  /// configured_sigma_m: sigma_0 (> 0); max_sigma_m: sigma_max (>= sigma_0); window: echoes
  /// remembered (>= min_samples >= 1). Throws std::invalid_argument otherwise.
  RangeNoiseEstimator(double configured_sigma_m, double max_sigma_m, std::size_t window, std::size_t min_samples);
  /// One that keeps sigma_m() = sigma_m whatever it observes (the adaptation switched off).
  static RangeNoiseEstimator Fixed(double sigma_m);

  /// Counts one echo's innovation (m) and the rest of its variance S_rest (m^2). Non-finite or
  /// negative values and innovations beyond kOtherSurfaceSigmas sigma_max are not counted
  /// (returns false); nor is anything by a Fixed estimator.
  bool Observe(double innovation_m, double other_variance_m2);
  /// The range sigma to use now, m.
  double sigma_m() const { return sigma_m_; }
  std::size_t samples() const { return count_; }

 private:
  void Estimate();
  /// Median of a sorted vector (not empty).
  static double Median(const std::vector<double>& sorted);
  static void InsertSorted(std::vector<double>& sorted, double value);
  /// Removes one element equal to `value` (present: it entered through InsertSorted).
  static void EraseOne(std::vector<double>& sorted, double value);
  bool fixed_ = false;
  double configured_sigma_m_, max_sigma_m_;
  std::size_t window_, min_samples_;
  std::vector<double> squared_innovations_, other_variances_;  ///< rings of `window`
  /// The same values sorted, kept so as each echo moves the window (a median in O(window) moves
  /// of doubles instead of a selection: 1.4 us an echo with nth_element, bench/map_aided_bench).
  std::vector<double> sorted_squared_innovations_, sorted_other_variances_;
  std::size_t next_ = 0, count_ = 0;
  double sigma_m_;
};

}  // namespace rowloc::localization
