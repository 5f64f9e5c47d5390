// Writers of the simulator's two NDJSON streams of docs/protocol.md: the sensor log (§1) and the
// ground-truth stream (§2). The estimate stream (§3) of the baseline estimators is written by
// rowloc/formats/estimate_stream_writer.hpp; both share the helpers of rowloc/formats/ndjson_writing.hpp.
//
// One JSON object per line, keys in the documented order (nlohmann::ordered_json), numbers as
// nlohmann-json prints them (at most 17 significant digits, reading back to the same double), so
// the same inputs give the same bytes. The writers refuse what the protocol forbids instead of
// writing it: a non-finite number, a time stamp before the previous one of the same stream, a
// message before the header, a wheel or sensor name the header does not list, a wheel listed
// twice, torques for only some wheels. Each refusal is a std::invalid_argument naming the message
// type and the reason; nothing is written for a refused message.
//
// The header is formats::LogHeader (the reader's type); its `protocol` is not read: the sensor log
// says "rowloc/1" and the truth stream "rowloc-truth/1". The messages below are the simulator's own
// writer inputs (flat, per-wheel values by name), not the reader's formats:: messages.
#pragma once

#include "rowloc/formats/gnss_fix_quality.hpp"
#include "rowloc/formats/sensor_messages.hpp"

#include <Eigen/Core>

#include <limits>
#include <optional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

namespace rowloc::sim {

/// Names attached to a value, in the order of the header's list (e.g. per-wheel speeds).
using NamedValues = std::vector<std::pair<std::string, double>>;

struct GpsMessage {
  double time_s = 0.0;
  std::string sensor = "gnss";
  formats::GnssFixQuality fix = formats::GnssFixQuality::kNone;  ///< kNone: no position keys are written
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
  SensorLogWriter(std::ostream& out, formats::LogHeader header);

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
  formats::LogHeader header_;
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
  TruthLogWriter(std::ostream& out, const formats::LogHeader& header);
  void Write(const TruthRecord& record);
  std::size_t records_written() const { return records_; }

 private:
  std::ostream& out_;
  std::vector<std::string> wheels_;
  double last_time_s_ = -std::numeric_limits<double>::infinity();
  std::size_t records_ = 0;
};

}  // namespace rowloc::sim
