// Ranger mount calibration from a recorded drive along a known row map (issue 28): `rowloc
// calibrate`. The drive is read into a DriveRecord (drive_record.hpp: the echoes, and the filter's
// smoothed trajectory without the rangers as the reference), then the mounts are fitted by
// localization::FitRangerMounts (localization/ranger_mount_fit.hpp states the least-squares problem,
// its observability and why most mounts are assumed right).
#pragma once

#include "rowloc/calibration/drive_record.hpp"
#include "rowloc/geometry/row_map.hpp"
#include "rowloc/localization/filter_config.hpp"
#include "rowloc/localization/ranger_mount_fit.hpp"
#include "rowloc/mapio/vehicle_config.hpp"

#include <stdexcept>
#include <string>

namespace rowloc::calibration {

using localization::RangerMountEstimate;
using localization::RangerMountFit;

struct RangerCalibrationConfig {
  double knot_interval_s = 0.2;  ///< a reference pose every this much log time, s
  localization::RangerMountFitConfig fit;
};

class RangerCalibrationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Reads a configuration overlay: a JSON object with any subset of the keys knot_interval_s and
/// those of RangerMountFitConfig, by their C++ names (docs/calibration.md), on the defaults. Throws
/// RangerCalibrationError for an unknown key, a wrong type or a value outside its domain.
RangerCalibrationConfig ParseRangerCalibrationConfig(const std::string& json_text, const std::string& source);
/// Throws RangerCalibrationError when a value is outside its domain.
void ValidateRangerCalibrationConfig(const RangerCalibrationConfig& config);

/// Fits the vehicle's ranger mounts to the drive against the map. The map may be in another local
/// frame than the drive's (re-expressed as the filter does); filter.map_aided supplies the sound
/// cone, the range limit and the row smoothing. Throws RangerCalibrationError for an invalid map or
/// configuration, a vehicle without rangers, or a drive whose echoes mostly meet no row of the map.
RangerMountFit CalibrateRangers(const DriveRecord& drive, const geometry::RowMap& map,
                                const mapio::VehicleConfig& vehicle, const localization::FilterConfig& filter,
                                const RangerCalibrationConfig& config = {});

/// The vehicle with every calibrated ranger's mount moved to its estimate (height and yaw kept).
mapio::VehicleConfig ApplyRangerCalibration(mapio::VehicleConfig vehicle, const RangerMountFit& calibration);

}  // namespace rowloc::calibration
