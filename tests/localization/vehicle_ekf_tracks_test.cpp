// VehicleEkf on a tracked vehicle in a turn (docs/notes/2026-12-02-localization-filter.md §5.8): the simulator's
// tracked-circle-gnss-loss run (two laps of a 5 m circle, no GNSS after 40 s) replayed with the
// turning resistance in the tracks' traction, and without it (mu_t = 0 in the vehicle file).
#include "rowloc/formats/sensor_log_reader.hpp"
#include "rowloc/formats/trajectory_streams.hpp"
#include "rowloc/localization/vehicle_ekf.hpp"
#include "rowloc/sim/scenario.hpp"
#include "rowloc/sim/simulation.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <sstream>
#include <string>

namespace rowloc::localization {
namespace {

struct CircleRun {
  sim::Scenario scenario;
  std::string sensors;
  formats::TruthStream truth;
};

CircleRun Simulate(std::optional<std::uint64_t> seed) {
  CircleRun r{sim::LoadScenario(test::SourceDir() / "config/scenarios/tracked-circle-gnss-loss.json"), {}, {}};
  if (seed) r.scenario.seed = *seed;
  std::stringstream sensors, truth;
  sim::RunSimulation(r.scenario, {&sensors, &truth, nullptr, nullptr});
  r.sensors = sensors.str();
  r.truth = formats::ParseTruthStream(truth, "truth");
  return r;
}

const CircleRun& Circle() {
  static const CircleRun run = Simulate(std::nullopt);
  return run;
}

struct Outcome {
  int wheels_accepted = 0, wheels_gated = 0;
  double final_error_m = 0.0;
  bool slip_compliance_in_domain = true;
};

Outcome Replay(const mapio::VehicleConfig& vehicle, const CircleRun& run = Circle()) {
  std::istringstream log(run.sensors);
  formats::SensorLogReader reader(log, "sensors");
  VehicleEkf ekf(vehicle, FilterConfig{}, reader.header().origin, reader.header().wheels);
  Outcome o;
  while (const auto m = reader.Next()) {
    for (const UpdateRecord& u : ekf.Process(*m).updates) {
      if (u.sensor != "wheels") continue;
      ++(u.outcome.accepted ? o.wheels_accepted : o.wheels_gated);
    }
    for (const int k : ekf.layout().slip_compliance) o.slip_compliance_in_domain &= ekf.state()(k) >= 0.0;
  }
  const formats::TruthSample& end = run.truth.samples.back();
  EXPECT_NEAR(ekf.time_s(), end.t_s, 0.05);
  o.final_error_m = (ekf.state().head<2>() - end.position_m).norm();
  return o;
}

TEST(VehicleEkfTracks, TheTurningResistanceKeepsTheTrackSpeedsInATurn) {
  const mapio::VehicleConfig& vehicle = Circle().scenario.vehicle;
  ASSERT_TRUE(vehicle.tracks.has_value());
  ASSERT_GT(vehicle.tracks->turning_resistance_coefficient, 0.0);
  const Outcome with = Replay(vehicle);
  mapio::VehicleConfig without_term = vehicle;
  without_term.tracks->turning_resistance_coefficient = 0.0;
  const Outcome without = Replay(without_term);
  // Without the term the outer track's 0.40 slip (0.13 on the straight) is beyond what R_w can
  // absorb: the speeds are gated out for the whole circle and the 42 s without GNSS run on the IMU.
  EXPECT_LT(without.wheels_accepted, without.wheels_gated / 5);
  EXPECT_GT(without.final_error_m, 1.0);
  // With it they are used, and the loss ends within centimetres (measured: 0.006 m; 3.87 without).
  EXPECT_GT(with.wheels_accepted, 20 * with.wheels_gated);
  EXPECT_LT(with.final_error_m, 0.15);
  EXPECT_TRUE(with.slip_compliance_in_domain);
  EXPECT_TRUE(without.slip_compliance_in_domain);
}

// Seeds 7 and 9 of the same scenario ended 2.98 and 5.36 m off when a crossed kappa >= 0 was
// clamped alone: the inner track's kappa sat on 0 while its R_w, correlated with it, ran to
// 0.18 m and the speeds were gated out. The covariance-weighted projection (state_bound.hpp)
// moves R_w with kappa.
TEST(VehicleEkfTracks, AKappaOnItsBoundDoesNotDragTheRadiusAway) {
  for (const std::uint64_t seed : {7u, 9u}) {
    const CircleRun run = Simulate(seed);
    const Outcome o = Replay(run.scenario.vehicle, run);
    EXPECT_LT(o.final_error_m, 0.15) << "seed " << seed;
    EXPECT_GT(o.wheels_accepted, 20 * o.wheels_gated) << "seed " << seed;
  }
}

}  // namespace
}  // namespace rowloc::localization
