// A recorded drive as the ranger calibration needs it (ranger_calibration.hpp): the echoes of the
// log, and a reference trajectory from the filter without the rangers.
//
// The reference is the vehicle EKF (localization/vehicle_ekf.hpp) run over the log with every
// sensor except the ultrasonic ones (GNSS, IMU, wheel and steering encoders, VIO), then smoothed
// with the fixed-interval smoother (fixed_interval_smoother.hpp), sampled every knot_interval_s of
// log time: its across-row error is the GNSS's, a few centimetres to decimetres, slowly varying,
// which the calibration corrects per knot. The rangers are left out so that a wrong mount cannot
// bend the reference it is measured against.
#pragma once

#include "rowloc/formats/sensor_messages.hpp"
#include "rowloc/geometry/row_map.hpp"
#include "rowloc/localization/filter_config.hpp"
#include "rowloc/localization/ranger_mount_fit.hpp"
#include "rowloc/mapio/vehicle_config.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <istream>
#include <stdexcept>
#include <string>
#include <vector>

namespace rowloc::calibration {

using localization::EchoRecord;
using localization::ReferenceKnot;

struct DriveRecord {
  geometry::GeoOrigin origin;          ///< the log's local frame
  std::vector<ReferenceKnot> knots;    ///< time order, initialised filter only
  std::vector<EchoRecord> echoes;      ///< time order
  std::size_t pings_without_echo = 0;  ///< pings with no range (nothing in the cone)
  std::size_t refused_messages = 0;    ///< messages the reader or the filter refused (logged, not used)
};

class DriveRecordError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Reads the sensor log (docs/protocol.md §1, or a service journal) from `log` and builds the
/// record. source: the log's name in messages. Throws DriveRecordError when the vehicle has no
/// ultrasonic sensor, knot_interval_s is not positive, a ping names a ranger the vehicle does not
/// list, the filter never initialises, or the log has no echo; formats::SensorLogError for an
/// unreadable header. A malformed message line is refused, counted and logged (spdlog), as
/// `rowloc replay` does.
DriveRecord ReadDriveRecord(std::istream& log, const std::string& source, const mapio::VehicleConfig& vehicle,
                            const localization::FilterConfig& filter, double knot_interval_s);

}  // namespace rowloc::calibration
