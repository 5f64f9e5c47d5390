// Steps 5-7 of the map build (docs/mapping.md), outline route: the outline of one row part at h_ref, traced
// directly from its band points (docs/mapping.md says why this route and what the mesh route adds).
//
// TraceOutline (parameters in OutlineParams):
//  1. centre line: the part's points binned along their principal axis (centreline_bin_m); per bin
//     the mean position; the bin means smoothed by a 3-point moving average. This follows curved
//     rows as long as a part does not turn by more than ~80 degrees from its principal axis;
//  2. every point gets its station s (arc length of its projection on the centre line) and signed
//     lateral offset e (> 0 to the left);
//  3. stations every ~station_step_m from the first to the last point; per station bin, the left
//     edge is the edge_quantile quantile of the positive offsets, the right edge that of the
//     negative ones' magnitudes (0.5: the median, right for a cloud sampled on the canopy surface;
//     towards 1 for a cloud that also fills the canopy's inside). Points within end_exclusion_m of
//     the part's ends (the end caps) are left out; bins without points on a side are interpolated;
//  4. the polygon: the right edge forward, then the left edge backward (counter-clockwise), the
//     ends closed by straight caps at the median station of the points near each end that lie
//     well inside the edges (the cap samples; the extreme station is biased outward by the
//     noise), or at the extreme station if there are none.
// SimplifyOutline then applies CGAL's Polyline_simplification_2 (polyline_simplification.hpp).
#pragma once

#include "rowloc/mapping/map_build_config.hpp"

#include <Eigen/Core>

#include <vector>

namespace rowloc::mapping {

struct PartOutline {
  std::vector<Eigen::Vector2d> polygon_m;     ///< closed (first point not repeated), counter-clockwise
  std::vector<Eigen::Vector2d> centreline_m;  ///< the smoothed centre line
  double length_m = 0.0;                      ///< last station - first station
  double median_width_m = 0.0;                ///< median of left + right edge over the stations
};

/// Traces the outline of a part (algorithm above). Returns an empty polygon if the points do not
/// give one: fewer than 3 points, no points on one side of the centre line, or a median width
/// below min_width_m (a lone face of a canopy whose other face and caps were not connected to it).
/// Throws std::invalid_argument for parameters outside their domains.
PartOutline TraceOutline(const std::vector<Eigen::Vector2d>& points_m, const OutlineParams& params);

}  // namespace rowloc::mapping
