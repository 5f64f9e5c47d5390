// The simulator's names for the shared vehicle configuration (rowloc/mapio/vehicle_config.hpp): the
// file format and its parser live in mapio so that localization reads the same files without
// depending on the simulator.
#pragma once

#include "rowloc/mapio/vehicle_config.hpp"

namespace rowloc::sim {

using mapio::AgrimaroSwerveConfig;
using mapio::DifferentialDriveConfig;
using mapio::LoadVehicleConfig;
using mapio::ParseVehicleConfig;
using mapio::SensorMount;
using mapio::TrackedVehicleConfig;
using mapio::TrackParameters;
using mapio::VehicleConfig;
using mapio::VehicleConfigError;
using mapio::VehicleConfigProblem;
using mapio::VehicleKind;
using mapio::VehicleKindFromName;
using mapio::VehicleKindName;
using mapio::VineyardUgv4wsConfig;
using mapio::WheelGeometry;

}  // namespace rowloc::sim
