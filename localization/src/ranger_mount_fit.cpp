// Ranger mount fit (ranger_mount_fit.hpp states the problem): association of the echoes, the Ceres
// problem, and the result.
#include "rowloc/localization/ranger_mount_fit.hpp"

#include "rowloc/localization/range_to_line_model.hpp"

#include <ceres/ceres.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>

namespace rowloc::localization {
namespace {

using Pose3 = std::array<double, 3>;   // (dX, dY, dphi) of one knot
using Mount2 = std::array<double, 2>;  // (along, across) its beam: the correction of one ranger's mount

double WrapAngle(double a) { return std::remainder(a, 2.0 * M_PI); }

Eigen::Matrix2d Rotation(double phi) {
  Eigen::Matrix2d r;
  r << std::cos(phi), -std::sin(phi), std::sin(phi), std::cos(phi);
  return r;
}

/// The columns are the beam's direction and its normal (90 degrees ccw), body frame: body = B (along, across).
Eigen::Matrix2d BeamFrame(const RangeSensorMount& mount) {
  return Rotation(mount.beam_angle_rad);
}

/// An echo associated with a row and its range model linearized at the current estimate.
struct LinearizedEcho {
  std::size_t knot = 0;  ///< the echo lies between knots knot and knot + 1
  double weight = 0.0;   ///< of knot + 1 (linear interpolation)
  std::size_t ranger = 0;
  double measured_m = 0.0;
  double predicted_m = 0.0;  ///< r0 at (dx0, dl0)
  Eigen::RowVector3d pose_jacobian = Eigen::RowVector3d::Zero();
  Eigen::RowVector2d mount_jacobian = Eigen::RowVector2d::Zero();  ///< dr / d(along, across): H_p R(phi) B
  Eigen::Vector3d pose_correction0 = Eigen::Vector3d::Zero();
  Eigen::Vector2d mount_correction0 = Eigen::Vector2d::Zero();
  double sigma_m = 0.0;
};

struct EchoCost {
  explicit EchoCost(LinearizedEcho e) : echo(std::move(e)) {}
  template <typename T>
  bool operator()(const T* a, const T* b, const T* dl, T* residual) const {
    T predicted = T(echo.predicted_m);
    for (int i = 0; i < 3; ++i) {
      const T dx = (1.0 - echo.weight) * a[i] + echo.weight * b[i];
      predicted += echo.pose_jacobian[i] * (dx - echo.pose_correction0[i]);
    }
    for (int i = 0; i < 2; ++i) predicted += echo.mount_jacobian[i] * (dl[i] - echo.mount_correction0[i]);
    residual[0] = (echo.measured_m - predicted) / echo.sigma_m;
    return true;
  }
  LinearizedEcho echo;
};

/// The knots' motion turned by the heading correction (ranger_mount_fit.hpp, "motion").
struct MotionCost {
  /// reference: the reference's displacement (world) and heading change; predicted: the motion's.
  MotionCost(Eigen::Vector2d reference_displacement_m, Eigen::Vector2d predicted_displacement_m,
             double heading_change_excess_rad, double sigma_position_m, double sigma_heading_rad)
      : dp_ref(std::move(reference_displacement_m)),
        d(std::move(predicted_displacement_m)),
        da(heading_change_excess_rad),
        sp(sigma_position_m),
        sh(sigma_heading_rad) {}
  template <typename T>
  bool operator()(const T* a, const T* b, T* residual) const {
    using std::cos;
    using std::sin;
    const T c = cos(a[2]);
    const T s = sin(a[2]);
    residual[0] = (dp_ref.x() + b[0] - a[0] - (c * d.x() - s * d.y())) / sp;
    residual[1] = (dp_ref.y() + b[1] - a[1] - (s * d.x() + c * d.y())) / sp;
    residual[2] = (b[2] - a[2] + da) / sh;
    return true;
  }
  Eigen::Vector2d dp_ref, d;
  double da, sp, sh;
};

struct ScaledCost {  // x / sigma, componentwise (anchors and the mount prior)
  template <typename T, int N>
  static bool Apply(const T* x, const std::array<double, N>& sigma, T* residual) {
    for (int i = 0; i < N; ++i) residual[i] = x[i] / sigma[i];
    return true;
  }
};
struct AnchorCost {
  std::array<double, 3> sigma;
  template <typename T>
  bool operator()(const T* x, T* residual) const { return ScaledCost::Apply<T, 3>(x, sigma, residual); }
};
struct MountPriorCost {
  std::array<double, 2> sigma;
  template <typename T>
  bool operator()(const T* x, T* residual) const { return ScaledCost::Apply<T, 2>(x, sigma, residual); }
};

/// The problem's data and its current estimate.
class Calibrator {
 public:
  Calibrator(const RowMapRanging& ranging, const std::vector<mapio::SensorMount>& mounts, double cone_half_angle_rad,
             double max_range_m, const std::vector<ReferenceKnot>& knots, const std::vector<EchoRecord>& echoes,
             const RangerMountFitConfig& config)
      : ranging_(ranging),
        knots_(knots),
        echoes_(echoes),
        max_range_m_(max_range_m),
        config_(config),
        pose_correction_(knots.size(), Pose3{0.0, 0.0, 0.0}),
        mount_correction_(mounts.size(), Mount2{0.0, 0.0}) {
    for (const mapio::SensorMount& m : mounts) {
      names_.push_back(m.name);
      mounts_.push_back(RangeSensorMount{m.position_m.head<2>(), m.yaw_rad, cone_half_angle_rad});
    }
    for (const EchoRecord& e : echoes) {
      if (e.ranger >= mounts_.size()) {
        throw std::invalid_argument("echo of ranger " + std::to_string(e.ranger) + ": the vehicle lists " +
                                    std::to_string(mounts_.size()));
      }
    }
  }

  RangerMountFit Run() {
    RangerMountFit result;
    std::vector<double> rms_before;
    for (int pass = 0; pass < config_.outer_iterations; ++pass) {
      const double gate = pass == 0 ? config_.association_gate_m : config_.refined_gate_m;
      const std::vector<LinearizedEcho> echoes = Associate(gate, result);
      if (pass == 0) rms_before = ResidualRms(echoes);
      const ceres::Solver::Summary summary = Solve(echoes, pass + 1 == config_.outer_iterations);
      result.solver_iterations += static_cast<int>(summary.iterations.size());
      result.solver_report = summary.BriefReport();
    }
    const std::vector<LinearizedEcho> final_echoes = Associate(config_.refined_gate_m, result);
    CheckAssociation(final_echoes.size(), result);
    const std::vector<double> rms_after = ResidualRms(final_echoes);
    Report(final_echoes, rms_before, rms_after, result);
    return result;
  }

 private:
  /// The knot interval holding time t (knot k and the weight of k + 1), or none.
  std::optional<std::pair<std::size_t, double>> Interval(double t) const {
    const std::vector<ReferenceKnot>& knots = knots_;
    if (t < knots.front().time_s || t > knots.back().time_s) return std::nullopt;
    auto it = std::upper_bound(knots.begin(), knots.end(), t,
                               [](double v, const ReferenceKnot& k) { return v < k.time_s; });
    std::size_t k = it == knots.end() ? knots.size() - 2 : static_cast<std::size_t>(it - knots.begin()) - 1;
    const double dt = knots[k + 1].time_s - knots[k].time_s;
    if (!(dt > 0.0) || dt > config_.max_knot_gap_s) return std::nullopt;
    return std::make_pair(k, std::clamp((t - knots[k].time_s) / dt, 0.0, 1.0));
  }

  Eigen::Vector3d Interpolate(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double w) const {
    Eigen::Vector3d x = (1.0 - w) * a + w * b;
    x[2] = a[2] + w * WrapAngle(b[2] - a[2]);
    return x;
  }
  static Eigen::Vector3d AsVector(const Pose3& p) { return {p[0], p[1], p[2]}; }

  /// Every echo of the span with its nearest candidate within `gate` at the current estimate.
  std::vector<LinearizedEcho> Associate(double gate, RangerMountFit& counts) {
    std::vector<LinearizedEcho> out;
    counts.echoes_unassociated = counts.echoes_outside_reference = 0;
    for (const EchoRecord& e : echoes_) {
      const auto interval = Interval(e.time_s);
      if (!interval) {
        ++counts.echoes_outside_reference;
        continue;
      }
      const auto [k, w] = *interval;
      LinearizedEcho le;
      le.knot = k;
      le.weight = w;
      le.ranger = e.ranger;
      le.measured_m = e.range_m;
      le.pose_correction0 = (1.0 - w) * AsVector(pose_correction_[k]) + w * AsVector(pose_correction_[k + 1]);
      le.mount_correction0 = {mount_correction_[e.ranger][0], mount_correction_[e.ranger][1]};
      Eigen::Vector3d pose = Interpolate(knots_[k].pose, knots_[k + 1].pose, w) + le.pose_correction0;
      RangeSensorMount mount = mounts_[e.ranger];
      mount.lever_arm_m += BeamFrame(mount) * le.mount_correction0;
      const std::vector<EchoCandidate>& candidates =
          ranging_.Candidates(pose, mount, max_range_m_, gate, buffers_);
      const EchoCandidate* best = nullptr;
      for (const EchoCandidate& c : candidates) {
        if (std::abs(e.range_m - c.predicted_range_m) > gate) continue;
        if (!best || std::abs(e.range_m - c.predicted_range_m) < std::abs(e.range_m - best->predicted_range_m)) best = &c;
      }
      if (!best) {
        ++counts.echoes_unassociated;
        continue;
      }
      le.predicted_m = best->predicted_range_m;
      le.pose_jacobian = best->jacobian;
      le.mount_jacobian = MountRangeJacobian(best->jacobian, pose[2], mounts_[e.ranger].beam_angle_rad);
      le.sigma_m = std::hypot(config_.range_sigma_m, best->map_sigma_m);
      out.push_back(le);
    }
    return out;
  }

  /// Refuses a drive whose echoes mostly meet no row of the map.
  void CheckAssociation(std::size_t used, const RangerMountFit& counts) const {
    const std::size_t span = used + counts.echoes_unassociated;
    if (span == 0) {
      throw RangerMountFitError("no echo falls inside the reference trajectory's span (did the filter initialise?)");
    }
    const double fraction = static_cast<double>(used) / static_cast<double>(span);
    if (fraction < config_.min_associated_fraction) {
      throw RangerMountFitError(
          "only " + std::to_string(used) + " of " + std::to_string(span) + " echoes meet a row of the map within " +
          std::to_string(config_.refined_gate_m) + " m: the map is not of this field, or a mount is off by more than "
          "association_gate_m (" + std::to_string(config_.association_gate_m) + " m)");
    }
  }

  /// Per ranger, the RMS of measured - predicted over its associated echoes (NaN: none).
  std::vector<double> ResidualRms(const std::vector<LinearizedEcho>& echoes) const {
    std::vector<double> sum(mounts_.size(), 0.0), n(mounts_.size(), 0.0);
    for (const LinearizedEcho& e : echoes) {
      sum[e.ranger] += (e.measured_m - e.predicted_m) * (e.measured_m - e.predicted_m);
      n[e.ranger] += 1.0;
    }
    std::vector<double> rms(mounts_.size(), std::numeric_limits<double>::quiet_NaN());
    for (std::size_t i = 0; i < rms.size(); ++i) {
      if (n[i] > 0) rms[i] = std::sqrt(sum[i] / n[i]);
    }
    return rms;
  }

  std::vector<std::size_t> EchoesPerRanger(const std::vector<LinearizedEcho>& echoes) const {
    std::vector<std::size_t> used(mounts_.size(), 0);
    for (const LinearizedEcho& e : echoes) ++used[e.ranger];
    return used;
  }

  void AddMotionAndAnchors(ceres::Problem& problem) {
    const std::vector<ReferenceKnot>& knots = knots_;
    const std::array<double, 3> anchor{config_.position_anchor_sigma_m, config_.position_anchor_sigma_m,
                                       config_.heading_anchor_sigma_rad};
    for (std::size_t k = 0; k < knots.size(); ++k) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<AnchorCost, 3, 3>(new AnchorCost{anchor}), nullptr,
                               pose_correction_[k].data());
      if (k + 1 == knots.size()) break;
      const double dt = knots[k + 1].time_s - knots[k].time_s;
      if (!(dt > 0.0) || dt > config_.max_knot_gap_s) continue;
      const double root_dt = std::sqrt(dt);
      const Eigen::Vector2d reference = knots[k + 1].pose.head<2>() - knots[k].pose.head<2>();
      const double turn = WrapAngle(knots[k + 1].pose[2] - knots[k].pose[2]);
      Eigen::Vector2d predicted = reference;
      double predicted_turn = turn;
      if (knots[k].body_rates && knots[k + 1].body_rates) {
        const Eigen::Vector3d rates = 0.5 * (*knots[k].body_rates + *knots[k + 1].body_rates);
        predicted_turn = rates[2] * dt;
        predicted = Rotation(knots[k].pose[2] + 0.5 * predicted_turn) * rates.head<2>() * dt;
      }
      auto* cost = new MotionCost(reference, predicted, turn - predicted_turn,
                                  config_.position_walk_mps_per_sqrt_s * root_dt,
                                  config_.heading_walk_rad_per_sqrt_s * root_dt);
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<MotionCost, 3, 3, 3>(cost), nullptr,
                               pose_correction_[k].data(), pose_correction_[k + 1].data());
    }
  }

  /// with_covariance: also the mount corrections' covariance (the last pass only: it costs a factorisation).
  ceres::Solver::Summary Solve(const std::vector<LinearizedEcho>& echoes, bool with_covariance) {
    ceres::Problem problem;
    AddMotionAndAnchors(problem);
    for (const LinearizedEcho& e : echoes) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<EchoCost, 1, 3, 3, 2>(new EchoCost(e)),
                               new ceres::HuberLoss(config_.huber_sigmas), pose_correction_[e.knot].data(),
                               pose_correction_[e.knot + 1].data(), mount_correction_[e.ranger].data());
    }
    const std::vector<std::size_t> used = EchoesPerRanger(echoes);
    calibrated_.assign(mounts_.size(), false);
    for (std::size_t i = 0; i < mounts_.size(); ++i) {
      double* dl = mount_correction_[i].data();
      if (used[i] < config_.min_echoes_per_ranger) {
        mount_correction_[i] = {0.0, 0.0};
        if (problem.HasParameterBlock(dl)) problem.SetParameterBlockConstant(dl);
        continue;
      }
      calibrated_[i] = true;
      const double s = config_.mount_prior_scale_m;
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<MountPriorCost, 2, 2>(new MountPriorCost{{s, s}}),
                               new ceres::SoftLOneLoss(1.0), dl);
      if (!config_.estimate_across_beam) {
        mount_correction_[i][1] = 0.0;
        problem.SetManifold(dl, new ceres::SubsetManifold(2, {1}));
      }
    }
    ceres::Solver::Options options;
    options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    options.max_num_iterations = config_.max_solver_iterations;
    options.num_threads = 1;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    if (summary.termination_type == ceres::FAILURE) {
      throw RangerMountFitError("the least-squares solver failed: " + summary.message);
    }
    if (with_covariance) last_covariance_ = MountCovariances(problem);
    return summary;
  }

  /// Covariance of each calibrated ranger's correction (NaN where Ceres cannot compute it).
  std::vector<Eigen::Matrix2d> MountCovariances(ceres::Problem& problem) {
    std::vector<Eigen::Matrix2d> out(mounts_.size(), Eigen::Matrix2d::Constant(std::numeric_limits<double>::quiet_NaN()));
    std::vector<std::pair<const double*, const double*>> blocks;
    for (std::size_t i = 0; i < mounts_.size(); ++i) {
      if (calibrated_[i]) blocks.emplace_back(mount_correction_[i].data(), mount_correction_[i].data());
    }
    if (blocks.empty()) return out;
    ceres::Covariance::Options options;
    options.algorithm_type = ceres::SPARSE_QR;
    options.num_threads = 1;
    ceres::Covariance covariance(options);
    if (!covariance.Compute(blocks, &problem)) return out;
    for (std::size_t i = 0; i < mounts_.size(); ++i) {
      if (!calibrated_[i]) continue;
      double c[4];
      if (covariance.GetCovarianceBlock(mount_correction_[i].data(), mount_correction_[i].data(), c)) {
        out[i] << c[0], c[1], c[2], c[3];
      }
    }
    return out;
  }

  void Report(const std::vector<LinearizedEcho>& echoes,
              const std::vector<double>& rms_before, const std::vector<double>& rms_after, RangerMountFit& result) {
    const std::vector<std::size_t> used = EchoesPerRanger(echoes);
    std::vector<std::size_t> total(mounts_.size(), 0);
    for (const EchoRecord& e : echoes_) {
      if (Interval(e.time_s)) ++total[e.ranger];
    }
    double along_sum = 0.0;
    int calibrated = 0;
    for (std::size_t i = 0; i < mounts_.size(); ++i) {
      RangerMountEstimate r;
      r.name = names_[i];
      r.configured_lever_arm_m = mounts_[i].lever_arm_m;
      const Eigen::Vector2d correction(mount_correction_[i][0], mount_correction_[i][1]);
      r.lever_arm_m = r.configured_lever_arm_m + BeamFrame(mounts_[i]) * correction;
      r.along_beam_m = correction[0];
      r.across_beam_m = correction[1];
      r.along_beam_sigma_m = std::sqrt(last_covariance_[i](0, 0));
      r.across_beam_sigma_m = config_.estimate_across_beam ? std::sqrt(last_covariance_[i](1, 1)) : 0.0;
      r.calibrated = calibrated_[i];
      r.echoes = total[i];
      r.echoes_used = used[i];
      r.rms_before_m = rms_before[i];
      r.rms_after_m = rms_after[i];
      if (r.calibrated) {
        along_sum += r.along_beam_m;
        ++calibrated;
      }
      result.rangers.push_back(r);
    }
    if (calibrated == 0) {
      throw RangerMountFitError("no ranger has " + std::to_string(config_.min_echoes_per_ranger) +
                                   " echoes that meet a row of the map: is it the map of this field?");
    }
    result.common_along_beam_m = along_sum / calibrated;
    result.knots = knots_.size();
    result.echoes_used = echoes.size();
    double sum = 0.0;
    for (const Pose3& p : pose_correction_) sum += p[0] * p[0] + p[1] * p[1];
    result.position_correction_rms_m = std::sqrt(sum / static_cast<double>(pose_correction_.size()));
  }

  const RowMapRanging& ranging_;
  RowMapRanging::Buffers buffers_;
  const std::vector<ReferenceKnot>& knots_;
  const std::vector<EchoRecord>& echoes_;
  double max_range_m_;
  RangerMountFitConfig config_;
  std::vector<std::string> names_;
  std::vector<RangeSensorMount> mounts_;  ///< configured, vehicle order
  std::vector<Pose3> pose_correction_;    ///< per knot
  std::vector<Mount2> mount_correction_;  ///< per ranger
  std::vector<bool> calibrated_;
  std::vector<Eigen::Matrix2d> last_covariance_;
};

}  // namespace

RangerMountFit FitRangerMounts(const RowMapRanging& ranging, const std::vector<mapio::SensorMount>& mounts,
                               double cone_half_angle_rad, double max_range_m, const std::vector<ReferenceKnot>& knots,
                               const std::vector<EchoRecord>& echoes, const RangerMountFitConfig& config) {
  ValidateRangerMountFitConfig(config);
  if (mounts.empty()) throw RangerMountFitError("no ranger to fit");
  if (knots.size() < 2) throw RangerMountFitError("fewer than two reference poses");
  Calibrator calibrator(ranging, mounts, cone_half_angle_rad, max_range_m, knots, echoes, config);
  return calibrator.Run();
}

Eigen::RowVector2d MountRangeJacobian(const Eigen::RowVector3d& pose_jacobian, double heading_rad,
                                      double beam_angle_rad) {
  return pose_jacobian.head<2>() * Rotation(heading_rad) * Rotation(beam_angle_rad);
}

}  // namespace rowloc::localization
