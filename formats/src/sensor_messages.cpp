// Small helpers of the sensor message types (see sensor_messages.hpp).
#include "rowloc/formats/sensor_messages.hpp"

#include <variant>

namespace rowloc::formats {
namespace {

std::string_view TypeName(const GpsMessage&) { return "gps"; }
std::string_view TypeName(const ImuMessage&) { return "imu"; }
std::string_view TypeName(const WheelsMessage&) { return "wheels"; }
std::string_view TypeName(const SteeringMessage&) { return "steering"; }
std::string_view TypeName(const UltrasonicMessage&) { return "ultrasonic"; }
std::string_view TypeName(const VioMessage&) { return "vio"; }

}  // namespace

double TimeOf(const SensorMessage& message) {
  return std::visit([](const auto& m) { return m.time_s; }, message);
}

std::string_view TypeOf(const SensorMessage& message) {
  return std::visit([](const auto& m) { return TypeName(m); }, message);
}

}  // namespace rowloc::formats
