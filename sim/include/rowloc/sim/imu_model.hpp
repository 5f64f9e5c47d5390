// Planar IMU error model: truth in (body-frame specific force x, y in m/s^2 and yaw rate in rad/s),
// measurement out (the design's "IMU noise and bias drift"; issue 3, Sensors).
//
// Math, per axis (docs/simulation-sensors.md; IEEE Std 952 noise terms):
//   y_k = x_k + b_k + sigma_d w_k,  sigma_d = N sqrt(f)      (N: white-noise density, f: rate_hz)
//   b_k = b_{k-1} + K sqrt(t_k - t_{k-1}) v_k,  b_0 = initial bias
// with w_k, v_k i.i.d. N(0, 1). N is in [unit]/sqrt(Hz) (m/s^2/sqrt(Hz) or rad/s/sqrt(Hz));
// K is the bias random walk in [unit]/sqrt(s). The bias update is the exact discretisation of the
// Brownian motion db = K dW (Var[b(t+dt) - b(t)] = K^2 dt, for any dt), so irregular sampling
// keeps the bias statistics right. The white noise belongs to the sensor's own sampling at
// rate_hz (sigma_d = N / sqrt(1/f)), whatever times the caller asks at.
#pragma once

#include <cstdint>
#include <random>

namespace rowloc::sim {

struct ImuAxisConfig {
  double noise_density = 0.0;      ///< N: [unit]/sqrt(Hz)
  double bias_random_walk = 0.0;   ///< K: [unit]/sqrt(s)
  double initial_bias = 0.0;       ///< b_0: [unit]
  bool operator==(const ImuAxisConfig&) const = default;
};

struct ImuConfig {
  double rate_hz = 100.0;
  ImuAxisConfig accel_x;  ///< m/s^2 units
  ImuAxisConfig accel_y;  ///< m/s^2 units
  ImuAxisConfig gyro_z;   ///< rad/s units
  bool operator==(const ImuConfig&) const = default;

  /// Throws std::invalid_argument naming the offending field.
  void Validate() const;
  double period_s() const { return 1.0 / rate_hz; }
  /// Per-sample white-noise sigma N sqrt(rate_hz).
  double SampleSigma(const ImuAxisConfig& axis) const;
};

struct ImuTruth {
  double accel_x_mps2 = 0.0;
  double accel_y_mps2 = 0.0;
  double gyro_z_radps = 0.0;
};

struct ImuSample {
  double time_s = 0.0;
  double accel_x_mps2 = 0.0;
  double accel_y_mps2 = 0.0;
  double gyro_z_radps = 0.0;
  ImuTruth bias;  ///< true biases at time_s (ground truth, not seen by a real IMU)
};

class ImuModel {
 public:
  /// Throws std::invalid_argument if the configuration is invalid.
  ImuModel(const ImuConfig& config, std::uint64_t seed);

  /// time_s finite and strictly after the previous call; truth finite. Otherwise std::invalid_argument.
  ImuSample Measure(double time_s, const ImuTruth& truth);

  const ImuConfig& config() const { return config_; }

 private:
  double Axis(const ImuAxisConfig& axis, double truth, double dt_s, double& bias);

  ImuConfig config_;
  std::mt19937_64 rng_;
  bool has_previous_time_ = false;
  double previous_time_s_ = 0.0;
  ImuTruth bias_;
};

}  // namespace rowloc::sim
