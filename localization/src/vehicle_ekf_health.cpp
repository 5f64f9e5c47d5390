// VehicleEkf: clock faults and sensor health (vehicle_ekf.hpp; sensor_health.hpp;
// docs/localization-filter.md §7).
#include "rowloc/localization/vehicle_ekf.hpp"

#include <array>
#include <cmath>
#include <sstream>
#include <string>

namespace rowloc::localization {

namespace {

/// Consecutive messages (none in between at the filter's time) that must all jump before the
/// filter accepts a new time base: a log whose clock really moved (all sensors) gets there within
/// a fraction of a second; one sensor with offset stamps, interleaved with the others, never does.
constexpr std::size_t kTimeBaseRunMessages = 50;

}  // namespace

std::string HealthSensorName(const formats::SensorMessage& message) {
  return std::visit(
      [](const auto& m) -> std::string {
        using T = std::decay_t<decltype(m)>;
        if constexpr (std::is_same_v<T, formats::WheelsMessage>) {
          return "wheels";
        } else if constexpr (std::is_same_v<T, formats::SteeringMessage>) {
          return "steering";
        } else {
          return m.sensor;
        }
      },
      message);
}

void VehicleEkf::CheckTimeJump(const formats::SensorMessage& message, std::optional<std::string>& notice) {
  const double t = formats::TimeOf(message);
  if (!(std::abs(t) <= kMaxTimeS) || !std::isfinite(time_s_) || std::abs(t - time_s_) <= config_.max_time_jump_s) {
    time_jump_run_ = 0;
    return;
  }
  ++time_jump_run_;
  std::ostringstream text;
  text.precision(6);
  if (time_jump_run_ >= kTimeBaseRunMessages) {
    text << "time base moved from t=" << time_s_ << " s to t=" << t << " s (" << time_jump_run_
         << " consecutive messages beyond max_time_jump_s " << config_.max_time_jump_s
         << " s): state dropped, re-initialising from GNSS";
    Reset();
    time_s_ = t;
    time_jump_run_ = 0;
    notice = text.str();
    return;
  }
  ++time_jumps_refused_;
  text << formats::TypeOf(message) << " at t=" << t << " s: time stamp " << std::abs(t - time_s_) << " s "
       << (t > time_s_ ? "ahead of" : "behind") << " the filter's time " << time_s_ << " s (beyond max_time_jump_s "
       << config_.max_time_jump_s << " s): a clock fault, message refused (" << time_jumps_refused_ << " so far)";
  health_.ObserveRefusal(HealthSensorName(message), "time stamp jump");
  throw FilterInputError(text.str());
}

void VehicleEkf::ObserveReadings(const formats::SensorMessage& message) {
  double speed = 0.0;  // the wheels' mean wheel-centre speed: does the vehicle move?
  for (std::size_t i = 0; i < last_speed_radps_.size(); ++i) {
    speed += std::abs(last_speed_radps_[i]) * vehicle_.wheels[i].nominal_radius_m / static_cast<double>(last_speed_radps_.size());
  }
  const bool moving = speed > SensorHealthConfig{}.moving_speed_mps;
  if (const auto* imu = std::get_if<formats::ImuMessage>(&message)) {
    const std::array<double, 3> readings{imu->accel_x_mps2, imu->accel_y_mps2, imu->gyro_z_radps};
    health_.ObserveReadings(imu->sensor, readings, moving);
  } else if (const auto* gps = std::get_if<formats::GpsMessage>(&message); gps && gps->position) {
    const std::array<double, 2> readings{gps->position->latitude_deg, gps->position->longitude_deg};
    health_.ObserveReadings(gps->sensor, readings, moving);
  } else if (const auto* ping = std::get_if<formats::UltrasonicMessage>(&message); ping && ping->range_m) {
    const std::array<double, 1> readings{*ping->range_m};
    health_.ObserveReadings(ping->sensor, readings, moving);
  } else if (const auto* wheels = std::get_if<formats::WheelsMessage>(&message)) {
    // One encoder: dead when it reads exactly 0 while the mean of the others says the vehicle moves
    // (a live encoder at constant speed may well repeat its reading: only 0 is judged).
    const std::size_t n = wheels->speed_radps.size();
    for (std::size_t j = 0; j < n && n > 1; ++j) {
      const std::size_t i = wheel_index_[j];
      const double own = std::abs(wheels->speed_radps[j]) * vehicle_.wheels[i].nominal_radius_m;
      const double others = (speed * static_cast<double>(n) - own) / static_cast<double>(n - 1);
      const std::array<double, 1> readings{wheels->speed_radps[j]};
      const bool judged = others > SensorHealthConfig{}.moving_speed_mps && wheels->speed_radps[j] == 0.0;
      if (judged || own > 0.0) {  // a turning wheel's readings end a dead period
        thread_local std::string key;  // reused: no allocation per message
        key.assign("wheels.").append(vehicle_.wheels[i].name);
        health_.ObserveReadings(key, readings, judged);
      }
    }
  }
}

bool VehicleEkf::SkipExcluded(const std::string& sensor) {
  if (!health_.Excluded(sensor)) return false;
  health_.ObserveSkipped(sensor);
  return true;
}

void VehicleEkf::ApplyHealthChanges(ProcessResult& result) {
  std::optional<std::string> changes = health_.TakeChanges();
  if (!changes) return;
  if (health_.exclusions() > exclusions_seen_) {
    exclusions_seen_ = health_.exclusions();
    // The excluded sensor may have dragged the state: start again without it. Not for a GNSS
    // receiver: the filter needs it to initialise, and it dead-reckons on while the GNSS is out.
    if (initialised_ && health_.last_excluded() != last_gnss_sensor_) {
      Reset();
      *changes += ": state dropped, re-initialising from GNSS without the excluded sensor";
    }
  }
  result.notice = result.notice ? *result.notice + "; " + *changes : *changes;
}

}  // namespace rowloc::localization
