// Innovation metrics: recomputed NIS per sensor, gating, whiteness (see metrics.hpp; Lindgren et al. 2002,
// Eqs. 42-43).
#include "rowloc/sim/metrics.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <map>

namespace rowloc::sim {

WhitenessResult InnovationWhiteness(const std::vector<Eigen::VectorXd>& whitened, std::size_t max_lag,
                                    double probability) {
  WhitenessResult r;
  r.sample_count = whitened.size();
  if (whitened.size() < 2) {
    r.not_computed = "fewer than 2 innovations";
    return r;
  }
  for (const Eigen::VectorXd& w : whitened) {
    if (w.size() != whitened.front().size()) {
      r.not_computed = "innovation length changes within the sensor";
      return r;
    }
  }
  const std::size_t k_count = whitened.size();
  const std::size_t lags = std::min(max_lag, k_count - 1);
  // rho(l) of m-dimensional whitened white noise has variance ~ 1/(K m) (numerator: K terms of
  // variance m; denominator ~ K m), so the band is z / sqrt(K m); Lindgren et al.'s z / sqrt(K) is the m = 1 case.
  const auto dim = static_cast<std::size_t>(whitened.front().size());
  r.band_half_width = WhitenessBandHalfWidth(k_count * dim, probability);
  std::size_t inside = 0;
  for (std::size_t l = 1; l <= lags; ++l) {
    double cross = 0.0, head = 0.0, tail = 0.0;
    for (std::size_t k = 0; k + l < k_count; ++k) {
      cross += whitened[k].dot(whitened[k + l]);
      head += whitened[k].squaredNorm();
      tail += whitened[k + l].squaredNorm();
    }
    const double denom = std::sqrt(head * tail);
    const double rho = denom > 0.0 ? cross / denom : 0.0;
    r.autocorrelation.push_back(rho);
    if (std::abs(rho) <= r.band_half_width) ++inside;
  }
  r.fraction_inside = lags == 0 ? 0.0 : static_cast<double>(inside) / static_cast<double>(lags);
  return r;
}

namespace {

SensorInnovationResult AnalyzeSensor(const std::string& sensor,
                                     const std::vector<const formats::UpdateRecord*>& records, std::size_t max_lag,
                                     double probability) {
  SensorInnovationResult r;
  r.sensor = sensor;
  r.update_count = records.size();
  std::vector<double> accepted_nis;
  std::vector<int> accepted_dofs;
  std::vector<Eigen::VectorXd> whitened;
  for (const formats::UpdateRecord* u : records) {
    const double nis = u->innovation.dot(u->innovation_covariance.ldlt().solve(u->innovation));
    const double rel = std::abs(nis - u->nis) / std::max(std::abs(nis), 1e-300);
    r.max_nis_relative_difference = std::max(r.max_nis_relative_difference, rel);
    if (rel > 1e-6) ++r.nis_mismatch_count;
    const int dof = static_cast<int>(u->innovation.size());
    r.times_s.push_back(u->t_s);
    r.nis_values.push_back(nis);
    r.dofs.push_back(dof);
    if (!u->accepted) {
      ++r.gated_out_count;
      continue;
    }
    accepted_nis.push_back(nis);
    accepted_dofs.push_back(dof);
    const Eigen::LLT<Eigen::MatrixXd> llt(u->innovation_covariance);
    whitened.push_back(llt.matrixL().solve(u->innovation));
  }
  r.gated_out_fraction =
      r.update_count == 0 ? 0.0 : static_cast<double>(r.gated_out_count) / static_cast<double>(r.update_count);
  r.nis = SummarizeConsistency(accepted_nis, accepted_dofs, probability);
  r.whiteness = InnovationWhiteness(whitened, max_lag, probability);
  return r;
}

}  // namespace

std::vector<SensorInnovationResult> AnalyzeInnovations(const std::vector<formats::UpdateRecord>& updates,
                                                       std::size_t max_lag, double probability) {
  std::map<std::string, std::vector<const formats::UpdateRecord*>> by_sensor;
  for (const formats::UpdateRecord& u : updates) by_sensor[u.sensor].push_back(&u);
  std::vector<SensorInnovationResult> out;
  for (const auto& [sensor, records] : by_sensor) out.push_back(AnalyzeSensor(sensor, records, max_lag, probability));
  return out;
}

}  // namespace rowloc::sim
