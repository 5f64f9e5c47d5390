// Writers of the three NDJSON streams of docs/protocol.md: the sensor log (§1), the ground-truth
// stream (§2) and the estimate stream (§3, written here for the simulator's baseline estimators).
//
// One JSON object per line, keys in the documented order (nlohmann::ordered_json), numbers as
// nlohmann-json prints them (at most 17 significant digits, reading back to the same double), so
// the same inputs give the same bytes. The writers refuse what the protocol forbids instead of writing it: a non-finite number,
// a time stamp before the previous one of the same stream, a message before the header, a wheel or
// sensor name the header does not list, a wheel listed twice, torques for only some wheels. Each refusal is a std::invalid_argument naming the message
// type and the reason; nothing is written for a refused message.
#pragma once

#include "rowloc/geometry/row_map.hpp"
#include "rowloc/sim/gnss_model.hpp"
#include "rowloc/sim/wheel_calibration_record.hpp"

#include <Eigen/Core>

#include <limits>
#include <optional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

namespace rowloc::sim {

/// "none", "sbas", "rtk_float", "rtk_fixed" (docs/protocol.md, `gps`).
std::string_view GnssFixQualityName(GnssFixQuality fix);

/// Names attached to a value, in the order of the header's list (e.g. per-wheel speeds).
using NamedValues = std::vector<std::pair<std::string, double>>;

struct LogHeader {
  std::string source = "rowloc simulate";
  std::string scenario;
  std::string vehicle;
  geometry::GeoOrigin origin;
  std::vector<std::string> wheels;      ///< wheel (or track) names
  std::vector<std::string> ultrasonic;  ///< ultrasonic sensor names
};

struct GpsMessage {
  double time_s = 0.0;
  std::string sensor = "gnss";
  GnssFixQuality fix = GnssFixQuality::kNone;  ///< kNone: no position keys are written
  double latitude_deg = 0.0, longitude_deg = 0.0, altitude_m = 0.0;
  double sigma_horizontal_m = 0.0, sigma_vertical_m = 0.0;
};

struct ImuMessage {
  double time_s = 0.0;
  std::string sensor = "imu";
  double accel_x_mps2 = 0.0, accel_y_mps2 = 0.0, gyro_z_radps = 0.0;
};

struct WheelsMessage {
  double time_s = 0.0;
  NamedValues speed_radps;  ///< every wheel of the header
  NamedValues torque_nm;    ///< optional: empty means "no torque sensor"
  NamedValues angle_rad;    ///< optional: the encoders' cumulative angle (ticks x tick angle), every wheel or none
};

struct SteeringMessage {
  double time_s = 0.0;
  NamedValues angle_rad;  ///< steerable wheels only
};

struct UltrasonicMessage {
  double time_s = 0.0;
  std::string sensor;
  std::optional<double> range_m;  ///< nullopt: no echo (written as null)
};

struct VioMessage {
  double time_s = 0.0;
  std::string sensor = "camera";
  double velocity_x_mps = 0.0, velocity_y_mps = 0.0;  ///< at the camera, body frame
  double sigma_mps = 0.0;                             ///< claimed 1-sigma per axis
};

/// Writes a sensor log: the header first, then messages in non-decreasing time.
class SensorLogWriter {
 public:
  /// Writes the header line. Throws std::invalid_argument for an invalid origin or duplicate names.
  SensorLogWriter(std::ostream& out, LogHeader header);

  void Write(const GpsMessage& message);
  void Write(const ImuMessage& message);
  void Write(const WheelsMessage& message);
  void Write(const SteeringMessage& message);
  void Write(const UltrasonicMessage& message);
  void Write(const VioMessage& message);

  std::size_t messages_written() const { return messages_; }

 private:
  void CheckTime(const char* type, double time_s);
  void CheckWheels(const char* type, const NamedValues& values, bool all_required) const;
  void Emit(const std::string& line);
  /// Emits a message line and advances the stream's time and count.
  void EmitMessage(const std::string& line, double time_s);

  std::ostream& out_;
  LogHeader header_;
  double last_time_s_ = -std::numeric_limits<double>::infinity();
  std::size_t messages_ = 0;
};

/// Ground truth of one wheel at one instant (docs/protocol.md §2).
struct WheelTruthRecord {
  std::string name;
  double steering_rad = 0.0, speed_radps = 0.0, slip = 0.0, rolling_radius_m = 0.0, torque_nm = 0.0;
  std::string terrain;
};

struct TruthRecord {
  double time_s = 0.0;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  ///< reference point, ENU (z on the terrain)
  double heading_rad = 0.0;
  double velocity_x_mps = 0.0, velocity_y_mps = 0.0, yaw_rate_radps = 0.0;
  double accel_x_mps2 = 0.0, accel_y_mps2 = 0.0;  ///< specific force at the reference point, body frame
  bool gnss_available = true;
  bool gnss_multipath = false;
  double canopy_cover = 0.0;
  double imu_bias_accel_x_mps2 = 0.0, imu_bias_accel_y_mps2 = 0.0, imu_bias_gyro_z_radps = 0.0;
  std::vector<WheelTruthRecord> wheels;
};

/// Writes the ground-truth stream: a truth_header (the log header's keys) then truth lines.
class TruthLogWriter {
 public:
  TruthLogWriter(std::ostream& out, const LogHeader& header);
  void Write(const TruthRecord& record);
  std::size_t records_written() const { return records_; }

 private:
  std::ostream& out_;
  std::vector<std::string> wheels_;
  double last_time_s_ = -std::numeric_limits<double>::infinity();
  std::size_t records_ = 0;
};

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

}  // namespace rowloc::sim
