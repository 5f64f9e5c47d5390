// Sensor faults a simulation scenario can inject (docs/simulation-scenarios.md, "faults"), so that
// the filter's defences (consensus initialisation, sensor health, clock checks;
// docs/localization-filter.md §2 and §7) are tested on the faults they are meant for:
//
//   gnss_outliers       [{t_s, offset_m: [east, north]}]: the first fix at or after t_s is moved by
//                       offset_m (a multipath or software fault; 111 m or 4,000 km)
//   gnss_outages        [{start_s, end_s}]: no GNSS message at all in [start_s, end_s) (a tunnel of
//                       canopy, a receiver reset); sorted, not overlapping. Unlike
//                       sensors.gnss.off_after_s the fixes come back, so a loss can sit in the
//                       middle of a run and a run can have several
//   imu_dead_after_s    from then on the IMU reads exactly 0 on every axis (a dead or unplugged IMU)
//   wheel_encoders_dead [{wheel, after_s}]: from then on that encoder reads 0 rad/s and its angle
//                       stops (a broken encoder cable)
//   ultrasonic_stuck_after_s  from then on every ranger repeats its last range
//   clock_jump          {after_s, jump_s}: every message's stamp from after_s on is t + jump_s (the
//                       logger's clock jumps; 1e18 s is the fuzzer's offset)
//
// The object is optional in a scenario; each key inside it is optional (absent: no such fault). The
// truth is never faulted. Values are checked like every scenario value (finite, in range, the wheel
// named by the vehicle), errors naming the key path.
#pragma once

#include <Eigen/Core>

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rowloc::sim {

struct GnssOutlierFault {
  double time_s = 0.0;
  Eigen::Vector2d offset_m = Eigen::Vector2d::Zero();
};

struct GnssOutageFault {
  double start_s = 0.0;
  double end_s = 0.0;  ///< > start_s; the first message at or after end_s is written again
};

struct WheelEncoderDeadFault {
  std::string wheel;
  double after_s = 0.0;
};

struct ClockJumpFault {
  double after_s = 0.0;
  double jump_s = 0.0;  ///< added to every stamp from after_s on; > 0 (the log's time never decreases)
};

struct SensorFaults {
  std::vector<GnssOutlierFault> gnss_outliers;
  std::vector<GnssOutageFault> gnss_outages;  ///< sorted by start_s, not overlapping
  std::optional<double> imu_dead_after_s;
  std::vector<WheelEncoderDeadFault> wheel_encoders_dead;
  std::optional<double> ultrasonic_stuck_after_s;
  std::optional<ClockJumpFault> clock_jump;

  bool empty() const {
    return gnss_outliers.empty() && gnss_outages.empty() && !imu_dead_after_s && wheel_encoders_dead.empty() && !ultrasonic_stuck_after_s &&
           !clock_jump;
  }
  /// Whether time_s [s] falls in one of the GNSS outages.
  bool GnssOut(double time_s) const;
  /// The stamp a message sampled at time_s carries.
  double Stamp(double time_s) const { return clock_jump && time_s >= clock_jump->after_s ? time_s + clock_jump->jump_s : time_s; }
};

/// Parses the "faults" object (its JSON text); wheel_names: the vehicle's. Errors (ScenarioError)
/// name source_name and the key path under key_path_prefix.
SensorFaults ParseSensorFaults(std::string_view json_object_text, std::string_view source_name,
                               std::string_view key_path_prefix, const std::vector<std::string>& wheel_names);

}  // namespace rowloc::sim
