// Trajectory metrics: interpolation, pose errors, NEES, drift, slip (see metrics.hpp).
// The innovation metrics (NIS, whiteness) are in metrics_innovations.cpp.
#include "rowloc/sim/metrics.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

namespace rowloc::sim {

double WrapAngle(double angle_rad) {
  double a = std::remainder(angle_rad, 2.0 * std::numbers::pi);  // [-pi, pi]
  if (a <= -std::numbers::pi) a += 2.0 * std::numbers::pi;
  return a;
}

ErrorStatistics Summarize(const std::vector<double>& values) {
  ErrorStatistics s;
  s.count = values.size();
  if (values.empty()) return s;
  const double n = static_cast<double>(values.size());
  double sum = 0.0;
  double sum_sq = 0.0;
  for (double v : values) {
    sum += v;
    sum_sq += v * v;
    s.max_abs = std::max(s.max_abs, std::abs(v));
  }
  s.mean = sum / n;
  s.rms = std::sqrt(sum_sq / n);
  double centred = 0.0;
  for (double v : values) centred += (v - s.mean) * (v - s.mean);
  s.std = std::sqrt(centred / n);
  return s;
}

namespace {
std::string Seconds(double t_s) {
  std::ostringstream out;
  out.precision(17);
  out << t_s << " s";
  return out.str();
}

/// Per-wheel values at fraction s between two samples: the wheels named in both.
std::map<std::string, double> InterpolateWheels(const std::map<std::string, double>& v0,
                                                const std::map<std::string, double>& v1, double s) {
  std::map<std::string, double> out;
  for (const auto& [wheel, value0] : v0) {
    if (const auto it = v1.find(wheel); it != v1.end()) out[wheel] = value0 + s * (it->second - value0);
  }
  return out;
}
}  // namespace

TruthState InterpolateTruth(const formats::TruthStream& truth, double t_s) {
  const auto& samples = truth.samples;
  if (samples.empty()) throw EvaluationError(truth.source_name + ": the truth stream has no truth samples");
  if (!(t_s >= samples.front().t_s && t_s <= samples.back().t_s)) {
    throw EvaluationError("time " + Seconds(t_s) + " is outside the truth's span [" + Seconds(samples.front().t_s) +
                          ", " + Seconds(samples.back().t_s) + "] of " + truth.source_name +
                          " (estimates are not extrapolated)");
  }
  const auto after = std::upper_bound(samples.begin(), samples.end(), t_s,
                                      [](double t, const formats::TruthSample& s) { return t < s.t_s; });
  TruthState out;
  out.t_s = t_s;
  if (after == samples.end()) {  // t_s == last time
    const formats::TruthSample& last = samples.back();
    out.position_m = last.position_m;
    out.phi_rad = WrapAngle(last.phi_rad);
    out.wheel_slip = last.wheel_slip;
    out.wheel_rolling_radius_m = last.wheel_rolling_radius_m;
    return out;
  }
  const formats::TruthSample& s1 = *after;
  const formats::TruthSample& s0 = *(after - 1);  // exists: t_s >= front().t_s and s1.t_s > t_s
  const double s = (t_s - s0.t_s) / (s1.t_s - s0.t_s);
  out.position_m = s0.position_m + s * (s1.position_m - s0.position_m);
  out.phi_rad = WrapAngle(s0.phi_rad + s * WrapAngle(s1.phi_rad - s0.phi_rad));
  out.wheel_slip = InterpolateWheels(s0.wheel_slip, s1.wheel_slip, s);
  out.wheel_rolling_radius_m = InterpolateWheels(s0.wheel_rolling_radius_m, s1.wheel_rolling_radius_m, s);
  return out;
}

Eigen::Vector2d AlongDirection(const Eigen::Vector2d& true_position_m, double true_phi_rad,
                               const std::optional<geometry::SegmentIndex>& rows) {
  const Eigen::Vector2d heading(std::cos(true_phi_rad), std::sin(true_phi_rad));
  if (!rows || rows->size() == 0) return heading;
  const auto nearest = rows->Nearest(true_position_m, 1);
  Eigen::Vector2d u = rows->entries()[nearest.front().second].segment.Direction();
  if (u.dot(heading) < 0.0) u = -u;
  return u;
}

namespace {

/// NEES and its dof for one estimate (nullopt without covariance).
void FillConsistency(const formats::EstimateSample& est, const Eigen::Vector2d& error_m,
                     std::optional<double> heading_rad, const Eigen::Vector2d& u, PoseError& out) {
  if (!est.covariance) return;
  const Eigen::MatrixXd& p = *est.covariance;
  const Eigen::Matrix2d pxy = p.topLeftCorner<2, 2>();
  const Eigen::Vector2d n(-u.y(), u.x());
  out.sigma_along_m = std::sqrt(std::max(0.0, u.dot(pxy * u)));
  out.sigma_across_m = std::sqrt(std::max(0.0, n.dot(pxy * n)));
  if (p.rows() == 3) out.sigma_heading_rad = std::sqrt(std::max(0.0, p(2, 2)));
  const bool with_heading = p.rows() == 3 && heading_rad.has_value();
  const Eigen::MatrixXd used = with_heading ? p : Eigen::MatrixXd(pxy);
  Eigen::VectorXd e(used.rows());
  e.head<2>() = error_m;
  if (with_heading) e(2) = *heading_rad;
  const Eigen::LLT<Eigen::MatrixXd> llt(used);
  if (llt.info() != Eigen::Success) {  // singular (PSD) covariance: NEES undefined
    out.covariance_singular = true;
    return;
  }
  out.nees = llt.matrixL().solve(e).squaredNorm();
  out.nees_dof = with_heading ? 3 : 2;
}

}  // namespace

std::vector<PoseError> ComputePoseErrors(const formats::TruthStream& truth, const formats::EstimateStream& estimates,
                                         const std::optional<geometry::SegmentIndex>& rows) {
  std::vector<PoseError> out;
  out.reserve(estimates.estimates.size());
  for (const formats::EstimateSample& est : estimates.estimates) {
    TruthState state;
    try {
      state = InterpolateTruth(truth, est.t_s);
    } catch (const EvaluationError& e) {
      throw EvaluationError(estimates.source_name + ":" + std::to_string(est.line) + ": estimate at " + e.what());
    }
    PoseError pe;
    pe.t_s = est.t_s;
    pe.error_m = est.position_m - state.position_m;
    const Eigen::Vector2d u = AlongDirection(state.position_m, state.phi_rad, rows);
    pe.along_m = pe.error_m.dot(u);
    pe.across_m = pe.error_m.dot(Eigen::Vector2d(-u.y(), u.x()));
    pe.total_m = pe.error_m.norm();
    if (est.phi_rad) pe.heading_rad = WrapAngle(*est.phi_rad - state.phi_rad);
    FillConsistency(est, pe.error_m, pe.heading_rad, u, pe);
    out.push_back(pe);
  }
  return out;
}

PositionSummary SummarizePoseErrors(const std::vector<PoseError>& errors) {
  std::vector<double> total, along, across_abs, heading;
  double across_sum = 0.0;
  for (const PoseError& e : errors) {
    total.push_back(e.total_m);
    along.push_back(e.along_m);
    across_abs.push_back(std::abs(e.across_m));
    across_sum += e.across_m;
    if (e.heading_rad) heading.push_back(*e.heading_rad);
  }
  PositionSummary s;
  s.total_m = Summarize(total);
  s.along_m = Summarize(along);
  s.across_abs_m = Summarize(across_abs);
  s.across_signed_mean_m = errors.empty() ? 0.0 : across_sum / static_cast<double>(errors.size());
  s.heading_rad = Summarize(heading);
  return s;
}

/// Batch-means interval (batch_means.hpp): batches of at least kBatchLengthInTau integrated
/// autocorrelation times, so that neighbouring batch means are nearly independent (their
/// correlation is then about 1 / (2 kBatchLengthInTau)), and between kMinBatches and kMaxBatches of
/// them; a run shorter than kMinBatches such batches is too short for an interval (not reported).
constexpr double kBatchLengthInTau = 4.0;
constexpr std::size_t kMinBatches = 5;
constexpr std::size_t kMaxBatches = 20;

ConsistencySummary SummarizeConsistency(const std::vector<double>& values, const std::vector<int>& dofs,
                                        double probability) {
  if (values.size() != dofs.size()) throw std::invalid_argument("SummarizeConsistency: sizes differ");
  ConsistencySummary s;
  s.probability = probability;
  s.count = values.size();
  if (values.empty()) return s;
  std::size_t inside = 0;
  double sum = 0.0;
  for (std::size_t k = 0; k < values.size(); ++k) {
    sum += values[k];
    s.total_dof += dofs[k];
    if (ChiSquareInterval(dofs[k], probability).Contains(values[k])) ++inside;
  }
  s.mean = sum / static_cast<double>(s.count);
  s.band = TimeAveragedBand(s.total_dof, s.count, probability);
  s.mean_inside = s.band.Contains(s.mean);
  s.fraction_inside = static_cast<double>(inside) / static_cast<double>(s.count);
  s.correlation_time_samples = IntegratedAutocorrelationTime(values);
  s.effective_sample_count = static_cast<double>(s.count) / s.correlation_time_samples;
  const auto batches = static_cast<std::size_t>(
      std::min(static_cast<double>(kMaxBatches), s.effective_sample_count / kBatchLengthInTau));
  if (batches >= kMinBatches) s.batch_means = BatchMeans(values, batches, probability);
  s.expected_inside = s.batch_means && s.batch_means->Contains(s.total_dof / static_cast<double>(s.count));
  return s;
}

std::vector<DriftInterval> DriftAfterFixLoss(const formats::TruthStream& truth, const std::vector<PoseError>& errors,
                                             double min_duration_s) {
  std::vector<DriftInterval> out;
  const auto& samples = truth.samples;
  std::size_t i = 0;
  while (i < samples.size()) {
    if (samples[i].gnss_available) {
      ++i;
      continue;
    }
    std::size_t j = i;
    while (j < samples.size() && !samples[j].gnss_available) ++j;
    DriftInterval d;
    d.start_s = samples[i].t_s;
    d.fixes_returned = j < samples.size();
    d.end_s = d.fixes_returned ? samples[j].t_s : samples.back().t_s;
    i = j;
    if (d.end_s - d.start_s < min_duration_s) continue;
    for (const PoseError& e : errors) {
      if (e.t_s < d.start_s || e.t_s > d.end_s) continue;
      if (d.estimate_count == 0) d.error_start_m = e.total_m;
      d.error_end_m = e.total_m;
      d.max_error_m = std::max(d.max_error_m, e.total_m);
      ++d.estimate_count;
    }
    d.growth_m = d.error_end_m - d.error_start_m;
    out.push_back(d);
  }
  return out;
}

std::vector<WheelSlipError> CompareWheelSlip(const formats::TruthStream& truth,
                                             const formats::EstimateStream& estimates) {
  std::map<std::string, std::vector<double>> diffs;
  for (const formats::EstimateSample& est : estimates.estimates) {
    if (est.wheel_slip.empty()) continue;
    const TruthState state = InterpolateTruth(truth, est.t_s);
    for (const auto& [wheel, slip] : est.wheel_slip) {
      if (const auto it = state.wheel_slip.find(wheel); it != state.wheel_slip.end()) {
        diffs[wheel].push_back(slip - it->second);
      }
    }
  }
  std::vector<WheelSlipError> out;
  for (const auto& [wheel, d] : diffs) out.push_back({wheel, Summarize(d)});
  return out;
}

EvaluationResult Evaluate(const formats::TruthStream& truth, const formats::EstimateStream& estimates,
                          const EvaluationOptions& options) {
  if (estimates.estimates.empty()) {
    throw EvaluationError(estimates.source_name + ": the estimate stream has no estimate lines");
  }
  EvaluationResult r;
  r.options = options;
  r.reference = options.rows ? AlongAcrossReference::kRowDirection : AlongAcrossReference::kTrueHeading;
  r.truth_count = truth.samples.size();
  r.estimate_count = estimates.estimates.size();
  r.start_s = estimates.estimates.front().t_s;
  r.end_s = estimates.estimates.back().t_s;
  r.pose_errors = ComputePoseErrors(truth, estimates, options.rows);
  r.position = SummarizePoseErrors(r.pose_errors);
  std::vector<double> nees;
  std::vector<int> dofs;
  for (const PoseError& e : r.pose_errors) {
    if (e.covariance_singular) ++r.singular_covariance_count;
    if (!e.nees) continue;
    nees.push_back(*e.nees);
    dofs.push_back(e.nees_dof);
  }
  r.nees = SummarizeConsistency(nees, dofs, options.probability);
  r.innovations = AnalyzeInnovations(estimates.updates, options.max_lag, options.probability);
  r.drift = DriftAfterFixLoss(truth, r.pose_errors, options.drift_min_duration_s);
  r.slip = CompareWheelSlip(truth, estimates);
  r.rolling_radius = CompareRollingRadius(truth, estimates, options.probability);
  return r;
}

}  // namespace rowloc::sim
