// Quality of a built row map against the true one (issue 27): Hausdorff-type distances between
// the outlines and which rows were found, missed or invented.
//
// Both maps' outlines are sampled every sample_step_m (vertices included). For every sample of one
// map, its distance to the nearest segment of the other map (R-tree, geometry::SegmentIndex); the
// p95 and the maximum are taken over the samples of both directions (the maximum is the Hausdorff
// distance of the two outline sets). A built part is matched to the true part that holds the
// nearest segment of most of its samples, if their median distance is at most match_distance_m;
// a true part without any built part matched is missed, a built part without a match is invented.
// Rows are counted by their base id (before ".part-N"). Maps with different origins are compared
// in the true map's frame (built vertices through WGS84, mapio::LocalFrame).
#pragma once

#include "rowloc/geometry/row_map.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <string>
#include <vector>

namespace rowloc::mapping {

struct MapComparisonParams {
  double sample_step_m = 0.01;
  double match_distance_m = 0.3;
};

struct PartMatch {
  std::string built_id;
  std::string truth_id;    ///< empty: invented
  double p95_m = 0.0;      ///< over this part's samples (built -> truth)
  double max_m = 0.0;
  double rms_m = 0.0;          ///< over this part's samples (built -> truth)
  double stated_sigma_m = 0.0; ///< the built part's own outline_sigma_m (its estimate of rms_m)
  Eigen::Vector2d worst_m = Eigen::Vector2d::Zero();  ///< the sample at max_m (true map's frame)
};

struct MapComparison {
  std::size_t truth_parts = 0;
  std::size_t built_parts = 0;
  std::size_t truth_rows = 0;
  std::size_t built_rows = 0;
  std::size_t truth_parts_found = 0;
  std::size_t truth_rows_found = 0;       ///< true rows with at least one part found
  std::vector<std::string> missed;        ///< true part ids without a match
  std::vector<std::string> invented;      ///< built part ids without a match
  std::vector<PartMatch> matches;         ///< one per built part
  double p95_m = 0.0;                     ///< over the samples of both directions
  double max_m = 0.0;                     ///< Hausdorff distance
  double built_to_truth_p95_m = 0.0;
  double truth_to_built_p95_m = 0.0;
  double built_to_truth_rms_m = 0.0;      ///< RMS over the built map's samples
  double stated_sigma_rms_m = 0.0;        ///< RMS of the built parts' outline_sigma_m over the same samples
  std::size_t samples = 0;
};

/// Compares (algorithm above). Throws std::invalid_argument for a step or distance that is not
/// positive and finite, or an empty map.
MapComparison CompareRowMaps(const geometry::RowMap& built, const geometry::RowMap& truth,
                             const MapComparisonParams& params = {});

/// Plain-text summary (several lines) and JSON text of a comparison.
/// The largest distance of `from`'s outlines, sampled every step_m as CompareRowMaps samples them,
/// to the nearest segment of `to` (the directed Hausdorff distance; both maps in one frame, their
/// origins ignored). Segments of `to` shorter than 1 nm are left out. 0 when `from` has no
/// segments; infinity when `to` has none. Throws std::invalid_argument unless step_m > 0.
double LargestDistanceToOutlines(const geometry::RowMap& from, const geometry::RowMap& to, double step_m);

std::string FormatMapComparison(const MapComparison& comparison);
std::string FormatMapComparisonJson(const MapComparison& comparison);

}  // namespace rowloc::mapping
