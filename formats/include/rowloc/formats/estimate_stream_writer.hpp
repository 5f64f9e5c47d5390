// Writer of the estimate stream of docs/protocol.md §3: an `estimate_header`, then `estimate` and
// `update` lines. Written by `rowloc replay` (the EKF and its smoothed track) and by the simulator's
// baseline estimators; read back by trajectory_streams.hpp.
//
// One JSON object per line, keys in the documented order, numbers as nlohmann-json prints them (at
// most 17 significant digits, reading back to the same double), so the same records give the same
// bytes. The writer refuses what the protocol forbids instead of writing it: a non-finite number, a
// time before the previous line's (estimate and update lines share one clock), a covariance that is
// not symmetric positive semi-definite, duplicate or empty wheel names, a calibration value out of its
// domain, a sensor health with an unknown state or a repeated or empty sensor name. Each refusal is a std::invalid_argument naming the line type and the reason; nothing is
// written for a refused record.
#pragma once

#include "rowloc/formats/wheel_calibration_record.hpp"
#include "rowloc/geometry/row_map.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <limits>
#include <optional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

namespace rowloc::formats {

/// One sensor's health in an `estimate` line (docs/protocol.md §3, `sensor_health`): the filter's
/// verdict on it (state "ok", "suspect" or "excluded"), why, and its update counts since the start.
struct SensorHealthRecord {
  std::string sensor;
  std::string state;   ///< "ok", "suspect" or "excluded"
  std::string reason;  ///< empty when ok
  std::size_t accepted = 0, gated = 0, skipped = 0, refused = 0;
};

/// One `estimate` line.
struct EstimateRecord {
  double time_s = 0.0;
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  std::optional<double> heading_rad;
  /// Covariance of (x, y, phi) when heading_rad is set, of (x, y) otherwise (top-left block used).
  std::optional<Eigen::Matrix3d> covariance;
  /// Estimated slip per wheel name (SAE slip, or track slip i), written as `slip` when not empty.
  std::vector<std::pair<std::string, double>> slip;
  /// Calibration states per wheel, written as `wheel_calibration` when not empty.
  std::vector<WheelCalibrationRecord> wheel_calibration;
  /// Sensors the filter distrusts (not ok), written as `sensor_health` when not empty.
  std::vector<SensorHealthRecord> sensor_health;
};

/// One measurement update (docs/protocol.md §3 `update` line).
struct UpdateLogRecord {
  double time_s = 0.0;
  std::string sensor;
  Eigen::VectorXd innovation;             ///< length m >= 1
  Eigen::MatrixXd innovation_covariance;  ///< m x m, symmetric
  double nis = 0.0;                       ///< y^T S^-1 y, finite
  bool accepted = false;
};

/// Writes an estimate stream (docs/protocol.md §3): estimate and update lines.
class EstimateLogWriter {
 public:
  /// Writes the `estimate_header` line. Throws std::invalid_argument for an invalid origin.
  EstimateLogWriter(std::ostream& out, const std::string& source, const std::string& vehicle,
                    const geometry::GeoOrigin& origin);
  /// Throws std::invalid_argument for non-finite values, time going backwards, or a covariance
  /// that is not symmetric and positive semi-definite (up to round-off).
  void Write(const EstimateRecord& record);
  /// An `update` line; same time order as the estimate lines. Throws std::invalid_argument for
  /// an empty sensor name, sizes that do not match or non-finite innovation/covariance/NIS.
  void WriteUpdate(const UpdateLogRecord& record);

 private:
  std::ostream& out_;
  double last_time_s_ = -std::numeric_limits<double>::infinity();
};

}  // namespace rowloc::formats
