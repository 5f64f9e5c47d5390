// One localization run: the vehicle EKF (vehicle_ekf.hpp) with its vehicle, filter configuration and
// optional row map, fed sensor messages in time order, emitting the estimate stream of
// docs/protocol.md §3. `rowloc replay` (a log file) and `rowloc serve` (a socket session) both run
// their messages through this type, so that a replayed journal gives the service's states bit for bit.
//
// Per message: the filter processes it (predict to its time, then its update); every update is
// counted per sensor (accepted / gated, last NIS) and, with record_updates, returned as an `update`
// record; an `estimate` record (pose, (x, y, phi) covariance, per-wheel slip, wheel calibration) is
// returned whenever the filter's time has advanced estimate_period_s since the last one (with
// `sensor_health`, the sensors the filter distrusts: sensor_health.hpp). Slip is the
// SAE slip of wheel_slip_estimate.hpp from the filtered state and the raw encoder speeds, or for a
// skid-steer vehicle the track slip i = 1 - eta of the adaptive observer (track_slip_observer.hpp)
// fed with the filtered pose and the raw sprocket speeds.
// A message the filter refuses (FilterInputError: non-finite, out of range, time going backwards)
// leaves the filter unchanged and is reported in the output's `error`, never thrown.
#pragma once

#include "rowloc/formats/estimate_stream_writer.hpp"
#include "rowloc/formats/sensor_messages.hpp"
#include "rowloc/localization/filter_config.hpp"
#include "rowloc/localization/ranger_mount_monitor.hpp"
#include "rowloc/localization/track_slip_observer.hpp"
#include "rowloc/localization/vehicle_ekf.hpp"
#include "rowloc/mapio/vehicle_config.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace rowloc::localization {

/// The `source` of the estimate stream a session's estimates are written in (docs/protocol.md §3),
/// by `rowloc replay` and by the service alike, so that both write the same bytes.
inline constexpr const char* kEstimateStreamSource = "rowloc filter";

struct SessionOptions {
  double estimate_period_s = 0.1;  ///< log time between estimate records, > 0
  bool record_updates = true;      ///< return an update record per measurement update (finite NIS)
  std::vector<std::string> skip_types;  ///< message types not given to the filter (ablation runs)
  /// With a row map: check the rangers' mounts against it while driving (ranger_mount_monitor.hpp);
  /// a ranger found off is reported in the estimates' sensor_health and as a notice.
  bool check_ranger_mounts = true;
};

/// What one message did.
struct SessionStep {
  bool skipped = false;                            ///< its type is in skip_types (not processed)
  std::optional<std::string> error;                ///< the filter (or track observer) refused it
  std::optional<std::string> notice;               ///< initialisation, re-initialisation
  std::vector<formats::UpdateLogRecord> updates;   ///< with record_updates
  std::optional<formats::EstimateRecord> estimate; ///< when an estimate period has passed
  std::optional<EchoTrace> echo;                   ///< an ultrasonic echo with a row map attached
  bool changed_state = false;                      ///< the filter's state or time changed
};

/// Accepted and gated updates of one sensor since the start, and the last NIS.
struct SensorUpdateCounts {
  std::size_t accepted = 0;
  std::size_t gated = 0;
  double last_nis = std::numeric_limits<double>::quiet_NaN();
};

class LocalizationSession {
 public:
  /// header: the wheel order and origin of the messages (a log's header). Throws what VehicleEkf
  /// throws for a bad configuration, and std::invalid_argument for bad options.
  LocalizationSession(mapio::VehicleConfig vehicle, FilterConfig config, const formats::LogHeader& header,
                      SessionOptions options = {});

  /// Uses ultrasonic echoes against the map (VehicleEkf::AttachRowMap; throws std::invalid_argument),
  /// and checks the rangers' mounts against it (SessionOptions::check_ranger_mounts).
  void AttachRowMap(const geometry::RowMap& map);
  /// The rangers' mount check, once a row map is attached (and the check is on).
  const RangerMountMonitor* ranger_mount_monitor() const { return mount_monitor_ ? &*mount_monitor_ : nullptr; }
  /// The R_w and kappa priors of a previous drive (VehicleEkf::SetWheelCalibrationPrior).
  void SetWheelCalibrationPrior(const std::vector<WheelCalibrationPrior>& wheels) {
    ekf_.SetWheelCalibrationPrior(wheels);
  }
  /// Initialises (or overrides) the pose (VehicleEkf::SetPose; throws FilterInputError).
  void SetPose(double time_s, const Eigen::Vector3d& pose, const Eigen::Matrix3d& covariance);
  /// Records the run for fixed-interval smoothing (VehicleEkf::EnableSmoothing); every estimate
  /// record is then also a smoothing mark.
  void EnableSmoothing();
  /// The smoothed estimates at the times of the estimate records (after the last message).
  std::vector<formats::EstimateRecord> FinishSmoothing();

  /// Processes one message (see the header comment). Never throws for bad input.
  SessionStep Process(const formats::SensorMessage& message);

  /// The estimate record of the current state (what an estimate line would say now). Requires an
  /// initialised filter (std::logic_error otherwise).
  formats::EstimateRecord CurrentEstimate() const;

  const VehicleEkf& filter() const { return ekf_; }
  const formats::LogHeader& header() const { return header_; }
  const SessionOptions& options() const { return options_; }
  const std::map<std::string, SensorUpdateCounts>& update_counts() const { return counts_; }
  std::size_t messages() const { return messages_; }         ///< given to Process
  std::size_t refused() const { return refused_; }           ///< with an error
  std::size_t skipped() const { return skipped_; }
  std::size_t estimates() const { return estimates_; }
  std::size_t ultrasonic_pings() const { return ultrasonic_; }
  /// Log time of the last accepted GNSS update, if any.
  std::optional<double> last_fix_time_s() const { return last_fix_time_s_; }

 private:
  /// Track slip per wheel name (skid steer, once the observer runs), else empty.
  std::vector<std::pair<std::string, double>> TrackSlip() const;
  formats::EstimateRecord EstimateOf(double time_s, const Eigen::VectorXd& x, const Eigen::MatrixXd& p,
                                     const std::vector<double>& speeds_radps) const;
  /// Feeds the track-slip observer after a wheels message; false with `error` when it refused.
  bool ObserveTracks(const formats::SensorMessage& message, std::string& error);
  void CountUpdates(const ProcessResult& result, SessionStep& step);
  /// Feeds the mount check with the filter's pose and the message's echo; its changes as a notice.
  void CheckRangerMounts(const formats::SensorMessage& message, SessionStep& step);

  mapio::VehicleConfig vehicle_;
  formats::LogHeader header_;
  SessionOptions options_;
  VehicleEkf ekf_;
  std::optional<TrackSlipObserver> tracks_;
  std::optional<RangerMountMonitor> mount_monitor_;
  std::size_t right_track_ = 0;
  std::map<std::string, SensorUpdateCounts> counts_;
  std::size_t messages_ = 0, refused_ = 0, skipped_ = 0, estimates_ = 0, ultrasonic_ = 0;
  std::optional<double> last_fix_time_s_;
  double next_estimate_s_ = -std::numeric_limits<double>::infinity();
  /// Smoothing: per estimate record, its track slip and the raw speeds of that time.
  struct SmoothingMark {
    std::vector<std::pair<std::string, double>> track_slip;
    std::vector<double> speeds_radps;
  };
  std::optional<std::vector<SmoothingMark>> marks_;
};

/// The sensors the filter does not trust (suspect or excluded; VehicleEkf::health), for the
/// estimate record's `sensor_health`; empty when every sensor is ok.
std::vector<formats::SensorHealthRecord> SensorHealthOf(const VehicleEkf& ekf);

/// The calibration of every wheel (R_w, kappa and their sigmas) in state x with covariance p;
/// empty without slip-aware odometry.
std::vector<formats::WheelCalibrationRecord> WheelCalibrationOf(const VehicleEkf& ekf, const Eigen::VectorXd& x,
                                                                const Eigen::MatrixXd& p);

}  // namespace rowloc::localization
