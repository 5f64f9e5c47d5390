// The state of one simulation run (private to sim/src; the model is stated in simulation.hpp).
#pragma once

#include "rowloc/formats/estimate_stream_writer.hpp"
#include "rowloc/formats/sensor_messages.hpp"
#include "rowloc/mapio/local_frame.hpp"
#include "rowloc/sim/canopy_cover.hpp"
#include "rowloc/sim/dead_reckoning.hpp"
#include "rowloc/sim/log_writers.hpp"
#include "rowloc/sim/simulation.hpp"
#include "rowloc/sim/vehicle_truth.hpp"

#include <memory>
#include <optional>
#include <random>
#include <vector>

namespace rowloc::sim::detail {

/// Stream ids of StreamSeed (fixed: changing them changes every shipped run).
enum StreamId : std::uint64_t {
  kGnssStream = 1, kImuStream = 2, kTorqueStream = 3, kVioStream = 4,
  kWheelStreamBase = 100, kSteeringStreamBase = 200, kUltrasonicStreamBase = 300,
};

/// What a clock drives, in tie-break order.
enum class ClockKind { kGnss, kImu, kSteering, kWheels, kVio, kUltrasonic, kTruth };

struct Clock {
  ClockKind kind;
  double rate_hz;
  double phase_s;
  std::size_t sensor = 0;  ///< ultrasonic sensor index
  std::int64_t k = 0;
  double Next() const { return phase_s + static_cast<double>(k) / rate_hz; }
};

class SimulationRun {
 public:
  SimulationRun(const Scenario& scenario, const SimulationOutputs& outputs, std::uint64_t seed);
  SimulationSummary Run(const std::function<void(double, double)>& progress);

 private:
  /// The truth at time_s, evaluated once per distinct time (a reference valid until the next call).
  const VehicleTruth& TruthAt(double time_s);
  void Tick(const Clock& clock, double time_s);
  void SampleGnss(double time_s);
  void SampleImu(double time_s);
  void SampleSteering(double time_s);
  void SampleWheels(double time_s);
  void SampleVio(double time_s);
  void SampleUltrasonic(std::size_t sensor, double time_s);
  void WriteTruth(double time_s);
  std::vector<Clock> MakeClocks() const;
  formats::LogHeader MakeHeader() const;

  const Scenario& scenario_;
  SimulationOutputs outputs_;
  std::uint64_t seed_;
  Route route_;
  VehicleModel vehicle_;
  std::optional<RowWorld> world_;
  std::unique_ptr<CanopyCaster> caster_;
  std::unique_ptr<CanopyCover> cover_;
  VehicleTruthSampler truth_;
  mapio::LocalFrame frame_;

  std::optional<GnssModel> gnss_;
  std::optional<ImuModel> imu_;
  std::vector<WheelEncoderModel> wheel_encoders_;
  std::vector<std::optional<SteeringEncoderModel>> steering_encoders_;  ///< per wheel, steerable only
  std::vector<UltrasonicModel> ultrasonic_;
  std::mt19937_64 torque_rng_, vio_rng_;

  std::unique_ptr<SensorLogWriter> sensor_log_;
  std::unique_ptr<TruthLogWriter> truth_log_;
  std::unique_ptr<formats::EstimateLogWriter> gnss_baseline_, odometry_baseline_;
  std::optional<DeadReckoning> dead_reckoning_;

  // Latest states shared between streams.
  std::optional<VehicleTruth> cached_truth_;  ///< TruthAt's last result, at cached_truth_time_s_
  double cached_truth_time_s_ = 0.0;
  std::optional<double> previous_wheel_time_s_;
  std::vector<double> previous_wheel_rate_radps_;
  std::vector<double> steering_readings_rad_;
  // Injected faults (scenario_.faults, sensor_faults.hpp).
  std::size_t next_gnss_outlier_ = 0;                   ///< the next outlier not yet applied
  std::vector<std::optional<double>> dead_wheel_angle_;  ///< per wheel: the frozen angle of a dead encoder
  std::vector<std::optional<double>> stuck_range_m_;     ///< per ranger: the range it repeats
  GnssFaultState gnss_faults_;
  bool gnss_fix_ = false;
  ImuTruth imu_bias_;
  SimulationSummary summary_;
};

}  // namespace rowloc::sim::detail
