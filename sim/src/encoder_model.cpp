// Wheel and steering encoder error models; the math is in encoder_model.hpp.
#include "rowloc/sim/encoder_model.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rowloc::sim {
namespace {

void Require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

bool FiniteNonNegative(double v) { return std::isfinite(v) && v >= 0.0; }

void CheckTime(const char* who, bool has_previous, double previous_s, double time_s) {
  Require(std::isfinite(time_s), std::string(who) + ": time_s is not finite");
  Require(!has_previous || time_s > previous_s, std::string(who) + ": time " + std::to_string(time_s) +
                                                    " s is not after the previous sample time " +
                                                    std::to_string(previous_s) + " s");
}

}  // namespace

void WheelEncoderConfig::Validate() const {
  Require(std::isfinite(rate_hz) && rate_hz > 0.0, "WheelEncoderConfig: rate_hz must be finite and > 0");
  Require(std::isfinite(ticks_per_revolution) && ticks_per_revolution > 0.0,
          "WheelEncoderConfig: ticks_per_revolution must be finite and > 0");
  Require(FiniteNonNegative(low_pass_time_constant_s),
          "WheelEncoderConfig: low_pass_time_constant_s must be finite and >= 0");
  Require(FiniteNonNegative(speed_noise_sigma_radps),
          "WheelEncoderConfig: speed_noise_sigma_radps must be finite and >= 0");
}

WheelEncoderModel::WheelEncoderModel(const WheelEncoderConfig& config, std::uint64_t seed)
    : config_(config), rng_(seed) {
  config_.Validate();
}

WheelEncoderSample WheelEncoderModel::Measure(double time_s, double true_wheel_rate_radps) {
  CheckTime("WheelEncoderModel::Measure", has_previous_time_, previous_time_s_, time_s);
  Require(std::isfinite(true_wheel_rate_radps), "WheelEncoderModel::Measure: true wheel rate is not finite");
  WheelEncoderSample sample;
  sample.time_s = time_s;
  const bool first = !has_previous_time_;
  const double dt_s = first ? 0.0 : time_s - previous_time_s_;
  has_previous_time_ = true;
  previous_time_s_ = time_s;
  if (!first) {
    const double ticks_per_rad = config_.ticks_per_revolution / (2.0 * std::numbers::pi);
    const double ticks = tick_remainder_ + true_wheel_rate_radps * dt_s * ticks_per_rad;
    const double whole = std::floor(ticks);
    tick_remainder_ = ticks - whole;
    sample.tick_count = static_cast<std::int64_t>(whole);
    cumulative_ticks_ += sample.tick_count;
    sample.quantized_speed_radps = whole / ticks_per_rad / dt_s;
    const double tau = config_.low_pass_time_constant_s;
    if (tau > 0.0) {
      filtered_speed_radps_ += -std::expm1(-dt_s / tau) * (sample.quantized_speed_radps - filtered_speed_radps_);
    } else {
      filtered_speed_radps_ = sample.quantized_speed_radps;  // filter disabled: exact pass-through
    }
  }
  sample.cumulative_ticks = cumulative_ticks_;
  sample.cumulative_angle_rad = static_cast<double>(cumulative_ticks_) * 2.0 * std::numbers::pi / config_.ticks_per_revolution;
  std::normal_distribution<double> normal(0.0, 1.0);
  sample.speed_radps = filtered_speed_radps_ + config_.speed_noise_sigma_radps * normal(rng_);
  return sample;
}

void SteeringEncoderConfig::Validate() const {
  Require(std::isfinite(rate_hz) && rate_hz > 0.0, "SteeringEncoderConfig: rate_hz must be finite and > 0");
  Require(FiniteNonNegative(quantization_step_rad),
          "SteeringEncoderConfig: quantization_step_rad must be finite and >= 0");
  Require(FiniteNonNegative(noise_sigma_rad), "SteeringEncoderConfig: noise_sigma_rad must be finite and >= 0");
}

SteeringEncoderModel::SteeringEncoderModel(const SteeringEncoderConfig& config, std::uint64_t seed)
    : config_(config), rng_(seed) {
  config_.Validate();
}

SteeringEncoderSample SteeringEncoderModel::Measure(double time_s, double true_angle_rad) {
  CheckTime("SteeringEncoderModel::Measure", has_previous_time_, previous_time_s_, time_s);
  Require(std::isfinite(true_angle_rad), "SteeringEncoderModel::Measure: true angle is not finite");
  has_previous_time_ = true;
  previous_time_s_ = time_s;
  std::normal_distribution<double> normal(0.0, 1.0);
  const double analogue = true_angle_rad + config_.noise_sigma_rad * normal(rng_);
  const double step = config_.quantization_step_rad;
  return {time_s, step > 0.0 ? step * std::round(analogue / step) : analogue};
}

}  // namespace rowloc::sim
