// Chi-square bands from Boost.Math quantiles (see chi_square_bands.hpp).
#include "rowloc/sim/chi_square_bands.hpp"

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/normal.hpp>

#include <cmath>
#include <stdexcept>
#include <string>

namespace rowloc::sim {
namespace {
void CheckProbability(double probability) {
  if (!(probability > 0.0 && probability < 1.0)) {
    throw std::invalid_argument("probability must be in (0, 1), got " + std::to_string(probability));
  }
}
}  // namespace

ChiSquareBand ChiSquareInterval(double dof, double probability) {
  CheckProbability(probability);
  if (!(dof > 0.0) || !std::isfinite(dof)) {
    throw std::invalid_argument("chi-square degrees of freedom must be positive, got " + std::to_string(dof));
  }
  const boost::math::chi_squared dist(dof);
  return {boost::math::quantile(dist, (1.0 - probability) / 2.0),
          boost::math::quantile(dist, (1.0 + probability) / 2.0)};
}

ChiSquareBand TimeAveragedBand(double total_dof, std::size_t sample_count, double probability) {
  if (sample_count == 0) throw std::invalid_argument("time-averaged band of zero samples");
  const ChiSquareBand sum = ChiSquareInterval(total_dof, probability);
  const double n = static_cast<double>(sample_count);
  return {sum.lower / n, sum.upper / n};
}

double WhitenessBandHalfWidth(std::size_t sample_count, double probability) {
  CheckProbability(probability);
  if (sample_count == 0) throw std::invalid_argument("whiteness band of zero samples");
  const double z = boost::math::quantile(boost::math::normal(), (1.0 + probability) / 2.0);
  return z / std::sqrt(static_cast<double>(sample_count));
}

}  // namespace rowloc::sim
