#include "rowloc/localization/state_bound.hpp"

#include <cmath>
#include <stdexcept>

namespace rowloc::localization {

void ProjectOntoBound(Eigen::VectorXd& x, const Eigen::MatrixXd& p, int index, double bound) {
  if (p.rows() != x.size() || p.cols() != x.size()) throw std::invalid_argument("state bound: P is not n x n");
  if (index < 0 || index >= x.size()) throw std::invalid_argument("state bound: no such state");
  if (!std::isfinite(bound)) throw std::invalid_argument("state bound: the bound is not finite");
  const double step = bound - x(index);
  if (step == 0.0) return;
  const double variance = p(index, index);
  if (variance > 0.0) x += p.col(index) * (step / variance);
  x(index) = bound;  // exactly, whatever the rounding of the line above
}

}  // namespace rowloc::localization
