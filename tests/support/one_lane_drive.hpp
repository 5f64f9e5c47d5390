// Simulated drives of vineyard-002-4us's world, vehicle, sensors and seed with its route edited (one
// lane; a start inside a lane): the sensor log, the truth and the true row map. For tests that link
// rowloc::sim (the localization and calibration tests); the simulation's ranger mounts are the
// vehicle file's.
#pragma once

#include "rowloc/formats/trajectory_streams.hpp"
#include "rowloc/sim/row_world.hpp"
#include "rowloc/sim/scenario.hpp"
#include "rowloc/sim/simulation.hpp"
#include "test_support.hpp"

#include <nlohmann/json.hpp>

#include <fstream>
#include <functional>
#include <sstream>
#include <string>

namespace rowloc::test {

struct OneLaneDrive {
  sim::Scenario scenario;
  geometry::RowMap map;  ///< the world's true row map at the scenario's height (1 mm tolerance)
  std::string sensors;   ///< the sensor log
  formats::TruthStream truth;
};

/// vineyard-002-4us with `edit` applied to its scenario document, simulated.
inline OneLaneDrive SimulateVineyard0024us(const std::function<void(nlohmann::json&)>& edit) {
  const auto path = SourceDir() / "config/scenarios/vineyard-002-4us.json";
  std::ifstream in(path);
  nlohmann::json document = nlohmann::json::parse(in);
  edit(document);
  OneLaneDrive d{sim::ParseScenario(document.dump(), "edited", path.parent_path()), {}, {}, {}};
  const sim::RowWorld world(*d.scenario.world);
  d.map = world.TrueRowMap(d.scenario.row_map_height_m, world.StepForTolerance(1e-3));
  std::stringstream sensors, truth;
  sim::RunSimulation(d.scenario, {&sensors, &truth, nullptr, nullptr});
  d.sensors = sensors.str();
  d.truth = formats::ParseTruthStream(truth, "truth");
  return d;
}

/// vineyard-002-4us cut to its first lane (about 130 s), simulated once per test program.
inline const OneLaneDrive& SimulatedOneLaneDrive() {
  static const OneLaneDrive drive = SimulateVineyard0024us([](nlohmann::json& d) { d["route"]["lane_count"] = 1; });
  return drive;
}

/// The vehicle file as a user with a mis-measured ranger would write it: `name` moved by (dx, dy), m.
inline mapio::VehicleConfig WithRangerMoved(mapio::VehicleConfig vehicle, const std::string& name, double dx_m,
                                            double dy_m) {
  for (mapio::SensorMount& m : vehicle.ultrasonic) {
    if (m.name == name) m.position_m += Eigen::Vector3d(dx_m, dy_m, 0.0);
  }
  return vehicle;
}

}  // namespace rowloc::test
