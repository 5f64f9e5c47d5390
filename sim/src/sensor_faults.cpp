// Parsing of a scenario's sensor faults (sensor_faults.hpp).
#include "rowloc/sim/sensor_faults.hpp"

#include "rowloc/mapio/detail/json_object_reader.hpp"
#include "rowloc/sim/scenario.hpp"

#include <algorithm>

namespace rowloc::sim {
namespace {

using Reader = mapio::detail::JsonObjectReader<ScenarioError>;
constexpr double kMaxTimeS = 1e7;     ///< a fault's time inside a scenario, s
constexpr double kMaxOffsetM = 1e7;   ///< 10,000 km
constexpr double kMaxJumpS = 1e18;    ///< the fuzzer's offset
constexpr std::size_t kMaxFaults = 1000;

}  // namespace

bool SensorFaults::GnssOut(double time_s) const {
  // The first outage ending after time_s (they are sorted and apart).
  const auto it = std::upper_bound(gnss_outages.begin(), gnss_outages.end(), time_s,
                                   [](double t, const GnssOutageFault& o) { return t < o.end_s; });
  return it != gnss_outages.end() && time_s >= it->start_s;
}

SensorFaults ParseSensorFaults(std::string_view json_object_text, std::string_view source_name,
                               std::string_view key_path_prefix, const std::vector<std::string>& wheel_names) {
  const std::string source(source_name);
  const nlohmann::json json = mapio::detail::ParseJsonText<ScenarioError>(json_object_text, source);
  Reader reader(json, source, std::string(key_path_prefix));
  SensorFaults faults;
  if (reader.Has("gnss_outliers")) {
    faults.gnss_outliers = reader.ObjectArray(
        "gnss_outliers",
        [](Reader& item) {
          GnssOutlierFault f{item.NumberIn("t_s", 0.0, kMaxTimeS), item.Vector<2>("offset_m")};
          if (f.offset_m.cwiseAbs().maxCoeff() > kMaxOffsetM) item.Fail(item.Key("offset_m"), "must be within 1e7 m");
          item.RejectUnknownKeys();
          return f;
        },
        1, kMaxFaults);
  }
  if (reader.Has("gnss_outages")) {
    faults.gnss_outages = reader.ObjectArray(
        "gnss_outages",
        [](Reader& item) {
          GnssOutageFault f{item.NumberIn("start_s", 0.0, kMaxTimeS), item.NumberIn("end_s", 0.0, kMaxTimeS)};
          if (!(f.end_s > f.start_s)) item.Fail(item.Key("end_s"), "must be after start_s");
          item.RejectUnknownKeys();
          return f;
        },
        1, kMaxFaults);
    for (std::size_t i = 1; i < faults.gnss_outages.size(); ++i) {
      if (faults.gnss_outages[i].start_s < faults.gnss_outages[i - 1].end_s) {
        reader.Fail(reader.Key("gnss_outages"), "outage " + std::to_string(i) + " starts before outage " +
                                                    std::to_string(i - 1) + " ends: give them in time order, apart");
      }
    }
  }
  if (reader.Has("imu_dead_after_s")) faults.imu_dead_after_s = reader.NumberIn("imu_dead_after_s", 0.0, kMaxTimeS);
  if (reader.Has("wheel_encoders_dead")) {
    faults.wheel_encoders_dead = reader.ObjectArray(
        "wheel_encoders_dead",
        [&](Reader& item) {
          WheelEncoderDeadFault f{item.String("wheel"), item.NumberIn("after_s", 0.0, kMaxTimeS)};
          if (std::find(wheel_names.begin(), wheel_names.end(), f.wheel) == wheel_names.end()) {
            item.Fail(item.Key("wheel"), "'" + f.wheel + "' is not a wheel of the vehicle");
          }
          item.RejectUnknownKeys();
          return f;
        },
        1, kMaxFaults);
  }
  if (reader.Has("ultrasonic_stuck_after_s")) {
    faults.ultrasonic_stuck_after_s = reader.NumberIn("ultrasonic_stuck_after_s", 0.0, kMaxTimeS);
  }
  if (reader.Has("clock_jump")) {
    Reader jump = reader.Object("clock_jump");
    faults.clock_jump = ClockJumpFault{jump.NumberIn("after_s", 0.0, kMaxTimeS), jump.NumberIn("jump_s", 1e-3, kMaxJumpS)};
    jump.RejectUnknownKeys();
  }
  reader.RejectUnknownKeys();
  return faults;
}

}  // namespace rowloc::sim
