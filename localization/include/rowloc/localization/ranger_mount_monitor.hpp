// Online check of the rangers' mounts (issue 28): a ranger whose echoes fit the row map only with
// its mount moved along its beam is reported, while the vehicle drives.
//
// The localization session (localization_session.hpp) gives the monitor the filter's pose (a knot
// every knot_interval_s) and every echo; every check_every_s it fits the mounts to the last window_s
// of them (ranger_mount_fit.hpp: the filter's poses as the reference, corrected per knot; the
// soft-L1 prior that most mounts are right). A ranger is suspect when its along-beam correction
// exceeds both suspect_offset_m and k_sigma of its 1-sigma in `confirmations` consecutive fits, and
// ok again after as many fits that do not find it. The filter's own estimate is not changed (a suspect ranger's echoes are still used:
// the gate and the sensor health decide that); the user is told which ranger, by how much, and to
// run `rowloc calibrate`.
//
// Why a fit over a window and not per echo: with four side rangers a single ranger's bias is
// confounded, echo by echo, with the filter's across and heading error (the filter absorbs part of
// it); the fit separates them with the vehicle's kinematics over many metres of row
// (docs/notes/2026-12-04-map-agreement.md has the per-echo attempts that failed).
// A window whose echoes mostly meet no row (a wrong map, a lost lane) is not judged: the map
// agreement check (map_agreement.hpp) reports that case.
#pragma once

#include "rowloc/geometry/row_map.hpp"
#include "rowloc/localization/filter_config.hpp"
#include "rowloc/localization/map_aided_ranging.hpp"
#include "rowloc/localization/ranger_mount_fit.hpp"
#include "rowloc/mapio/vehicle_config.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace rowloc::localization {

struct RangerMountMonitorConfig {
  double window_s = 20.0;          ///< the fit uses the poses and echoes of the last window_s, s
  double check_every_s = 5.0;      ///< log time between fits, s
  double min_span_s = 10.0;        ///< the first fit waits until the poses span this much, s
  double knot_interval_s = 0.2;    ///< a pose every this much log time, s
  double max_pose_jump_m = 1.0;    ///< a pose this far from the last (a re-initialisation) restarts the window
  double suspect_offset_m = 0.02;  ///< an along-beam correction above this ...
  double k_sigma = 5.0;            ///< ... and above k_sigma of its 1-sigma makes the ranger suspect
  /// Consecutive fits that must agree before a ranger becomes suspect, or ok again (a window that
  /// holds a headland turn has few echoes and little heading information: one such fit blamed the
  /// opposite ranger once in a drive).
  int confirmations = 2;
  RangerMountFitConfig fit = [] {
    RangerMountFitConfig f;
    f.outer_iterations = 2;  // the filter's poses are close: one re-association suffices
    return f;
  }();
};

/// A ranger whose mount the last check found off.
struct RangerMountFinding {
  std::string ranger;
  double along_beam_m = 0.0;  ///< the fitted correction along its beam (+: nearer to what it hears)
  double sigma_m = 0.0;       ///< its 1-sigma
};

class RangerMountMonitor {
 public:
  /// ranging: the row map the filter uses, in its frame (VehicleEkf::row_map_ranging: shared, not
  /// built twice); mounts: the vehicle's ultrasonic list. Throws std::invalid_argument for a null
  /// map or an invalid configuration (non-positive times, window below min_span_s).
  RangerMountMonitor(std::shared_ptr<const RowMapRanging> ranging, std::vector<mapio::SensorMount> mounts,
                     const MapAidedConfig& map_aided, RangerMountMonitorConfig config = {});

  /// The filter's pose (X, Y, phi) and body rates (v_x, v_y, r) at time_s (the motion between
  /// knots is dead-reckoned from the rates: the filter's positions jump with its updates); kept
  /// when knot_interval_s has passed since the last.
  void ObservePose(double time_s, const Eigen::Vector3d& pose, const Eigen::Vector3d& body_rates);
  /// An echo of ranger `ranger` (index in the mounts), range in m.
  void ObserveEcho(double time_s, std::size_t ranger, double range_m);
  /// The filter lost its state (re-initialisation): the window starts again.
  void Restart();
  /// Fits the window when check_every_s has passed since the last fit (and the window spans
  /// min_span_s). Returns true when the set of suspect rangers changed (their offsets, updated by
  /// every fit, are in suspects()).
  bool Check(double time_s);

  const std::vector<RangerMountFinding>& suspects() const { return suspects_; }
  /// The reason a user reads for a finding.
  static std::string Reason(const RangerMountFinding& finding, double window_s);
  const RangerMountMonitorConfig& config() const { return config_; }
  std::size_t checks() const { return checks_; }  ///< fits run so far

 private:
  void DropBefore(double time_s);

  std::shared_ptr<const RowMapRanging> ranging_;
  std::vector<mapio::SensorMount> mounts_;
  MapAidedConfig map_aided_;
  RangerMountMonitorConfig config_;
  std::deque<ReferenceKnot> knots_;
  std::deque<EchoRecord> echoes_;
  std::optional<double> last_check_s_;
  std::vector<RangerMountFinding> suspects_;  ///< vehicle order
  std::vector<int> streak_;  ///< per ranger: consecutive fits that disagree with its current state
  std::vector<bool> suspect_;
  std::size_t checks_ = 0;
};

}  // namespace rowloc::localization
