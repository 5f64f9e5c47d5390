// One simulated run of a scenario (issue 3): the vehicle drives its route, every sensor
// samples the exact truth through its error model on its own clock, and the run writes the sensor
// log, the ground-truth stream and two baseline estimate streams (docs/protocol.md,
// docs/simulation-scenarios.md).
//
// Clocks: sensor j samples at t_k = phase_j + k / rate_j for t_k <= route duration (k counted, not
// accumulated, so no drift); ultrasonic sensor i of N pings at phase i / (N rate), everything else
// at phase 0. The messages of all sensors are merged in time order; at equal times the order is
// gnss, imu, steering, wheels, vio, ultrasonic sensors (so a consumer sees the gyro and the steering
// angles of an instant before the wheel speeds of that instant).
//
// Truth per message (vehicle_truth.hpp):
//  - gps: the antenna's true ENU position through GnssModel with the canopy cover over the antenna
//    (canopy_cover.hpp), converted to WGS84 with the scenario origin (GeographicLib, LocalFrame).
//    After sensors.gnss.off_after_s no gps message is written.
//  - imu: specific force at the IMU mount and the yaw rate through ImuModel.
//  - wheels: each encoder gets the mean true wheel rate over (t_{k-1}, t_k] (Simpson's rule on the
//    exact rate: the encoder model counts ticks of the integral); torque readings, if configured,
//    are the true torque at t_k plus white noise.
//  - steering: the true steering angle of each steerable wheel through its encoder model.
//  - vio: the body-frame velocity of the camera point (v + r x p) plus white noise.
//  - ultrasonic: the exact canopy cone cast from the mount (ultrasonic_model.hpp).
// Randomness: each stream has its own std::mt19937_64 seeded with StreamSeed(seed, stream id), so
// adding or removing one sensor leaves the others' noise unchanged, and a run is a pure function of
// (scenario, seed): same inputs, same bytes.
//
// Baselines: baseline-gnss reports each fix as a position estimate of the reference point with the
// receiver's sigma, the antenna lever arm removed with the dead-reckoning heading (the raw antenna
// position when the odometry baseline is not written);
// baseline-odometry is DeadReckoning (dead_reckoning.hpp) over the written encoder and gyro
// messages with nominal radii and no slip model, started from the true initial pose.
#pragma once

#include "rowloc/sim/scenario.hpp"

#include <cstdint>
#include <functional>
#include <optional>
#include <ostream>

namespace rowloc::sim {

/// SplitMix64 of the seed mixed with a stream id: independent generator seeds per noise stream.
std::uint64_t StreamSeed(std::uint64_t seed, std::uint64_t stream_id);

struct SimulationOutputs {
  std::ostream* sensors = nullptr;            ///< required: the sensor log
  std::ostream* truth = nullptr;              ///< required: the ground-truth stream
  std::ostream* baseline_gnss = nullptr;      ///< optional
  std::ostream* baseline_odometry = nullptr;  ///< optional
};

struct SimulationOptions {
  std::optional<std::uint64_t> seed;          ///< overrides the scenario's seed
  /// Called about every 1 % of the simulated time with (simulated time, duration), in seconds.
  std::function<void(double, double)> progress;
};

struct SimulationSummary {
  double duration_s = 0.0;
  std::size_t sensor_messages = 0, truth_records = 0;
  std::size_t gps_fixes = 0, gps_no_fix = 0, gps_multipath = 0;
  std::size_t imu = 0, wheels = 0, steering = 0, vio = 0;
  std::size_t ultrasonic_echoes = 0, ultrasonic_no_echo = 0;
  std::size_t traction_limited_samples = 0;   ///< wheel samples at the traction limit (truth)
  double max_abs_slip = 0.0;                  ///< over all wheels and truth records
  double distance_m = 0.0;                    ///< route length
  double baseline_odometry_final_error_m = 0.0;  ///< |dead reckoning - truth| at the end (if run)
};

/// Runs the scenario. Throws std::invalid_argument for missing required outputs or a motion the
/// vehicle cannot drive, and whatever the models throw for invalid parameters; an output stream
/// that fails to write gives std::runtime_error.
SimulationSummary RunSimulation(const Scenario& scenario, const SimulationOutputs& outputs,
                                const SimulationOptions& options = {});

}  // namespace rowloc::sim
