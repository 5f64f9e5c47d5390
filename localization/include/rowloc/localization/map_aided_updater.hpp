// The map-aided ultrasonic update, up to the Kalman update (issue 5; issue 29 item 2): from one
// echo and the predicted pose (X, Y, phi) with its 3x3 covariance, the measurement the filter
// applies, or why there is none. map_aided_ranging.hpp states the models (echo model, segment
// selection, association checks 1-3, the three methods); this class only runs them in order:
//   1. heading check (k sigma_phi against the cone's half aperture),
//   2. the candidate segments of a cone cast (RowMapRanging::Candidates), the sensor inside a
//      canopy outline, no segment in the cone,
//   3. the candidate with the smallest range NIS, then the lane check and the along check (near a
//      corner: the full model, the across-row model only, or nothing),
//   4. the measurement of config.method (MakeMapAidedMeasurement) with the range sigma of the
//      RangeNoiseEstimator (the canopy's roughness, estimated from the echoes' innovations; fed
//      with this echo's innovation after its measurement is made); a cut that does not update is
//      counted (contradicting, uninformative, degenerate).
// It owns what the echoes need between messages: the row map (RowMapRanging), its candidate
// buffers and R-tree cache, the rangers' mounts, the chi-square gates, the counts (MapAidedStats),
// the map agreement monitor (map_agreement.hpp) and the range noise estimator. The filter (VehicleEkf,
// vehicle_ekf_map_aided.cpp) applies the returned measurement to its full state, reports the map
// agreement through its sensor health and completes the echo's trace with the posterior.
#pragma once

#include "rowloc/formats/sensor_messages.hpp"
#include "rowloc/geometry/row_map.hpp"
#include "rowloc/geometry/segment_index.hpp"
#include "rowloc/localization/filter_config.hpp"
#include "rowloc/localization/map_agreement.hpp"
#include "rowloc/localization/map_aided_ranging.hpp"
#include "rowloc/localization/range_noise_estimator.hpp"
#include "rowloc/localization/range_to_line_model.hpp"
#include "rowloc/mapio/vehicle_config.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace rowloc::localization {

/// What happened to the ultrasonic echoes offered to the map-aided update (the accepted and gated
/// ones are in the update records); counts since construction.
struct MapAidedStats {
  std::size_t echoes = 0;         ///< echoes with a range while a map is attached and the filter runs
  std::size_t no_segment = 0;     ///< no row segment inside the predicted cone within max_range_m
  std::size_t ambiguous = 0;      ///< more than one candidate segment (a corner, or a prediction error)
  std::size_t contradicting = 0;  ///< cut methods: the slab misses the k-sigma ellipse (reported, not clipped)
  std::size_t uninformative = 0;  ///< cut methods: the slab holds the whole ellipse (nothing to update)
  std::size_t degenerate = 0;     ///< no usable geometry (grazing beam, sensor on a vertex, degenerate slab)
  // Echoes not used because their association is not certain (map_aided_ranging.hpp, checks 1-3):
  std::size_t heading_uncertain = 0;  ///< k sigma_phi above the cone's half aperture
  std::size_t inside_outline = 0;     ///< the predicted sensor inside a canopy outline
  std::size_t lane_ambiguous = 0;     ///< k sigma of the predicted range above half the lane clearance
  /// Echoes near a corner whose along-row association is ambiguous: k sigma along the row above
  /// half the distance to the next corner, or for an echo from a point above the cone's footprint
  /// (check 4). Used across the row only (counted also in the
  /// accepted or gated ones), or not at all when their range is mostly along-row (outcome
  /// "along_ambiguous").
  std::size_t along_ambiguous = 0;
};

/// What one echo did to the position (the ellipse before and after it), for plots and debugging:
/// filled for every echo with a range that reaches the map-aided update (MapAidedStats::echoes).
struct EchoTrace {
  std::string sensor;
  double measured_range_m = 0.0;
  /// "accepted", "gated", "no_segment", "contradicting", "uninformative", "degenerate",
  /// "heading_uncertain", "inside_outline", "lane_ambiguous" or "along_ambiguous".
  std::string outcome;
  Eigen::Vector2d prior_position_m = Eigen::Vector2d::Zero();
  Eigen::Matrix2d prior_covariance = Eigen::Matrix2d::Zero();      ///< of the position, m^2
  Eigen::Vector2d posterior_position_m = Eigen::Vector2d::Zero();  ///< = prior unless accepted
  Eigen::Matrix2d posterior_covariance = Eigen::Matrix2d::Zero();
  std::optional<geometry::Segment2> segment;  ///< the row segment of the chosen candidate
  std::optional<EdgeLine> line;               ///< its local straight row (normal towards the sensor)
};

/// What the updater made of one echo (MapAidedUpdater::Measure).
struct MapAidedEcho {
  /// The echo's trace, posterior = prior. Its outcome is empty when `measurement` is set: the
  /// filter's update decides it ("accepted" or "gated") and fills the posterior.
  EchoTrace trace;
  /// The measurement of the pose (X, Y, phi) to apply, or none (trace.outcome says why).
  std::optional<MapAidedMeasurement> measurement;
  double gate = 0.0;  ///< chi-square gate of the measurement's dimension (config.gate_probability)
  /// True every kAgreementEveryEchoes echoes: the map agreement was evaluated, and map_problem is
  /// its finding (nullopt: the map agrees) for the sensor health's "map".
  bool agreement_checked = false;
  std::optional<std::string> map_problem;
};

class MapAidedUpdater {
 public:
  /// Echoes between two evaluations of the map's agreement (map_agreement.hpp).
  static constexpr std::size_t kAgreementEveryEchoes = 20;

  /// The rangers are the vehicle's `ultrasonic` mounts (lever arm and yaw; vehicle order), with the
  /// cone of `config`; filter_origin: the filter's local frame, which maps are re-expressed in.
  /// Throws FilterConfigError for a config that FilterConfigProblem refuses.
  MapAidedUpdater(const mapio::VehicleConfig& vehicle, const MapAidedConfig& config,
                  const geometry::GeoOrigin& filter_origin);

  /// Uses this row map from now on (replacing any map attached before). Throws
  /// std::invalid_argument for an invalid map (e.g. no rows), or when the vehicle has no ranger.
  void AttachRowMap(const geometry::RowMap& map);
  bool has_row_map() const { return ranging_ != nullptr; }
  /// The attached map in the filter's frame, or null.
  const RowMapRanging* ranging() const { return ranging_.get(); }
  /// The same, shared (the session's mount check fits against it instead of building its own).
  std::shared_ptr<const RowMapRanging> shared_ranging() const { return ranging_; }
  const MapAidedStats& stats() const { return stats_; }
  /// The cache of R-tree box queries of the row map (hits and misses since construction).
  const geometry::SegmentQueryCache& row_search_cache() const { return buffers_.query_cache; }
  const MapAidedConfig& config() const { return config_; }
  /// The range sigma the echoes are weighted with now, m (config().range_sigma_m, or above it as
  /// estimated from the echoes' innovations: range_noise_estimator.hpp).
  double range_sigma_m() const { return range_noise_.sigma_m(); }

  /// Index of the ranger `name` in the vehicle's `ultrasonic` list, if it lists it; `hint` (the
  /// message's index in the log header, usually the vehicle's order) is tried first.
  std::optional<std::size_t> RangerIndex(const std::string& name, std::size_t hint) const;

  /// The measurement of one echo at the predicted pose (X, Y, phi; m, m, rad) with its covariance
  /// (positive definite); counted in stats(). Throws std::logic_error without a row map, and
  /// std::invalid_argument (nothing counted) for an echo without a finite positive range_m or from
  /// a ranger the vehicle does not list.
  MapAidedEcho Measure(const formats::UltrasonicMessage& ping, const Eigen::Vector3d& pose,
                       const Eigen::Matrix3d& pose_covariance);

 private:
  /// Refuses (std::invalid_argument) what Measure cannot use; returns the ranger's mount.
  const RangeSensorMount& CheckedMount(const formats::UltrasonicMessage& ping) const;
  /// The candidates of the cone cast; feeds the map agreement (and evaluates it when due).
  const std::vector<EchoCandidate>& FindCandidates(const Eigen::Vector3d& pose, const Eigen::Matrix3d& pose_covariance,
                                                   const RangeSensorMount& mount, MapAidedEcho& echo);
  /// The candidate with the smallest range NIS (the first of equal ones).
  const EchoCandidate& Nearest(const std::vector<EchoCandidate>& candidates, const RangeSensorMount& mount,
                               double measured_range_m, const Eigen::Matrix3d& pose_covariance) const;
  /// Counts a cut that did not update, and names it in the trace.
  void CountCutFailure(geometry::CutStatus status, EchoTrace& trace);

  MapAidedConfig config_;
  std::string vehicle_name_;                 ///< for the error messages
  geometry::GeoOrigin filter_origin_;
  std::vector<std::string> ranger_names_;    ///< vehicle order
  std::vector<RangeSensorMount> mounts_;     ///< vehicle order
  double gate_1_ = 0.0, gate_2_ = 0.0;       ///< 1- and 2-dimensional measurements
  std::shared_ptr<const RowMapRanging> ranging_;  ///< null: no map, echoes are not used
  /// Reused by every echo: scratch, and the cache of R-tree results, which changes no result.
  RowMapRanging::Buffers buffers_;
  MapAidedStats stats_;
  MapAgreementMonitor map_agreement_;  ///< does the map agree with the echoes?
  RangeNoiseEstimator range_noise_;    ///< the range sigma in use (the canopy's roughness)
};

}  // namespace rowloc::localization
