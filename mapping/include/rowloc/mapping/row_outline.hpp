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
//
// TraceOneSidedOutline: a part whose band points are one face only (a scan from one side of the
// row: a mobile LiDAR driven along every other alley, a drone flight along one side) has no
// measurable width at h_ref. Its hidden face is placed from the footprint of the canopy above the
// band (the "top": points higher than h_ref + band_half_width, thinned to one per kTopCellM cell),
// which such scans still see, under the assumption of vertical canopy walls (a trellised hedge):
//  1. the face's line (bin means along the principal axis, fitted again without the end caps'
//     points, which lie across the canopy), station range and median offset per station bin;
//  2. per station, over a window of one_sided_window_m, the top's cells on each side of the face
//     that are contiguous with it (gaps up to kTopGapM: beyond a wider gap lies the next row);
//     the side with more such cells holds the canopy;
//  3. the canopy's width per station: the kTopQuantile quantile of those cells' distances from
//     the face divided by kTopQuantile (cells spread evenly from the face to the far edge: the
//     quantile ignores stray cells beyond the edge and leaves that stick out), where the window
//     holds at least kMinTopCells cells; interpolated elsewhere, if at least half of the stations
//     are measured, then a running median of three;
//  4. the polygon: the right edge forward, then the left edge backward (counter-clockwise), the
//     ends closed by straight caps at the median station of the points near each end that lie
//     well inside the edges (the cap samples; the extreme station is biased outward by the
//     noise), or at the extreme station if there are none.
// SimplifyOutline then applies CGAL's Polyline_simplification_2 (polyline_simplification.hpp).
//
// TraceOneSidedOutline: a part whose band points are one face only (a scan from one side of the
// row: a mobile LiDAR driven along every other alley, a drone flight along one side) has no
// measurable width at h_ref. Its hidden face is placed from the footprint of the canopy above the
// band (the "top": points higher than h_ref + band_half_width, thinned to one per kTopCellM cell),
// which such scans still see, under the assumption of vertical canopy walls (a trellised hedge):
//  1. the face's line (bin means along the principal axis, fitted again without the end caps'
//     points, which lie across the canopy), station range and median offset per station bin;
//  2. per station, over a window of one_sided_window_m, the top's cells on each side of the face
//     that are contiguous with it (gaps up to kTopGapM: beyond a wider gap lies the next row);
//     the side with more such cells holds the canopy;
//  3. the canopy's width per station: per station bin of the window, from its farthest such
//     cell, d / 0.5^(1/n) for n cells (the farthest of n cells spread evenly over [0, W] is
//     below W 0.5^(1/n) half the time), where n >= kMinTopCellsPerBin; the median of these bins'
//     widths where there are at least kMinTopBins (the median ignores a stray cell beyond the
//     edge and follows the edge's mean position through leaves that stick out); interpolated
//     elsewhere, if at least half of the stations are measured, then a running median of three;
//  4. the polygon: the right edge forward, then the left edge backward (counter-clockwise), the
//     ends closed by straight caps at the median station of the points near each end that lie
//     well inside the edges (the cap samples; the extreme station is biased outward by the
//     noise), or at the extreme station if there are none.
// SimplifyOutline then applies CGAL's Polyline_simplification_2 (polyline_simplification.hpp).
//
// TraceOneSidedOutline: a part whose band points are one face only (a scan from one side of the
// row: a mobile LiDAR driven along every other alley, a drone flight along one side) has no
// measurable width at h_ref. Its hidden face is placed from the footprint of the canopy above the
// band (the "top": points higher than h_ref + band_half_width, thinned to one per kTopCellM cell),
// which such scans still see, under the assumption of vertical canopy walls (a trellised hedge):
//  1. the face's line (bin means along the principal axis, fitted again without the end caps'
//     points, which lie across the canopy), station range and median offset per station bin;
//  2. per station, over a window of one_sided_window_m, the top's cells on each side of the face
//     that are contiguous with it (gaps up to kTopGapM: beyond a wider gap lies the next row);
//     the side with more such cells holds the canopy;
//  3. the canopy's width W per station, where the window holds n >= kMinTopCells cells: the
//     (kTopStrays + 1)-th largest distance d from the face times (n + 1) / (n - kTopStrays) (the
//     cells spread evenly over [0, W]: E[d] = W (n - kTopStrays) / (n + 1); kTopStrays stray
//     cells beyond the edge are ignored); interpolated elsewhere, if at least half of the stations
//     are measured, then a running median of three;
//  4. the polygon: the face on one side, face + width on the other, the caps placed as in
//     TraceOutline (the end caps' band points between the face and the far edge).
// The width's spread over the stations (width_spread_m) is reported with the part: the error of
// such a part is that of the vertical-wall assumption, which the survey cannot check.
#pragma once

#include "rowloc/mapping/map_build_config.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace rowloc::mapping {

struct PartOutline {
  std::vector<Eigen::Vector2d> polygon_m;     ///< closed (first point not repeated), counter-clockwise
  std::vector<Eigen::Vector2d> centreline_m;  ///< the smoothed centre line
  double length_m = 0.0;                      ///< last station - first station
  double median_width_m = 0.0;                ///< median of left + right edge over the stations
  bool one_sided = false;                     ///< traced by TraceOneSidedOutline
  double width_spread_m = 0.0;                ///< one-sided: robust spread (IQR / 1.349) of the width
  /// Noise of the per-station edge estimates (both edges; one-sided: the face), from their second
  /// differences (1.4826 MAD / sqrt(1.5)): roughness and sampling noise the outline cannot follow.
  double edge_noise_m = 0.0;
  double width_sigma_m = 0.0;                 ///< one-sided: standard deviation of the width estimate
};

/// The top's points are thinned to the first point of each square cell of this edge (map build, step 3).
inline constexpr double kTopCellM = 0.05;
/// One-sided outlines: the widest gap between the top's cells within one canopy.
inline constexpr double kTopGapM = 0.15;
/// One-sided outlines: the fewest top cells in a station's window that measure a width.
inline constexpr std::size_t kMinTopCells = 10;
/// One-sided outlines: the quantile of the cells' distances from the face that measures the width.
inline constexpr double kTopQuantile = 0.9;

/// Traces the outline of a part (algorithm above). Returns an empty polygon if the points do not
/// give one: fewer than 3 points, no points on one side of the centre line, or a median width
/// below min_width_m (a lone face of a canopy whose other face and caps were not connected to it).
/// Throws std::invalid_argument for parameters outside their domains.
PartOutline TraceOutline(const std::vector<Eigen::Vector2d>& points_m, const OutlineParams& params);

/// Traces the outline of a part seen from one side (algorithm above) from its band points
/// (`face_m`) and the top's cells near it (`top_m`, any others are ignored). Returns an empty
/// polygon if the face has fewer than 3 points, params.one_sided_max_width_m is 0 (the route is
/// off), the top is seen along less than half the part, or the width is below min_width_m.
/// Throws std::invalid_argument for parameters outside their domains.
PartOutline TraceOneSidedOutline(const std::vector<Eigen::Vector2d>& face_m, const std::vector<Eigen::Vector2d>& top_m,
                                 const OutlineParams& params);

}  // namespace rowloc::mapping
