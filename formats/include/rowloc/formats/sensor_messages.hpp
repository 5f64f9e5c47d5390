// Value types of the sensor log and the sensor messages of docs/protocol.md §1, as read by
// SensorLogReader (sensor_log_reader.hpp) and, one line at a time, by the service. LogHeader is
// also the header the simulator's writers take (sim/log_writers.hpp).
//
// SI units are named in every field (docs/protocol.md, conventions); times are seconds (double)
// since the log's epoch. Per-wheel values are stored by position in the header's wheel list, not by
// name: index i of WheelsMessage::speed_radps is the wheel LogHeader::wheels[i]. Absence is explicit:
// a GPS message without a fix has no position, an ultrasonic ping without an echo has no range
// (docs/protocol.md §1: "no echo is no measurement, never a zero range"), a wheel that is not
// steerable has no steering angle.
#pragma once

#include "rowloc/formats/gnss_fix_quality.hpp"
#include "rowloc/geometry/row_map.hpp"

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace rowloc::formats {

/// The `log_header` line (docs/protocol.md §1).
struct LogHeader {
  /// As read: "rowloc/1" (or a minor revision "rowloc/1.N"). The simulator's writers do not read it:
  /// they write the version they implement.
  std::string protocol;
  std::string source;                   ///< who wrote the log, e.g. "rowloc simulate"
  std::string scenario;                 ///< informative
  std::string vehicle;                  ///< informative (replay takes the vehicle config from its options)
  geometry::GeoOrigin origin;           ///< WGS84 origin of the local ENU frame
  std::vector<std::string> wheels;      ///< wheel (or track) names, unique; defines the wheel order
  std::vector<std::string> ultrasonic;  ///< ultrasonic sensor names, unique
  /// Optional `reorder_window_s` (a service journal, docs/service.md §8): the messages are in
  /// arrival order and are ordered within this window (s, >= 0); 0: the log is in time order.
  double reorder_window_s = 0.0;
};

/// Antenna position of a GNSS fix and the receiver's own 1-sigma claims.
struct GpsPosition {
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
  double altitude_m = 0.0;          ///< above the WGS84 ellipsoid
  double sigma_horizontal_m = 0.0;  ///< per horizontal axis, > 0
  double sigma_vertical_m = 0.0;    ///< > 0
};

struct GpsMessage {
  double time_s = 0.0;
  std::string sensor;
  GnssFixQuality fix = GnssFixQuality::kNone;
  std::optional<GpsPosition> position;  ///< set exactly when fix != kNone
};

/// Body-frame specific force (x, y) and yaw rate at the IMU, as measured.
struct ImuMessage {
  double time_s = 0.0;
  std::string sensor;
  double accel_x_mps2 = 0.0;
  double accel_y_mps2 = 0.0;
  double gyro_z_radps = 0.0;
};

/// Encoder speeds of every wheel of the header, in the header's wheel order.
struct WheelsMessage {
  double time_s = 0.0;
  std::vector<double> speed_radps;               ///< one per header wheel
  std::optional<std::vector<double>> torque_nm;  ///< absent: no torque sensing; else one per header wheel
  /// Absent: no angle output; else one per header wheel: the encoder's cumulative rotation (rad,
  /// counted ticks times the tick angle; any zero), the measurement of the wheel-angle states.
  std::optional<std::vector<double>> angle_rad;
};

/// Steering-encoder angles (body frame, 0 = straight ahead, positive to the left) in the header's
/// wheel order; nullopt for a wheel the message does not carry (not steerable).
struct SteeringMessage {
  double time_s = 0.0;
  std::vector<std::optional<double>> angle_rad;  ///< one entry per header wheel
};

/// One ping of one ultrasonic sensor.
struct UltrasonicMessage {
  double time_s = 0.0;
  std::string sensor;
  std::size_t sensor_index = 0;    ///< position of `sensor` in LogHeader::ultrasonic
  std::optional<double> range_m;   ///< nullopt: no echo (no measurement); else > 0
};

/// Visual-odometry velocity at the camera, body frame.
struct VioMessage {
  double time_s = 0.0;
  std::string sensor;
  double velocity_x_mps = 0.0;
  double velocity_y_mps = 0.0;
  double sigma_mps = 0.0;  ///< claimed 1-sigma per axis, > 0
};

using SensorMessage =
    std::variant<GpsMessage, ImuMessage, WheelsMessage, SteeringMessage, UltrasonicMessage, VioMessage>;

/// The time stamp (s) of any sensor message.
double TimeOf(const SensorMessage& message);

/// The protocol's `type` of a message: "gps", "imu", "wheels", "steering", "ultrasonic" or "vio".
std::string_view TypeOf(const SensorMessage& message);

}  // namespace rowloc::formats
