// Small helpers of the sensor message types (see sensor_messages.hpp).
#include "rowloc/localization/sensor_messages.hpp"

#include <variant>

namespace rowloc::localization {
namespace {

std::string_view TypeName(const GpsMessage&) { return "gps"; }
std::string_view TypeName(const ImuMessage&) { return "imu"; }
std::string_view TypeName(const WheelsMessage&) { return "wheels"; }
std::string_view TypeName(const SteeringMessage&) { return "steering"; }
std::string_view TypeName(const UltrasonicMessage&) { return "ultrasonic"; }
std::string_view TypeName(const VioMessage&) { return "vio"; }

}  // namespace

std::string_view GnssFixQualityName(GnssFixQuality fix) {
  switch (fix) {
    case GnssFixQuality::kNone: return "none";
    case GnssFixQuality::kSbas: return "sbas";
    case GnssFixQuality::kRtkFloat: return "rtk_float";
    case GnssFixQuality::kRtkFixed: return "rtk_fixed";
  }
  return "none";
}

double TimeOf(const SensorMessage& message) {
  return std::visit([](const auto& m) { return m.time_s; }, message);
}

std::string_view TypeOf(const SensorMessage& message) {
  return std::visit([](const auto& m) { return TypeName(m); }, message);
}

}  // namespace rowloc::localization
