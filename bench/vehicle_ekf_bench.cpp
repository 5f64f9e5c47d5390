// Cost of the vehicle EKF (issue 4): "a predict + GPS + IMU + wheels update cycle <= 5 us median".
// One cycle = time advances 0.01 s, then one gps, one imu, (one steering for the swerve and 4WS
// vehicles) and one wheels message go through VehicleEkf::Process, in the simulator's order. The
// messages are pre-generated from a noisy drive around a circle (1 m/s, a lap of exactly 30 s = 3000
// cycles, so that the messages repeat lap after lap with only the time stamps shifted); the filter is
// converged over two laps before timing, and the benchmark fails if updates are gated out.
// Micro benchmarks: PredictStep alone (dt = 0.01 s) and KalmanUpdate of a 2-D (GNSS) measurement, both
// on the swerve with slip-aware odometry (20 states with the accelerometer bias); each iteration
// restores x and P first (the copy is timed too; BM_RestoreStateAndCovariance is that copy alone).
// Run the Release build with
//   vehicle_ekf_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include "rowloc/formats/sensor_messages.hpp"
#include "rowloc/localization/filter_config.hpp"
#include "rowloc/localization/kalman_update.hpp"
#include "rowloc/localization/measurement_models.hpp"
#include "rowloc/localization/process_model.hpp"
#include "rowloc/localization/vehicle_ekf.hpp"
#include "rowloc/mapio/local_frame.hpp"

#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace {

namespace formats = rowloc::formats;
namespace loc = rowloc::localization;
using rowloc::mapio::VehicleConfig;

const rowloc::geometry::GeoOrigin kOrigin{45.0628, 7.6621, 240.0};
constexpr int kCyclesPerLap = 3000;  // 30 s at 0.01 s
constexpr double kSpeed = 1.0, kYawRate = 2.0 * std::numbers::pi / 30.0;

Eigen::Vector2d Rotate(double a, const Eigen::Vector2d& v) {
  return {std::cos(a) * v.x() - std::sin(a) * v.y(), std::sin(a) * v.x() + std::cos(a) * v.y()};
}

/// Wheel i's exact rate on the circle (rad/s): the encoders' angle at time t is t times it.
double WheelRate(const rowloc::mapio::WheelGeometry& w) {
  const Eigen::Vector2d c(kSpeed - kYawRate * w.position_m.y(), kYawRate * w.position_m.x());
  return (w.steerable ? c.norm() : c.x()) / w.nominal_radius_m;
}

/// Messages of cycle k of the lap (times relative to the lap start; wheel angles, when wanted, are
/// set by Converged::RunCycle from the absolute time).
std::vector<std::vector<formats::SensorMessage>> MakeLap(const VehicleConfig& v, bool torque, bool angles) {
  const rowloc::mapio::LocalFrame frame(kOrigin);
  std::mt19937_64 rng(4);
  std::normal_distribution<double> n01;
  const bool steers = v.kind == rowloc::mapio::VehicleKind::kSwerveDrive ||
                      v.kind == rowloc::mapio::VehicleKind::kFourWheelSteer;
  std::vector<std::vector<formats::SensorMessage>> lap(kCyclesPerLap);
  for (int k = 0; k < kCyclesPerLap; ++k) {
    const double t = 0.01 * k, phi = kYawRate * t;
    const Eigen::Vector2d p(kSpeed / kYawRate * std::sin(phi), kSpeed / kYawRate * (1.0 - std::cos(phi)));
    const Eigen::Vector2d antenna = p + Rotate(phi, v.gnss_antenna.position_m.head<2>()) +
                                    0.01 * Eigen::Vector2d(n01(rng), n01(rng));
    const rowloc::geometry::GeoOrigin g = frame.ToGeodetic({antenna.x(), antenna.y(), 0.0});
    const formats::GpsPosition position{g.latitude_deg, g.longitude_deg, g.altitude_m, 0.01, 0.02};
    lap[k].push_back(formats::GpsMessage{t, "gnss", formats::GnssFixQuality::kRtkFixed, position});
    const Eigen::Vector2d l = v.imu.position_m.head<2>();
    lap[k].push_back(formats::ImuMessage{t, "imu", -kYawRate * kYawRate * l.x() + 0.01 * n01(rng),
                                         kYawRate * kSpeed - kYawRate * kYawRate * l.y() + 0.01 * n01(rng),
                                         kYawRate + 5e-4 * n01(rng)});
    formats::SteeringMessage steering{t, {}};
    formats::WheelsMessage wheels{t, {}, std::nullopt, std::nullopt};
    for (const auto& w : v.wheels) {
      const Eigen::Vector2d c(kSpeed - kYawRate * w.position_m.y(), kYawRate * w.position_m.x());
      steering.angle_rad.push_back(w.steerable ? std::optional<double>(std::atan2(c.y(), c.x())) : std::nullopt);
      wheels.speed_radps.push_back((w.steerable ? c.norm() : c.x()) / w.nominal_radius_m + 0.01 * n01(rng));
    }
    if (torque) wheels.torque_nm = std::vector<double>(v.wheels.size(), 2.0);
    if (angles) wheels.angle_rad = std::vector<double>(v.wheels.size(), 0.0);
    if (steers) lap[k].push_back(steering);
    lap[k].push_back(wheels);
  }
  return lap;
}

/// A filter at the start of the lap, converged over two laps; `fraction` gets the share of accepted updates.
struct Converged {
  loc::VehicleEkf ekf;
  std::vector<std::vector<formats::SensorMessage>> lap;
  long cycle = 0;  ///< cycles processed so far (time = 0.01 cycle)
  double accepted_fraction = 0.0;

  std::vector<double> wheel_rates_radps;  ///< exact, vehicle order (wheel angles)

  Converged(const VehicleConfig& v, bool slip_aware, bool angles = false)
      : Converged(v, Config(slip_aware, angles)) {}
  /// With a whole filter configuration (its slip-aware and angle switches shape the lap).
  Converged(const VehicleConfig& v, const loc::FilterConfig& config)
      : ekf(v, config, kOrigin, Names(v)),
        lap(MakeLap(v, config.slip_aware_odometry.enabled, config.wheels.angle_measurement)) {
    for (const auto& w : v.wheels) wheel_rates_radps.push_back(WheelRate(w));
    ekf.SetPose(0.0, {0.0, 0.0, 0.0}, Eigen::Vector3d(1e-4, 1e-4, 1e-4).asDiagonal());
    long accepted = 0, updates = 0;
    for (int i = 0; i < 2 * kCyclesPerLap; ++i) {
      for (const auto& u : RunCycle()) {
        accepted += u.outcome.accepted ? 1 : 0;
        ++updates;
      }
    }
    accepted_fraction = static_cast<double>(accepted) / static_cast<double>(updates);
  }
  /// Processes the next cycle's messages (time stamps shifted to the current lap).
  std::vector<loc::UpdateRecord> RunCycle() {
    std::vector<loc::UpdateRecord> records;
    const double t = 0.01 * static_cast<double>(cycle);
    for (formats::SensorMessage& m : lap[static_cast<std::size_t>(cycle % kCyclesPerLap)]) {
      SetTime(m, t);
      loc::ProcessResult r = ekf.Process(m);
      for (auto& u : r.updates) records.push_back(std::move(u));
    }
    ++cycle;
    return records;
  }
  /// The timed step: the next cycle's messages through the filter, each result kept from the
  /// optimizer (no copies, unlike RunCycle).
  void TimedCycle() {
    const double t = 0.01 * static_cast<double>(cycle);
    for (formats::SensorMessage& m : lap[static_cast<std::size_t>(cycle % kCyclesPerLap)]) {
      SetTime(m, t);
      auto result = ekf.Process(m);
      benchmark::DoNotOptimize(result);
    }
    ++cycle;
  }
  /// Sets a message's time to t and, for wheels with angles, the angles the wheels turned by t.
  void SetTime(formats::SensorMessage& m, double t) const {
    std::visit([t](auto& message) { message.time_s = t; }, m);
    if (auto* wheels = std::get_if<formats::WheelsMessage>(&m); wheels && wheels->angle_rad) {
      for (std::size_t i = 0; i < wheel_rates_radps.size(); ++i) (*wheels->angle_rad)[i] = wheel_rates_radps[i] * t;
    }
  }
  static loc::FilterConfig Config(bool slip_aware, bool angles = false) {
    loc::FilterConfig c;
    c.slip_aware_odometry.enabled = slip_aware;
    c.wheels.angle_measurement = angles;
    return c;
  }
  static std::vector<std::string> Names(const VehicleConfig& v) {
    std::vector<std::string> names;
    for (const auto& w : v.wheels) names.push_back(w.name);
    return names;
  }
};

void RunCycles(benchmark::State& state, const VehicleConfig& v, const loc::FilterConfig& config, bool steering = true) {
  Converged c(v, config);
  if (!steering) {  // issue 4's cycle exactly: predict + GPS + IMU + wheels (steering angles then float)
    for (auto& messages : c.lap) {
      std::erase_if(messages, [](const formats::SensorMessage& m) {
        return std::holds_alternative<formats::SteeringMessage>(m);
      });
    }
  }
  if (c.accepted_fraction < 0.99) {
    state.SkipWithError(("only " + std::to_string(c.accepted_fraction) + " of the updates accepted").c_str());
    return;
  }
  const double t0 = 0.01 * static_cast<double>(c.cycle);
  for (auto _ : state) c.TimedCycle();
  benchmark::DoNotOptimize(c.ekf.state().data());
  state.counters["states"] = c.ekf.layout().size;
  state.counters["sim_s"] = 0.01 * static_cast<double>(c.cycle) - t0;
}

void RunCycles(benchmark::State& state, const VehicleConfig& v, bool slip_aware, bool steering = true,
               bool angles = false) {
  RunCycles(state, v, Converged::Config(slip_aware, angles), steering);
}

void BM_CycleSwerve(benchmark::State& state) { RunCycles(state, rowloc::mapio::AgrimaroSwerveConfig(), false); }
void BM_CycleSwerveSlipAware(benchmark::State& state) { RunCycles(state, rowloc::mapio::AgrimaroSwerveConfig(), true); }
void BM_Cycle4ws(benchmark::State& state) { RunCycles(state, rowloc::mapio::VineyardUgv4wsConfig(), false); }
void BM_CycleDifferential(benchmark::State& state) { RunCycles(state, rowloc::mapio::DifferentialDriveConfig(), false); }
void BM_CycleTracked(benchmark::State& state) { RunCycles(state, rowloc::mapio::TrackedVehicleConfig(), false); }
void BM_Cycle4wsSlipAware(benchmark::State& state) { RunCycles(state, rowloc::mapio::VineyardUgv4wsConfig(), true); }
/// The 4WS UGV with a shipped filter file of config/filters/, against BM_Cycle4wsSlipAware.
void RunCycles4wsWithFile(benchmark::State& state, const std::string& file_name) {
  RunCycles(state, rowloc::mapio::VineyardUgv4wsConfig(),
            loc::LoadFilterConfig(std::filesystem::path(ROWLOC_SOURCE_DIR) / "config/filters" / file_name));
}
/// canopy-gnss.json: slip-aware, GNSS-bias states, correlated radius priors, three iterations of
/// the wheel-speed update.
void BM_Cycle4wsCanopyGnss(benchmark::State& state) { RunCycles4wsWithFile(state, "canopy-gnss.json"); }
/// canopy-gnss-flat.json: the same without the iterations.
void BM_Cycle4wsCanopyGnssFlat(benchmark::State& state) { RunCycles4wsWithFile(state, "canopy-gnss-flat.json"); }
/// Issue 4's cycle with wheel angles instead of speeds (wheels.angle_measurement; slip-aware).
void BM_CycleDifferentialWheelAngles(benchmark::State& state) {
  RunCycles(state, rowloc::mapio::DifferentialDriveConfig(), true, true, true);
}
void BM_CycleDifferentialSlipAware(benchmark::State& state) {
  RunCycles(state, rowloc::mapio::DifferentialDriveConfig(), true);
}
void BM_CycleSwerveWithoutSteeringMessage(benchmark::State& state) {
  RunCycles(state, rowloc::mapio::AgrimaroSwerveConfig(), false, false);
}

/// The swerve slip-aware cycle while the filter records its pass for the fixed-interval smoother
/// (VehicleEkf::EnableSmoothing; rowloc replay --smoothed), one mark every 10 cycles (the replay's
/// 0.1 s estimate period). The backward pass after the run is not timed (one pass per mark, far
/// fewer than the nodes).
void BM_CycleSwerveSlipAwareSmoothing(benchmark::State& state) {
  Converged c(rowloc::mapio::AgrimaroSwerveConfig(), true);
  c.ekf.EnableSmoothing();
  for (auto _ : state) {
    const bool mark = c.cycle % 10 == 0;
    c.TimedCycle();
    if (mark) c.ekf.MarkForSmoothing();
  }
  state.counters["states"] = c.ekf.layout().size;
  state.counters["nodes_per_cycle"] =
      static_cast<double>(c.ekf.smoother()->nodes()) / static_cast<double>(state.iterations());
}

/// x and P of the converged 18-state swerve filter.
struct Snapshot {
  VehicleConfig vehicle = rowloc::mapio::AgrimaroSwerveConfig();
  loc::FilterConfig config = Converged::Config(true);
  loc::StateLayout layout = loc::StateLayout::For(vehicle, true);
  Eigen::VectorXd x;
  Eigen::MatrixXd p;
  Snapshot() {
    Converged c(vehicle, true);
    x = c.ekf.state();
    p = c.ekf.covariance();
  }
};

void BM_RestoreStateAndCovariance(benchmark::State& state) {
  const Snapshot s;
  Eigen::VectorXd x = s.x;
  Eigen::MatrixXd p = s.p;
  for (auto _ : state) {
    x = s.x;
    p = s.p;
    benchmark::DoNotOptimize(x.data());
    benchmark::DoNotOptimize(p.data());
  }
}

void BM_PredictStep(benchmark::State& state) {
  const Snapshot s;
  Eigen::VectorXd x = s.x;
  Eigen::MatrixXd p = s.p;
  for (auto _ : state) {
    x = s.x;
    p = s.p;
    loc::PredictStep(s.vehicle, s.layout, s.config, x, p, 0.01);
    benchmark::DoNotOptimize(x.data());
    benchmark::DoNotOptimize(p.data());
  }
}

void BM_KalmanUpdate2d(benchmark::State& state) {
  const Snapshot s;
  const loc::LinearizedMeasurement h = loc::GpsAntennaModel(s.x, s.vehicle.gnss_antenna.position_m.head<2>());
  const Eigen::VectorXd innovation = Eigen::Vector2d(0.01, -0.005);
  const Eigen::MatrixXd noise = Eigen::Matrix2d::Identity() * 1e-4;
  const double gate = loc::ChiSquareGate(2, 0.9999);
  Eigen::VectorXd x = s.x;
  Eigen::MatrixXd p = s.p;
  if (!loc::KalmanUpdate(x, p, innovation, h.jacobian, noise, gate, loc::StateLayout::kPhi).accepted) {
    state.SkipWithError("benchmark update is gated out");
    return;
  }
  for (auto _ : state) {
    x = s.x;
    p = s.p;
    auto outcome = loc::KalmanUpdate(x, p, innovation, h.jacobian, noise, gate, loc::StateLayout::kPhi);
    benchmark::DoNotOptimize(outcome);
    benchmark::DoNotOptimize(p.data());
  }
}

}  // namespace

BENCHMARK(BM_CycleSwerve);
BENCHMARK(BM_CycleSwerveSlipAware);
BENCHMARK(BM_Cycle4ws);
BENCHMARK(BM_Cycle4wsSlipAware);
BENCHMARK(BM_Cycle4wsCanopyGnss);
BENCHMARK(BM_Cycle4wsCanopyGnssFlat);
BENCHMARK(BM_CycleDifferential);
BENCHMARK(BM_CycleDifferentialSlipAware);
BENCHMARK(BM_CycleDifferentialWheelAngles);
BENCHMARK(BM_CycleTracked);
BENCHMARK(BM_CycleSwerveWithoutSteeringMessage);
BENCHMARK(BM_CycleSwerveSlipAwareSmoothing);
BENCHMARK(BM_RestoreStateAndCovariance);
BENCHMARK(BM_PredictStep);
BENCHMARK(BM_KalmanUpdate2d);
