// GNSS error model; the math is in gnss_model.hpp and docs/simulation-sensors.md.
#include "rowloc/sim/gnss_model.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rowloc::sim {
namespace {

void Require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("GnssConfig: " + what);
}

bool FiniteNonNegative(double v) { return std::isfinite(v) && v >= 0.0; }

void ValidateFault(const GnssMarkovFaultConfig& f, const std::string& name) {
  Require(FiniteNonNegative(f.onset_rate_open_per_s), name + ".onset_rate_open_per_s must be finite and >= 0");
  Require(FiniteNonNegative(f.onset_rate_canopy_per_s),
          name + ".onset_rate_canopy_per_s must be finite and >= 0");
  Require(std::isfinite(f.mean_duration_s) && f.mean_duration_s > 0.0,
          name + ".mean_duration_s must be finite and > 0");
}

double Interpolate(double open, double canopy, double c) { return open + (canopy - open) * c; }

}  // namespace

void GnssConfig::Validate() const {
  Require(std::isfinite(rate_hz) && rate_hz > 0.0, "rate_hz must be finite and > 0");
  Require(FiniteNonNegative(sigma_horizontal_m), "sigma_horizontal_m must be finite and >= 0");
  Require(FiniteNonNegative(sigma_vertical_m), "sigma_vertical_m must be finite and >= 0");
  Require(FiniteNonNegative(canopy_sigma_gain), "canopy_sigma_gain must be finite and >= 0");
  Require(nominal_fix != formats::GnssFixQuality::kNone, "nominal_fix must not be 'none'");
  ValidateFault(dropout, "dropout");
  ValidateFault(multipath, "multipath");
  Require(FiniteNonNegative(multipath_offset_min_m), "multipath_offset_min_m must be finite and >= 0");
  Require(std::isfinite(multipath_offset_max_m) && multipath_offset_max_m >= multipath_offset_min_m,
          "multipath_offset_max_m must be finite and >= multipath_offset_min_m");
}

MarkovStep ExactMarkovStep(double onset_rate_per_s, double recovery_rate_per_s, double dt_s) {
  const double total = onset_rate_per_s + recovery_rate_per_s;
  if (total <= 0.0) return {};
  const double mixing = -std::expm1(-total * dt_s);  // 1 - exp(-(a+b) dt), accurate for small dt
  return {onset_rate_per_s / total * mixing, recovery_rate_per_s / total * mixing};
}

GnssModel::GnssModel(const GnssConfig& config, std::uint64_t seed) : config_(config), rng_(seed) {
  config_.Validate();
}

void GnssModel::AdvanceFaults(double dt_s, double canopy_cover) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const auto& d = config_.dropout;
  const MarkovStep drop = ExactMarkovStep(
      Interpolate(d.onset_rate_open_per_s, d.onset_rate_canopy_per_s, canopy_cover), 1.0 / d.mean_duration_s, dt_s);
  const double u_drop = uniform(rng_);
  dropout_ = dropout_ ? !(u_drop < drop.p_recovery) : (u_drop < drop.p_onset);

  const auto& m = config_.multipath;
  const MarkovStep jump = ExactMarkovStep(
      Interpolate(m.onset_rate_open_per_s, m.onset_rate_canopy_per_s, canopy_cover), 1.0 / m.mean_duration_s, dt_s);
  const double u_jump = uniform(rng_);
  if (multipath_) {
    multipath_ = !(u_jump < jump.p_recovery);
    if (!multipath_) multipath_offset_m_.setZero();
  } else if (u_jump < jump.p_onset) {
    multipath_ = true;
    std::uniform_real_distribution<double> magnitude(config_.multipath_offset_min_m, config_.multipath_offset_max_m);
    std::uniform_real_distribution<double> direction(-std::numbers::pi, std::numbers::pi);
    const double r = magnitude(rng_);
    const double angle = direction(rng_);
    multipath_offset_m_ = Eigen::Vector2d(r * std::cos(angle), r * std::sin(angle));
  }
}

GnssSample GnssModel::Measure(double time_s, const Eigen::Vector3d& true_position_m, double canopy_cover) {
  if (!std::isfinite(time_s)) throw std::invalid_argument("GnssModel::Measure: time_s is not finite");
  if (has_previous_time_ && !(time_s > previous_time_s_)) {
    throw std::invalid_argument("GnssModel::Measure: time " + std::to_string(time_s) +
                                " s is not after the previous sample time " + std::to_string(previous_time_s_) + " s");
  }
  if (!true_position_m.allFinite()) throw std::invalid_argument("GnssModel::Measure: true position is not finite");
  if (!(canopy_cover >= 0.0 && canopy_cover <= 1.0)) {
    throw std::invalid_argument("GnssModel::Measure: canopy_cover must be in [0, 1], got " +
                                std::to_string(canopy_cover));
  }
  if (has_previous_time_) AdvanceFaults(time_s - previous_time_s_, canopy_cover);
  has_previous_time_ = true;
  previous_time_s_ = time_s;

  GnssSample sample;
  sample.time_s = time_s;
  const double inflation = 1.0 + config_.canopy_sigma_gain * canopy_cover;
  sample.sigma_horizontal_m = config_.sigma_horizontal_m * inflation;
  sample.sigma_vertical_m = config_.sigma_vertical_m * inflation;
  sample.faults = {dropout_, multipath_, multipath_offset_m_, canopy_cover};
  // The noise is drawn every epoch, fix or not, so that a dropout does not shift later noise.
  std::normal_distribution<double> normal(0.0, 1.0);
  const Eigen::Vector3d noise(normal(rng_) * sample.sigma_horizontal_m, normal(rng_) * sample.sigma_horizontal_m,
                              normal(rng_) * sample.sigma_vertical_m);
  if (dropout_) return sample;
  sample.has_fix = true;
  sample.fix = config_.nominal_fix;
  sample.position_m = true_position_m + noise;
  sample.position_m.head<2>() += multipath_offset_m_;
  return sample;
}

}  // namespace rowloc::sim
