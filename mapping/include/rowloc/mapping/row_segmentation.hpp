// Steps 3-4 of the map build (docs/mapping.md): the canopy band, and the rows found in it.
//
// SelectCanopyBand keeps the points whose height above the terrain is within band_half_width_m of
// h_ref and projects them to the horizontal plane.
//
// DetectRows (algorithm, parameters in RowParams):
//  1. occupancy raster of the band points (raster_cell_m);
//  2. parts: occupied cells closer than link_radius_m are connected (a dilation), and each
//     connected set of cells is a part with the points in its cells; parts with fewer than
//     min_part_points points or shorter than min_part_length_m (extent along their principal axis)
//     are dropped as clutter;
//  3. each end of a part gets a position (the outermost point along the direction of the last
//     end_window_m of the part, fitted by PCA) and an outward direction;
//  4. ends of two parts are linked when they face each other across a gap of at most max_gap_m:
//     directions within max_link_angle_rad of opposite, the gap ahead of both ends and within
//     max_link_offset_m laterally of the line along the mean of the two end directions (on a
//     circular arc that is the chord, so curvature does not count as offset). Links are taken shortest first, at most one per end,
//     never closing a loop; the chains of linked parts are the rows. This follows curved rows (only
//     the local directions at the ends are compared) and bridges missing plants, but never joins
//     neighbouring rows (their ends are a row spacing apart laterally);
//  5. the dominant row direction is the length-weighted mean of the part axes (doubled angles),
//     turned to point to +x (+y if it is across); rows are ordered by their lateral coordinate
//     along its left normal, and the parts of a row along the chain, first the one further back.
// The gaps between linked parts stay in the outline (a row map draws canopy, not rows); the links
// only decide which parts are one row (ids "row-3.part-2").
#pragma once

#include "rowloc/mapping/map_build_config.hpp"
#include "rowloc/mapping/point_cloud.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace rowloc::mapping {

/// Horizontal positions of the points with |h - reference_height_m| <= band_half_width_m, where
/// heights_above_terrain_m[i] is the height of cloud point i. Throws std::invalid_argument if the
/// sizes differ.
std::vector<Eigen::Vector2d> SelectCanopyBand(const PointCloud& cloud,
                                              const std::vector<double>& heights_above_terrain_m,
                                              const CanopyBandParams& params);

/// One connected piece of canopy in the band.
struct RowPart {
  std::vector<Eigen::Vector2d> points_m;  ///< band points of the part
  Eigen::Vector2d centroid_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d axis = Eigen::Vector2d::UnitX();  ///< principal direction (unit)
  double length_m = 0.0;                            ///< extent along the axis
};

/// One row: its parts in order along the row.
struct DetectedRow {
  std::vector<RowPart> parts;
};

struct RowDetection {
  std::vector<DetectedRow> rows;                    ///< ordered across the dominant direction
  Eigen::Vector2d direction = Eigen::Vector2d::UnitX();  ///< dominant row direction (unit)
  std::size_t raster_cells = 0;                     ///< occupied raster cells
  std::size_t parts_found = 0;                      ///< connected parts before the clutter filter
  std::size_t parts_dropped = 0;                    ///< parts dropped as clutter
  std::size_t points_dropped = 0;                   ///< band points in dropped parts
  std::size_t links = 0;                            ///< gaps bridged
};

/// Finds the rows in the band (algorithm above). No rows is a valid result (empty `rows`).
/// Throws std::invalid_argument for parameters outside their domains or a raster of more than
/// 4 * 10^8 cells.
RowDetection DetectRows(const std::vector<Eigen::Vector2d>& band_points_m, const RowParams& params);

/// Other points (e.g. the band at another height) given to the parts they lie near: a point goes to
/// the part that has a band point in its cell of edge radius_m or in one of the 8 neighbouring cells
/// (so within 2 sqrt(2) radius_m of it; the first such part in row order where parts are that
/// close), others are left out. One list per part, in the order of rows[r].parts[p] flattened.
/// Throws std::invalid_argument unless radius_m > 0.
std::vector<std::vector<Eigen::Vector2d>> AssignPointsToParts(const RowDetection& detection,
                                                              const std::vector<Eigen::Vector2d>& points_m,
                                                              double radius_m);

}  // namespace rowloc::mapping
