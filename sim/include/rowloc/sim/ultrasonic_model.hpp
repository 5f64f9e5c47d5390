// Ultrasonic rangers against the exact canopy of a RowWorld (the design's "ultrasonic noise, cone,
// missed echoes"; issue 3, "Sensors": "0.02-4 m, 15 degree cone cast against the exact canopy
// geometry, not voxels ... missed echoes"). Documented in docs/simulation-world.md.
//
// Geometry: an echo comes from the nearest reflecting point inside the beam (geometry/cone_cast.hpp),
//   r* = min { |x - apex| : x on the canopy outline at the sensor's height h above the terrain,
//              angle(x - apex, axis) <= half_aperture }.
// The outline at h is RowWorld::OutlineAt(h_q, step) with h quantized to h_q = quantum * round(h /
// quantum) (it only selects which stations carry canopy: faces are vertical), indexed by
// geometry::SegmentIndex (exact per-segment cone casts). The sampled outline is a chord polygon of
// the true surface, within M step^2 / 8 of it (RowWorld::OutlineCurvatureBound); the step is
// RowWorld::StepForTolerance(tolerance), tolerance 0.05 mm by default, far below the 3 mm sensor
// sigma (about 2.6 mm steps for 1.5 cm roughness of 0.1 m wavelength, 0.15 m for a smooth canopy;
// the bound is checked against the true surface in tests/sim/ultrasonic_model_test.cpp). The cast is 2-D: the
// terrain under the echo point is taken at the sensor's height above the terrain (the band edge
// moves by grade * range; see the doc).
//
// Measurement: each Measure() draws, in this order and always (so that the random stream does
// not depend on the geometry), u ~ U[0, 1) and n ~ N(0, 1) (Box-Muller from two uniform draws)
// from its own std::mt19937_64. No echo (nullopt) if no canopy point is in the cone within
// max_range, if r* < min_range (blind zone), if u < miss_probability, or if the noisy range
// r* + sigma n is outside [min_range, max_range] (rejected, not clamped).
#pragma once

#include "rowloc/geometry/cone_cast.hpp"
#include "rowloc/geometry/segment_index.hpp"
#include "rowloc/sim/row_world.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <map>
#include <numbers>
#include <optional>
#include <random>

namespace rowloc::sim {

/// The nearest canopy point in a cone.
struct CanopyEcho {
  double range_m = 0.0;                             ///< |point - apex|
  Eigen::Vector2d point_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d normal = Eigen::Vector2d::UnitY();///< outline normal facing the apex
  int row = 0;                                      ///< 0-based row index
};

/// The canopy outline at one height above the terrain, indexed for cone casts.
class CanopySlice {
 public:
  /// Throws std::invalid_argument as RowWorld::OutlineAt. No canopy at that height is valid.
  CanopySlice(const RowWorld& world, double height_m, double step_m);
  double height_m() const { return height_m_; }
  const geometry::SegmentIndex& index() const { return index_; }
  /// Nearest canopy point in the cone; throws std::invalid_argument for a bad cone (cone_cast.hpp).
  std::optional<CanopyEcho> ConeCast(const geometry::Cone2& cone) const;

 private:
  double height_m_;
  geometry::SegmentIndex index_;
};

/// Casts cones at any height, building (and keeping) one CanopySlice per quantized height.
/// Holds a reference to the world, which must outlive it.
class CanopyCaster {
 public:
  /// Samples the outline with world.StepForTolerance(tolerance_m). Throws std::invalid_argument
  /// unless tolerance is in [1e-9, 1] m and quantum in [1e-4, 1] m.
  explicit CanopyCaster(const RowWorld& world, double tolerance_m = 5e-5, double height_quantum_m = 0.01);
  double step_m() const { return step_m_; }
  /// Nearest canopy point in the cone at height h above the terrain (quantized). Throws
  /// std::invalid_argument for a non-finite height or a bad cone.
  std::optional<CanopyEcho> ConeCast(const geometry::Cone2& cone, double height_m);
  std::size_t cached_slices() const { return slices_.size(); }

 private:
  const RowWorld& world_;
  double step_m_;
  double height_quantum_m_;
  std::map<long long, CanopySlice> slices_;
};

struct UltrasonicParams {
  double min_range_m = 0.02;                                 ///< blind zone
  double max_range_m = 4.0;
  double half_aperture_rad = 7.5 * std::numbers::pi / 180.0; ///< 15 degree cone
  double range_sigma_m = 0.003;                              ///< sigma_us of Donati 2021
  double miss_probability = 0.0;                             ///< in [0, 1]
  bool operator==(const UltrasonicParams&) const = default;
};

/// Why the parameters are unusable, or nullopt.
std::optional<std::string> UltrasonicParamsProblem(const UltrasonicParams& params);

struct UltrasonicReading {
  double range_m = 0.0;       ///< measured (noisy) range
  CanopyEcho truth;           ///< the exact echo it came from
};

class UltrasonicModel {
 public:
  /// Throws std::invalid_argument with UltrasonicParamsProblem's message.
  UltrasonicModel(const UltrasonicParams& params, std::uint64_t seed);
  const UltrasonicParams& params() const { return params_; }

  /// One measurement of a sensor at apex (ENU metres) pointing along axis (normalized here), at
  /// height h above the terrain. Throws std::invalid_argument for non-finite inputs or a zero axis.
  std::optional<UltrasonicReading> Measure(CanopyCaster& caster, const Eigen::Vector2d& apex_m,
                                           const Eigen::Vector2d& axis, double height_m);

 private:
  UltrasonicParams params_;
  std::mt19937_64 rng_;
};

}  // namespace rowloc::sim
