// IMU error model; the math is in imu_model.hpp and docs/simulation-sensors.md.
#include "rowloc/sim/imu_model.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace rowloc::sim {
namespace {

void ValidateAxis(const ImuAxisConfig& axis, const std::string& name) {
  auto require = [&](bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument("ImuConfig: " + name + "." + what);
  };
  require(std::isfinite(axis.noise_density) && axis.noise_density >= 0.0, "noise_density must be finite and >= 0");
  require(std::isfinite(axis.bias_random_walk) && axis.bias_random_walk >= 0.0,
          "bias_random_walk must be finite and >= 0");
  require(std::isfinite(axis.initial_bias), "initial_bias must be finite");
}

}  // namespace

void ImuConfig::Validate() const {
  if (!(std::isfinite(rate_hz) && rate_hz > 0.0)) throw std::invalid_argument("ImuConfig: rate_hz must be finite and > 0");
  ValidateAxis(accel_x, "accel_x");
  ValidateAxis(accel_y, "accel_y");
  ValidateAxis(gyro_z, "gyro_z");
}

double ImuConfig::SampleSigma(const ImuAxisConfig& axis) const { return axis.noise_density * std::sqrt(rate_hz); }

ImuModel::ImuModel(const ImuConfig& config, std::uint64_t seed) : config_(config), rng_(seed) {
  config_.Validate();
  bias_ = {config_.accel_x.initial_bias, config_.accel_y.initial_bias, config_.gyro_z.initial_bias};
}

double ImuModel::Axis(const ImuAxisConfig& axis, double truth, double dt_s, double& bias) {
  std::normal_distribution<double> normal(0.0, 1.0);
  const double walk = normal(rng_);
  const double white = normal(rng_);
  bias += axis.bias_random_walk * std::sqrt(dt_s) * walk;
  return truth + bias + config_.SampleSigma(axis) * white;
}

ImuSample ImuModel::Measure(double time_s, const ImuTruth& truth) {
  if (!std::isfinite(time_s)) throw std::invalid_argument("ImuModel::Measure: time_s is not finite");
  if (has_previous_time_ && !(time_s > previous_time_s_)) {
    throw std::invalid_argument("ImuModel::Measure: time " + std::to_string(time_s) +
                                " s is not after the previous sample time " + std::to_string(previous_time_s_) + " s");
  }
  if (!std::isfinite(truth.accel_x_mps2) || !std::isfinite(truth.accel_y_mps2) || !std::isfinite(truth.gyro_z_radps)) {
    throw std::invalid_argument("ImuModel::Measure: true acceleration or yaw rate is not finite");
  }
  // The first sample sees the initial bias (dt = 0: no walk yet).
  const double dt_s = has_previous_time_ ? time_s - previous_time_s_ : 0.0;
  has_previous_time_ = true;
  previous_time_s_ = time_s;

  ImuSample sample;
  sample.time_s = time_s;
  sample.accel_x_mps2 = Axis(config_.accel_x, truth.accel_x_mps2, dt_s, bias_.accel_x_mps2);
  sample.accel_y_mps2 = Axis(config_.accel_y, truth.accel_y_mps2, dt_s, bias_.accel_y_mps2);
  sample.gyro_z_radps = Axis(config_.gyro_z, truth.gyro_z_radps, dt_s, bias_.gyro_z_radps);
  sample.bias = bias_;
  return sample;
}

}  // namespace rowloc::sim
