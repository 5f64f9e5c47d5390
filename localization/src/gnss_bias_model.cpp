// The GNSS bias's Gauss-Markov process, measurement columns and initialisation (gnss_bias_model.hpp).
#include "rowloc/localization/gnss_bias_model.hpp"

#include <cmath>

namespace rowloc::localization {

using L = StateLayout;

GnssBiasModel::GnssBiasModel(const GpsNoise& gps, const StateLayout& layout)
    : index_(layout.gnss_bias), sigma_m_(gps.bias_sigma_m), time_constant_s_(gps.bias_time_constant_s) {}

double GnssBiasModel::Decay(double dt_s) const {
  return index_ >= 0 ? std::exp(-dt_s / time_constant_s_) : 1.0;
}

void GnssBiasModel::Propagate(Eigen::VectorXd& x, Eigen::MatrixXd& p, double dt_s) const {
  if (index_ < 0) return;
  const int b = index_;
  const double a = Decay(dt_s);
  x.segment<2>(b) *= a;
  p.middleRows<2>(b) *= a;
  p.middleCols<2>(b) *= a;
  const double added = StationaryVariance() * -std::expm1(-2.0 * dt_s / time_constant_s_);
  p(b, b) += added;
  p(b + 1, b + 1) += added;
}

void GnssBiasModel::Initialise(Eigen::VectorXd& x, Eigen::MatrixXd& p, bool position_from_gnss) const {
  if (index_ < 0) return;
  const int b = index_;
  const double variance = StationaryVariance();
  x.segment<2>(b).setZero();
  p(b, b) = p(b + 1, b + 1) = variance;
  if (position_from_gnss) {
    p(L::kX, L::kX) += variance;
    p(L::kY, L::kY) += variance;
    p(L::kX, b) = p(b, L::kX) = p(L::kY, b + 1) = p(b + 1, L::kY) = -variance;
  }
}

void GnssBiasModel::MeasureAntenna(const Eigen::VectorXd& x, const Eigen::Vector2d& lever_arm_m,
                                   LinearizedMeasurement& out) const {
  GpsAntennaModel(x, lever_arm_m, index_, out);
}

}  // namespace rowloc::localization
