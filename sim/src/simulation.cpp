#include "rowloc/sim/simulation.hpp"

#include "simulation_run.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rowloc::sim {

std::uint64_t StreamSeed(std::uint64_t seed, std::uint64_t stream_id) {
  // SplitMix64 (Steele, Lea, Flood 2014) finalizer over seed + golden-ratio multiples of the id.
  std::uint64_t z = seed + (stream_id + 1) * 0x9E3779B97F4A7C15ULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

namespace detail {
namespace {

std::optional<RowWorld> MakeWorld(const Scenario& scenario) {
  if (!scenario.world) return std::nullopt;
  return RowWorld(*scenario.world);
}

}  // namespace

SimulationRun::SimulationRun(const Scenario& scenario, const SimulationOutputs& outputs, std::uint64_t seed)
    : scenario_(scenario),
      outputs_(outputs),
      seed_(seed),
      route_(scenario.route),
      vehicle_(scenario.vehicle, scenario.terrains),
      world_(MakeWorld(scenario)),
      truth_(route_, vehicle_, scenario.terrain_map, world_ ? &world_->terrain() : nullptr),
      frame_(scenario.origin),
      torque_rng_(StreamSeed(seed, kTorqueStream)),
      vio_rng_(StreamSeed(seed, kVioStream)) {
  if (outputs.sensors == nullptr || outputs.truth == nullptr) {
    throw std::invalid_argument("RunSimulation: the sensor log and truth outputs are required");
  }
  if (world_) {
    caster_ = std::make_unique<CanopyCaster>(*world_);
    cover_ = std::make_unique<CanopyCover>(*caster_, *world_);
  }
  if (scenario.gnss) gnss_.emplace(scenario.gnss->config, StreamSeed(seed, kGnssStream));
  imu_.emplace(scenario.imu, StreamSeed(seed, kImuStream));
  const auto& wheels = scenario.vehicle.wheels;
  for (std::size_t i = 0; i < wheels.size(); ++i) {
    wheel_encoders_.emplace_back(scenario.wheel_encoder, StreamSeed(seed, kWheelStreamBase + i));
    steering_encoders_.emplace_back();
    if (wheels[i].steerable && scenario.steering_encoder) {
      steering_encoders_.back().emplace(*scenario.steering_encoder, StreamSeed(seed, kSteeringStreamBase + i));
    }
  }
  steering_readings_rad_.assign(wheels.size(), 0.0);
  if (scenario.ultrasonic) {
    for (std::size_t i = 0; i < scenario.ultrasonic->mounts.size(); ++i) {
      ultrasonic_.emplace_back(scenario.ultrasonic->params, StreamSeed(seed, kUltrasonicStreamBase + i));
    }
  }
  const formats::LogHeader header = MakeHeader();
  sensor_log_ = std::make_unique<SensorLogWriter>(*outputs.sensors, header);
  truth_log_ = std::make_unique<TruthLogWriter>(*outputs.truth, header);
  if (outputs.baseline_gnss != nullptr) {
    gnss_baseline_ = std::make_unique<formats::EstimateLogWriter>(*outputs.baseline_gnss, "baseline-gnss",
                                                                  scenario.vehicle.name, scenario.origin);
  }
  if (outputs.baseline_odometry != nullptr) {
    odometry_baseline_ = std::make_unique<formats::EstimateLogWriter>(
        *outputs.baseline_odometry, "baseline-odometry", scenario.vehicle.name, scenario.origin);
    const VehicleTruth start = truth_.At(0.0);
    dead_reckoning_.emplace(scenario.vehicle, PlanarPose{0.0, start.route.position_m, start.route.heading_rad});
  }
}

formats::LogHeader SimulationRun::MakeHeader() const {
  formats::LogHeader header;
  header.protocol = "rowloc/1";
  header.source = "rowloc simulate";
  header.scenario = scenario_.name;
  header.vehicle = scenario_.vehicle.name;
  header.origin = scenario_.origin;
  for (const WheelGeometry& wheel : scenario_.vehicle.wheels) header.wheels.push_back(wheel.name);
  if (scenario_.ultrasonic) {
    for (const SensorMount& mount : scenario_.ultrasonic->mounts) header.ultrasonic.push_back(mount.name);
  }
  return header;
}

std::vector<Clock> SimulationRun::MakeClocks() const {
  std::vector<Clock> clocks;
  if (gnss_) clocks.push_back({ClockKind::kGnss, scenario_.gnss->config.rate_hz, 0.0});
  clocks.push_back({ClockKind::kImu, scenario_.imu.rate_hz, 0.0});
  if (scenario_.steering_encoder) clocks.push_back({ClockKind::kSteering, scenario_.steering_encoder->rate_hz, 0.0});
  clocks.push_back({ClockKind::kWheels, scenario_.wheel_encoder.rate_hz, 0.0});
  if (scenario_.vio) clocks.push_back({ClockKind::kVio, scenario_.vio->rate_hz, 0.0});
  if (scenario_.ultrasonic) {
    const double rate = scenario_.ultrasonic->rate_hz;
    const double n = static_cast<double>(ultrasonic_.size());
    for (std::size_t i = 0; i < ultrasonic_.size(); ++i) {
      clocks.push_back({ClockKind::kUltrasonic, rate, static_cast<double>(i) / (n * rate), i});
    }
  }
  clocks.push_back({ClockKind::kTruth, scenario_.truth_rate_hz, 0.0});
  return clocks;
}

SimulationSummary SimulationRun::Run(const std::function<void(double, double)>& progress) {
  const double duration = route_.duration_s();
  summary_.duration_s = duration;
  summary_.distance_m = route_.length_m();
  std::vector<Clock> clocks = MakeClocks();
  double next_progress = 0.0;
  while (true) {
    // The earliest pending clock; ties go to the earlier clock in the list (the documented order).
    auto earliest = clocks.end();
    for (auto it = clocks.begin(); it != clocks.end(); ++it) {
      if (it->Next() <= duration && (earliest == clocks.end() || it->Next() < earliest->Next())) earliest = it;
    }
    if (earliest == clocks.end()) break;
    const double time = earliest->Next();
    Tick(*earliest, time);
    ++earliest->k;
    if (progress && time >= next_progress) {
      progress(time, duration);
      next_progress = time + 0.01 * duration;
    }
  }
  if (dead_reckoning_) {
    summary_.baseline_odometry_final_error_m =
        (dead_reckoning_->pose().position_m - truth_.At(duration).route.position_m).norm();
  }
  summary_.sensor_messages = sensor_log_->messages_written();
  summary_.truth_records = truth_log_->records_written();
  for (std::ostream* out : {outputs_.sensors, outputs_.truth, outputs_.baseline_gnss, outputs_.baseline_odometry}) {
    if (out != nullptr && !out->flush()) throw std::runtime_error("RunSimulation: cannot write an output stream");
  }
  return summary_;
}

void SimulationRun::Tick(const Clock& clock, double time_s) {
  switch (clock.kind) {
    case ClockKind::kGnss:
      SampleGnss(time_s);
      return;
    case ClockKind::kImu: SampleImu(time_s); return;
    case ClockKind::kSteering: SampleSteering(time_s); return;
    case ClockKind::kWheels: SampleWheels(time_s); return;
    case ClockKind::kVio: SampleVio(time_s); return;
    case ClockKind::kUltrasonic: SampleUltrasonic(clock.sensor, time_s); return;
    case ClockKind::kTruth: WriteTruth(time_s); return;
  }
}

}  // namespace detail

SimulationSummary RunSimulation(const Scenario& scenario, const SimulationOutputs& outputs,
                                const SimulationOptions& options) {
  detail::SimulationRun run(scenario, outputs, options.seed.value_or(scenario.seed));
  return run.Run(options.progress);
}

}  // namespace rowloc::sim
