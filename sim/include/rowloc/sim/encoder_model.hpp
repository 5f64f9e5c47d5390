// Wheel and steering encoder error models (the design's "encoder quantization and filter delay";
// issue 3, Sensors). Truth in, measurement out.
//
// Wheel encoder (docs/simulation-sensors.md):
//  - The caller passes the true wheel angular rate w_k (rad/s), taken as the mean rate over
//    (t_{k-1}, t_k]. Ticks accumulate as r_k = r_{k-1} + w_k dt n / (2 pi) (n ticks per revolution);
//    the sample reports c_k = floor(r_k) whole ticks and carries r_k - c_k, so no tick is lost:
//    sum of counts = floor(total true ticks), and the speed error of one sample is under one
//    tick per interval, 2 pi / (n dt) rad/s.
//  - Quantized speed q_k = c_k 2 pi / (n dt), then a first-order low-pass tau dy/dt = q - y
//    discretised exactly for a piecewise-constant input (zero-order hold):
//    y_k = y_{k-1} + (1 - exp(-dt / tau)) (q_k - y_{k-1}); tau = 0 disables the filter.
//  - Optional additive Gaussian noise of sigma s on the output: z_k = y_k + s e_k.
//  - The cumulative count times the tick angle, (c_1 + ... + c_k) 2 pi / n, is reported too (the
//    wheels message's `angle_rad`): true angle minus a fraction of a tick, no filter, no noise.
// Steering encoder: z = step * round((delta + s e) / step) (noise on the analogue angle, then the
// quantizer; step = 0 disables quantization). The quantization error is uniform on
// [-step/2, step/2] (variance step^2 / 12) when the angle varies over many steps.
#pragma once

#include <cstdint>
#include <random>

namespace rowloc::sim {

struct WheelEncoderConfig {
  double rate_hz = 50.0;                  ///< nominal output rate
  double ticks_per_revolution = 1024.0;   ///< n > 0 (need not be an integer: gear ratios)
  double low_pass_time_constant_s = 0.0;  ///< tau >= 0
  double speed_noise_sigma_radps = 0.0;   ///< s >= 0, additive on the output
  bool operator==(const WheelEncoderConfig&) const = default;
  void Validate() const;  ///< std::invalid_argument naming the field
  double period_s() const { return 1.0 / rate_hz; }
};

struct WheelEncoderSample {
  double time_s = 0.0;
  std::int64_t tick_count = 0;        ///< whole ticks in (t_{k-1}, t_k] (negative when reversing)
  std::int64_t cumulative_ticks = 0;  ///< sum of tick_count since the first sample
  double quantized_speed_radps = 0.0; ///< q_k, before the filter
  double speed_radps = 0.0;           ///< z_k, the measurement
  /// c_1 + ... + c_k times the tick angle 2 pi / n: the angle the counter reports (no filter, no
  /// noise); it lags the true angle by the carried fraction, in [0, 1) tick.
  double cumulative_angle_rad = 0.0;
};

class WheelEncoderModel {
 public:
  WheelEncoderModel(const WheelEncoderConfig& config, std::uint64_t seed);

  /// time_s finite and strictly after the previous call; rate finite. Otherwise
  /// std::invalid_argument. The first call only starts the clock (no interval yet): zero ticks.
  WheelEncoderSample Measure(double time_s, double true_wheel_rate_radps);

  const WheelEncoderConfig& config() const { return config_; }

 private:
  WheelEncoderConfig config_;
  std::mt19937_64 rng_;
  bool has_previous_time_ = false;
  double previous_time_s_ = 0.0;
  double tick_remainder_ = 0.0;  ///< fractional ticks carried, in [0, 1)
  std::int64_t cumulative_ticks_ = 0;
  double filtered_speed_radps_ = 0.0;
};

struct SteeringEncoderConfig {
  double rate_hz = 50.0;
  double quantization_step_rad = 0.0;  ///< >= 0, 0 disables quantization
  double noise_sigma_rad = 0.0;        ///< >= 0
  bool operator==(const SteeringEncoderConfig&) const = default;
  void Validate() const;
  double period_s() const { return 1.0 / rate_hz; }
};

struct SteeringEncoderSample {
  double time_s = 0.0;
  double angle_rad = 0.0;
};

class SteeringEncoderModel {
 public:
  SteeringEncoderModel(const SteeringEncoderConfig& config, std::uint64_t seed);

  /// time_s finite and strictly after the previous call; angle finite. Otherwise std::invalid_argument.
  SteeringEncoderSample Measure(double time_s, double true_angle_rad);

  const SteeringEncoderConfig& config() const { return config_; }

 private:
  SteeringEncoderConfig config_;
  std::mt19937_64 rng_;
  bool has_previous_time_ = false;
  double previous_time_s_ = 0.0;
};

}  // namespace rowloc::sim
