// Health of each sensor of a filter run: ok, suspect or excluded, with the reason and counts
// (docs/localization-filter.md §7). A chi-square gate rejects single outliers; it cannot tell which
// sensor is wrong when one sensor drags the state and the others are then gated against it (a dead
// IMU reading zeros: the filter follows it and gates the GNSS fixes and the wheels). The monitor
// looks at two kinds of evidence that do not depend on the state the faulty sensor corrupted:
//
//  1. Stuck readings: a sensor whose readings repeat exactly for stuck_messages messages while the
//     wheels say the vehicle moves (a live MEMS IMU's noise, a live ultrasonic ranger's echo, a live
//     GNSS receiver's fix never repeat to the last bit while driving) is stuck (dead or frozen).
//  2. Persistent inconsistency: the fraction of a sensor's last `window` updates gated out by the
//     chi-square test (Bar-Shalom, Li & Kirubarajan 2001, §5.4: a consistent filter rejects
//     1 - p of them) at or above suspect_gated_fraction.
//
// States: suspect when either holds; excluded when a stuck sensor is suspect while another
// sensor is persistently inconsistent (the stuck one disagrees with all others and is the one to
// distrust), or while its own updates are persistently inconsistent. The filter skips an excluded
// sensor's updates and re-initialises without it (vehicle_ekf.hpp). A stuck sensor recovers (ok)
// after stuck_messages readings that change; refusals (bad values, time jumps) are counted and make
// the sensor suspect until its next accepted message. A disagreement found by another check (a ranger
// biased against the map, a map of another field: map_agreement.hpp) makes it suspect while it lasts.
#pragma once

#include <cstddef>
#include <deque>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace rowloc::localization {

enum class SensorHealthState { kOk, kSuspect, kExcluded };
/// "ok", "suspect", "excluded".
std::string_view SensorHealthStateName(SensorHealthState state);

struct SensorHealthConfig {
  std::size_t window = 20;               ///< updates per sensor in the gated fraction
  double suspect_gated_fraction = 0.5;   ///< in (0, 1]
  std::size_t stuck_messages = 50;       ///< identical readings while moving that make a sensor stuck
  double moving_speed_mps = 0.05;        ///< mean wheel-centre speed above which the vehicle moves
};

struct SensorHealth {
  std::string sensor;
  SensorHealthState state = SensorHealthState::kOk;
  std::string reason;            ///< empty when ok
  std::size_t accepted = 0;      ///< updates since the start
  std::size_t gated = 0;
  std::size_t skipped = 0;       ///< updates not made while excluded
  std::size_t refused = 0;       ///< messages refused (bad values, time jumps)
};

class SensorHealthMonitor {
 public:
  explicit SensorHealthMonitor(SensorHealthConfig config = {});

  /// The raw readings of one message of `sensor`; moving: the wheels say the vehicle moves.
  void ObserveReadings(const std::string& sensor, std::span<const double> readings, bool moving);
  /// One update of `sensor` (accepted or gated out by the chi-square test).
  void ObserveUpdate(const std::string& sensor, bool accepted);
  /// An update of an excluded sensor that was not made.
  void ObserveSkipped(const std::string& sensor);
  /// A message of `sensor` refused before any update (why: the refusal's text).
  void ObserveRefusal(const std::string& sensor, const std::string& why);
  /// A message of `sensor` accepted (clears a refusal's suspicion).
  void ObserveAccepted(const std::string& sensor);
  /// A check outside the monitor (the map agreement, map_agreement.hpp) finds `sensor` (a ranger,
  /// or "map") disagreeing, why; nullopt: it agrees again. Suspect while it disagrees.
  void ObserveDisagreement(const std::string& sensor, const std::optional<std::string>& why);

  bool Excluded(const std::string& sensor) const;
  /// Every sensor seen, by name.
  std::vector<SensorHealth> Report() const;
  /// Transitions to excluded since the start, and the sensor of the last one.
  std::size_t exclusions() const { return exclusions_; }
  const std::string& last_excluded() const { return last_excluded_; }
  /// The sensors whose state changed since the last call, as one line ("imu excluded: ..."), or none.
  std::optional<std::string> TakeChanges();

 private:
  struct Track {
    SensorHealth health;
    std::deque<bool> recent_gated;       ///< the last `window` updates: true = gated
    std::vector<double> last_readings;
    std::size_t repeats = 0;             ///< identical consecutive readings while moving
    std::size_t changing = 0;            ///< changing readings since it became stuck
    bool stuck = false;
    std::optional<std::string> refusal;  ///< the last message was refused: why
    std::optional<std::string> disagreement;  ///< ObserveDisagreement: why
  };
  bool Inconsistent(const Track& track) const;
  void Evaluate();

  SensorHealthConfig config_;
  std::map<std::string, Track, std::less<>> tracks_;
  std::vector<std::string> changes_;
  std::size_t exclusions_ = 0;
  std::string last_excluded_;
};

}  // namespace rowloc::localization
