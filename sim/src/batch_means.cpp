#include "rowloc/sim/batch_means.hpp"

#include <boost/math/distributions/students_t.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rowloc::sim {

namespace {

void CheckFinite(const std::vector<double>& values, const char* what) {
  for (const double v : values) {
    if (!std::isfinite(v)) throw std::invalid_argument(std::string(what) + ": non-finite value");
  }
}

double Mean(const std::vector<double>& v) {
  double sum = 0.0;
  for (const double x : v) sum += x;
  return sum / static_cast<double>(v.size());
}

/// rho_lag of a centred sequence with sum of squares `energy` (> 0).
double Autocorrelation(const std::vector<double>& centred, double energy, std::size_t lag) {
  double sum = 0.0;
  for (std::size_t k = 0; k + lag < centred.size(); ++k) sum += centred[k] * centred[k + lag];
  return sum / energy;
}

std::vector<double> Centred(const std::vector<double>& v, double& energy) {
  const double mean = Mean(v);
  std::vector<double> c(v.size());
  energy = 0.0;
  for (std::size_t k = 0; k < v.size(); ++k) {
    c[k] = v[k] - mean;
    energy += c[k] * c[k];
  }
  return c;
}

}  // namespace

std::optional<BatchMeansInterval> BatchMeans(const std::vector<double>& values, std::size_t batch_count,
                                             double probability) {
  if (batch_count < 2) throw std::invalid_argument("BatchMeans: batch_count must be >= 2");
  if (!(probability > 0.0 && probability < 1.0)) throw std::invalid_argument("BatchMeans: probability must be in (0, 1)");
  CheckFinite(values, "BatchMeans");
  const std::size_t length = values.size() / batch_count;
  if (length < 2) return std::nullopt;
  BatchMeansInterval r;
  r.batch_count = batch_count;
  r.batch_length = length;
  r.probability = probability;
  std::vector<double> means(batch_count, 0.0);
  for (std::size_t b = 0; b < batch_count; ++b) {
    for (std::size_t k = 0; k < length; ++k) means[b] += values[b * length + k];
    means[b] /= static_cast<double>(length);
  }
  double energy = 0.0;
  const std::vector<double> centred = Centred(means, energy);
  r.mean = Mean(means);
  const double b = static_cast<double>(batch_count);
  const double standard_error = std::sqrt(energy / (b - 1.0) / b);
  const double t = boost::math::quantile(boost::math::students_t(b - 1.0), 0.5 * (1.0 + probability));
  r.lower = r.mean - t * standard_error;
  r.upper = r.mean + t * standard_error;
  r.batch_lag1_autocorrelation = energy > 0.0 ? Autocorrelation(centred, energy, 1) : 0.0;
  return r;
}

double IntegratedAutocorrelationTime(const std::vector<double>& values, std::size_t max_lag) {
  CheckFinite(values, "IntegratedAutocorrelationTime");
  if (values.size() < 3) return 1.0;
  double energy = 0.0;
  const std::vector<double> centred = Centred(values, energy);
  if (!(energy > 0.0)) return 1.0;
  double tau = 1.0;
  const std::size_t last = std::min(max_lag, values.size() - 1);
  for (std::size_t lag = 1; lag <= last; ++lag) {
    const double rho = Autocorrelation(centred, energy, lag);
    if (!(rho > 0.0)) break;
    tau += 2.0 * rho;
  }
  return tau;
}

}  // namespace rowloc::sim
