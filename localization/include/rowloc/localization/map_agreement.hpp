// Does the row map agree with the rangers? A set-up error the chi-square gates do not name
// (docs/map-aided-update.md §1, "Set-up checks"): a map of another field, or one with a wrong
// origin. Most echoes then find no row segment where the map says the rows are. Over the last
// `window_echoes` echoes with a range (every ranger), the fraction without a segment in their cone
// (or with the ranger predicted inside a canopy outline) at or above suspect_no_segment_fraction
// makes the map suspect. The shipped drives peak at 0.14 over 100 echoes (headland turns) and 0.07
// over 300; a map of another field gave 0.84 over 200.
//
// Not here: a ranger mounted elsewhere than the vehicle file says. Its ranges are biased against
// the map, but with four rangers the bias is confounded with the filter's own across and heading
// errors and with a lane of the map narrower or wider than the canopy (docs/notes/
// 2026-12-04-map-agreement.md measures a window-mean model that could not tell them apart); it
// needs a calibration over a whole drive.
//
// The monitor only counts; the map-aided update (map_aided_updater.cpp) feeds it, and the filter
// reports what it finds through the sensor health (sensor_health.hpp: "map suspect: ...").
#pragma once

#include <cstddef>
#include <deque>
#include <optional>
#include <string>

namespace rowloc::localization {

struct MapAgreementConfig {
  std::size_t window_echoes = 100;           ///< echoes (all rangers) in the no-segment fraction, >= 2
  double suspect_no_segment_fraction = 0.6;  ///< in (0, 1]
};

class MapAgreementMonitor {
 public:
  /// Throws std::invalid_argument for a window < 2 or a fraction outside (0, 1].
  explicit MapAgreementMonitor(MapAgreementConfig config = {});

  /// An echo with a range reached the map: found_segment when a row segment was in its cone and
  /// the ranger was not predicted inside a canopy outline.
  void ObserveEcho(bool found_segment);

  /// Why the map looks wrong, or nullopt (also while fewer than window_echoes echoes were seen).
  std::optional<std::string> MapProblem() const;

 private:
  MapAgreementConfig config_;
  std::deque<bool> recent_no_segment_;
  std::size_t no_segment_in_window_ = 0;
};

}  // namespace rowloc::localization
